"""The probe a nano-placing run uses (section 4.2): composes the cantilever geometry, its FEM and
the reduction into a :class:`probedyn.schemes.placing.probe.PlacingProbe`.

Specs (``placing_probe(spec, ...)``):

The FEM probes are reduced once (:func:`placing_ritz`, :class:`probedyn.lumped.ritz.RitzBasis`: the
lowest FEM modes plus static shapes at the tip and at the sample positions); the probe's
static stiffness and modes come from that basis and it is kept for the capture and
several-sample models (low-rank additions, no FEM re-solve).

* ``"fem"`` (default): the cantilever of Table 4.4 (``L = 2 mm``, ``k = 1 N/m``; silicon, width
  30 um, thickness 18.48 um from ``3 EI / L^3 = k``: :func:`~probedyn.schemes.placing.probe.table_beam_geometry`)
  meshed with one P2 element through the thickness (13.8k DOFs; first three flapwise
  frequencies within 0.08 % of the converged FEM, docs/placing.md); ``--set`` overrides any
  cantilever parameter;
* ``"beam"``: the same geometry as an Euler-Bernoulli beam (analytic);
* ``"table-4.4"``: Table 4.4's numbers alone (``k``, ``m``, ``L``);
* any other probe name or TOML file of :mod:`probedyn.probes` with a beam along x clamped at
  x = 0 and a ``free_end`` face (its first flapwise modes and static stiffness from the FEM);
* a saved reduced probe (``.json``, :class:`probedyn.lumped.reduced.ReducedProbe`), another
  source table (``table-x.y``: must describe the normal direction) or a ``ReducedProbe`` object:
  :func:`placing_probe_from_reduced` (the normal stiffness and the normal modes at the reduced
  probe's point, its Ritz basis and, rebuilt from the mesh cache, its FE model).
"""

from __future__ import annotations

from typing import Any, Mapping

from probedyn.core.errors import ParameterError, ProbedynError
from probedyn.lumped.beam import RectBeam
from probedyn.lumped.reduced import ReducedProbe
from probedyn.lumped.ritz import RitzBasis
from probedyn.probes import get_probe
from probedyn.probes.reduce import attach_model, resolve_probe
from probedyn.schemes.placing.probe import (SILICON_E, SILICON_NU, SILICON_RHO, PlacingProbe, sample_point,
                                            table_beam_geometry)

SPECS = ("fem", "beam", "table-4.4")

#: mesh of the default FEM probe: one element layer through the thickness
DEFAULT_MESH = {"elements_through_thickness": 1}
#: FEM modes in the Ritz basis (flapwise 1-4 and the lateral, torsion modes between them)
RITZ_MODES = 8


def placing_model(overrides: Mapping[str, Any] | None = None, probe: str = "cantilever"):
    """The ElasticModel of the placing cantilever (Table 4.4 geometry + ``overrides``)."""
    p, extra = get_probe(probe)
    vals: dict[str, Any] = {}
    if probe == "cantilever":
        vals.update(table_beam_geometry())
        vals.update(DEFAULT_MESH)
    vals.update(extra or {})
    vals.update(dict(overrides or {}))
    values = p.resolve(vals)
    return p.build(values), values


