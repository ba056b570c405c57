"""``probedyn diagnose``: show what the simulation gets wrong, name the cause, measure the gain.
The text, the figures and the report section are in :mod:`probedyn.report.diagnose`."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Optional

import typer

from probedyn.commands._apps import app
from probedyn.commands._common import JSON_OPT, OUT_OPT, emit, format_table
from probedyn.core.io import make_dirs


def _human_list(rows: list[dict[str, Any]]) -> str:
    out = []
    for kind in ("modal", "friction", "force"):
        out.append(f"{kind} causes:")
        for c in rows:
            if c["kind"] != kind:
                continue
            ps = ", ".join(f"{p['name']} [{p['unit']}]" for p in c["parameters"])
            out.append(f"  {c['id']:<22} {c['title']}  ({ps})")
            out.append(f"  {'':<22} needs: {c['needs']}")
    return "\n".join(out)


@app.command("diagnose")
def diagnose_cmd(
    measurement: Optional[Path] = typer.Argument(None, help="Measurement: TOML sidecar or its CSV."),
    list_causes: bool = typer.Option(False, "--list-causes", help="List the catalog of causes and exit."),
    noise: str = typer.Option("auto", "--noise", help="Noise model: auto (AR(1) whitening where the residuals "
                              "show a correlation) or white (samples taken as independent)."),
    as_json: bool = JSON_OPT,
    out: Optional[Path] = OUT_OPT,
) -> None:
    """Calibrate the baseline, analyse residuals, rank catalog causes out of sample, extend, report the gain."""
    from probedyn.core.errors import ParameterError

    if noise not in ("auto", "white"):
        raise ParameterError(f"--noise must be auto or white, got {noise!r}")

    if list_causes:
        from probedyn.diagnose.causes import catalog_table

        emit(catalog_table(), as_json, _human_list)
        return
    if measurement is None:
        raise ParameterError("diagnose needs a MEASUREMENT file (or --list-causes)")
    from probedyn.diagnose.engine import diagnose
    from probedyn.diagnose.problems import make_problem

    problem = make_problem(measurement)
    res = diagnose(problem, noise_model=noise)
    if out is not None:
        from probedyn.core.io import write_json, write_text
        from probedyn.report.diagnose import markdown, plot_evidence, plot_residuals

        out = Path(out)
        make_dirs(out)
        fr = plot_residuals(res, out / "residuals.png", getattr(problem, "group_labels", None) if res["kind"] != "friction" else None)
        fe = plot_evidence(res, out / "evidence.png")
        write_json(out / "diagnose.json", res)
        write_text(out / "diagnose.md", markdown(res, fr.name, fe.name) + "\n")
        res["files"] = [str(out / "diagnose.json"), str(out / "diagnose.md"), str(fr), str(fe)]

    from probedyn.report.diagnose import summary

    def human(r: dict[str, Any]) -> str:
        rows = [{"cause": c["cause"], "evidence": c["evidence"], "dchi2": c["delta_chi2"], "LR": "pass" if c["lr_pass"] else "fail"}
                for c in r["candidates"]]
        txt = summary(r) + "\n\n" + format_table(rows, [("cause", "cause", ""), ("evidence", "evidence [nat]", ".1f"),
                                                           ("dchi2", "delta chi2", ".1f"), ("LR", "LR test", "")])
        if "files" in r:
            txt += "\n\nwritten: " + ", ".join(r["files"])
        return txt

    emit(res, as_json, human)
