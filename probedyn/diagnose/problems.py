"""Measurement -> diagnosis problem (one class per data kind)."""

from __future__ import annotations

from pathlib import Path

from probedyn.diagnose.formats import Measurement, read_measurement

__all__ = ["make_problem"]


def make_problem(meas: str | Path | Measurement):
    """The problem object for a measurement (a path or a read measurement)."""
    if not isinstance(meas, Measurement):
        meas = read_measurement(meas)
    if meas.kind == "modal":
        from probedyn.diagnose.modal import ModalProblem

        return ModalProblem(meas)
    if meas.kind in ("spectrum", "timeseries"):
        from probedyn.diagnose.spectrum import spectrum_problem

        return spectrum_problem(meas)
    if meas.kind == "friction" and getattr(meas, "regime", "stick-slip") == "loop":
        from probedyn.diagnose.friction_loop import FrictionLoopProblem

        return FrictionLoopProblem(meas)
    if meas.kind == "friction":
        from probedyn.diagnose.friction import FrictionProblem

        return FrictionProblem(meas)
    from probedyn.diagnose.forcecurve import ForceCurveProblem

    return ForceCurveProblem(meas)