def placing_probe(spec: str = "fem", overrides: Mapping[str, Any] | None = None, mass_source: str = "geometric",
                  n_modes: int = 4, zeta: float | None = None) -> PlacingProbe:
    """A :class:`PlacingProbe` from ``spec`` (module docstring)."""
    if isinstance(spec, ReducedProbe) or str(spec).endswith(".json") or (
            str(spec).lower().startswith("table-") and str(spec) != "table-4.4"):
        if overrides:
            raise ParameterError("a reduced probe or a table cannot take parameter overrides; reduce the probe again")
        return placing_probe_from_reduced(resolve_probe(spec), mass_source=mass_source, n_modes=n_modes, zeta=zeta)
    spec = str(spec)
    if not (isinstance(n_modes, int) and 1 <= n_modes <= RITZ_MODES):
        raise ParameterError(f"retained modes must lie in 1..{RITZ_MODES} (the Ritz basis of nano-placing), got {n_modes}")
    if spec == "table-4.4":
        if overrides:
            raise ParameterError("the Table 4.4 probe has no parameters to override (use 'fem' or 'beam')")
        if mass_source != "table":
            raise ParameterError("Table 4.4 alone has only the table's mass: use --mass-source table, or 'fem'/'beam'")
        return PlacingProbe.table(zeta=zeta, n_modes=n_modes)
    if spec == "beam":
        g = table_beam_geometry()
        ov = dict(overrides or {})
        unknown = set(ov) - {"length", "width", "thickness", "youngs_modulus", "density", "poisson_ratio"}
        if unknown:
            raise ParameterError(f"unknown beam parameter(s) {', '.join(sorted(unknown))} "
                                 "(length, width, thickness, youngs_modulus, density, poisson_ratio)")
        if ov:  # the same plausibility ranges as the cantilever probe's parameters (metres typed for micrometres...)
            get_probe("cantilever")[0].resolve(ov)
        b = RectBeam(float(ov.get("length", g["length"])), float(ov.get("width", g["width"])),
                     float(ov.get("thickness", g["thickness"])), float(ov.get("youngs_modulus", SILICON_E)),
                     float(ov.get("poisson_ratio", SILICON_NU)), float(ov.get("density", SILICON_RHO)))
        return PlacingProbe.from_beam(b, n_modes=n_modes, zeta=zeta, mass_source=mass_source)
    probe = "cantilever" if spec == "fem" else spec
    model, values = placing_model(overrides, probe)
    basis = placing_ritz(model)
    pp = PlacingProbe.from_ritz(basis, n_modes=n_modes, zeta=zeta, mass_source=mass_source)
    pp.provenance["parameters"] = {k: v for k, v in values.items() if isinstance(v, (int, float, str)) or v is None}
    return pp


def placing_probe_from_reduced(rp: ReducedProbe, mass_source: str = "geometric", n_modes: int = 4,
                               zeta: float | None = None) -> PlacingProbe:
    """Nano-placing's probe from a reduced probe (issue 10): ``PlacingProbe.from_reduced`` on its
    normal direction (static stiffness at its point, the first ``n_modes`` modes that move the
    point along the normal). A FEM-reduced probe gets its FE model back (mesh cache; the mesh must
    hash the same) so that the capture and several-sample models can attach samples anywhere."""
    if "normal" not in rp.directions:
        raise ParameterError(f"the {rp.source} probe describes no normal direction: nano-placing needs the "
                             "normal stiffness and modes (use fem, beam, table-4.4 or a FEM-reduced probe)")
    if rp.ritz is not None and rp.ritz.model is None and rp.source == "FEM" and rp.provenance.get("probe"):
        try:
            attach_model(rp)
        except ProbedynError:
            pass  # the probe file was reduced on another mesh: static and modal numbers still hold
    return PlacingProbe.from_reduced(rp, zeta=zeta, mass_source=mass_source, n_modes=n_modes)


def placing_ritz(model, n_modes: int = RITZ_MODES):
    """The FEM-mode Ritz basis nano-placing uses: ``n_modes`` FEM modes plus static correction
    shapes along z at the free-end face (the tip: capture, release) and at the centroid line at
    L/2 and L (the samples of Figs 4.24-4.26)."""
    L = float(model.bundle.mesh.p[0].max() - model.bundle.mesh.p[0].min())
    att = [("free_end", "z"), (sample_point(model, 0.5 * L), "z"), (sample_point(model, L), "z")]
    return RitzBasis.from_model(model, int(n_modes), attachments=att)


__all__ = ["placing_probe", "placing_probe_from_reduced", "placing_model", "placing_ritz", "SPECS", "DEFAULT_MESH", "RITZ_MODES"]
