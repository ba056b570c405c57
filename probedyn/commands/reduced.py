"""``probedyn reduced-probe``: reduce a probe from its FEM (or take a table) and show / save the
reduced probe every scheme's ``--probe`` accepts (docs/reduced-probes.md)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Optional

import typer

from probedyn.commands._apps import app
from probedyn.commands._common import JSON_OPT, SET_OPT, emit, format_table, out_file_option


@app.command("reduced-probe")
def reduced_probe_cmd(
    probe: str = typer.Argument("cantilever", help="Registry probe, TOML probe file, saved .json or table-2.1/2.2/4.1/4.3."),
    sets: Optional[list[str]] = SET_OPT,
    modes: int = typer.Option(6, "--modes", help="Retained modes (the validity limit is the next one)."),
    q: Optional[float] = typer.Option(None, "--q", help="Quality factor of every mode (zeta = 1/2Q)."),
    mu: Optional[float] = typer.Option(None, "--mu", help="Environment damping of eq 3.2 [N s/m^2] (beam-like probes)."),
    point: Optional[str] = typer.Option(None, "--point", help="Named point or face (default: the tip apex / lumped tip)."),
    cache: bool = typer.Option(True, "--cache/--no-cache", help="Reuse / store the reduction under its content hash."),
    actuation: bool = typer.Option(False, "--actuation", help="Smart probes: reduce the body without its tip at the "
                                   "holder and fill the piezo FEM's modal force per volt (for probedyn track)."),
    out: Optional[Path] = out_file_option(help="Write the reduced probe: FILE.json (+ FILE.ritz.npz)."),
    as_json: bool = JSON_OPT,
) -> None:
    """Reduce a probe: per direction (scan, lateral, normal) the static stiffness at the point, the
    retained modes' masses, stiffnesses, damping and participations, the validity limit."""
    from probedyn.core.errors import ParameterError
    from probedyn.core.params import parse_sets
    from probedyn.probes.reduce import reduce_probe, resolve_probe

    over = parse_sets(sets)
    if probe.endswith(".json") or probe.lower().startswith("table-"):
        if over or q is not None or mu is not None or point is not None:
            raise ParameterError("--set, --q, --mu and --point apply to a probe reduced from its FEM, "
                                 "not to a saved or table probe")
        rp = resolve_probe(probe)
    elif actuation:
        from probedyn.probes.reduced_tracking import actuated_probe

        if q is not None or mu is not None or point is not None:
            raise ParameterError("--actuation reduces the smart probe's body at its holder with the probe's own mu: "
                                 "no --q, --mu or --point")
        rp = actuated_probe(probe, over, n_modes=modes, cache=cache)
    else:
        rp = reduce_probe(probe, over, n_modes=modes, Q=q, mu=mu, point=point, cache=cache)
    res: dict[str, Any] = rp.to_dict()
    if out is not None:
        res["file"] = str(rp.save(out))

    def human(d: dict[str, Any]) -> str:
        pv = d["provenance"]
        lines = [f"reduced probe: {pv.get('probe', pv.get('preset'))} ({pv.get('source')}) at '{d['point']}'"
                 + (f", {pv.get('dofs')} DOFs, mesh {pv.get('mesh_key')}, cache {pv.get('cache')}" if pv.get("dofs") else ""),
                 f"validity limit: {d['validity_hz']:.5g} Hz" if d.get("validity_hz") else "validity limit: none (table)",
                 f"damping: {d['damping']}"]
        for name, v in d["per_direction"].items():
            lines.append(f"{name}: static stiffness {v['static_stiffness']:.5g} N/m, residual share "
                         f"{v['residual_compliance'] * v['static_stiffness']:.3f}")
            rows = [dict(mode=o["mode"], family=o["family"], f=o["frequency_hz"], m=o["mass"], k=o["stiffness"],
                         c=o["damping"], p=o["participation"]) for o in v["modes"]]
            if rows:
                lines.append(format_table(rows, [("mode", "mode", ""), ("family", "family", ""), ("f", "f [Hz]", ".5g"),
                                                 ("m", "mass [kg]", ".4g"), ("k", "stiffness [N/m]", ".4g"),
                                                 ("c", "damping [N s/m]", ".3g"), ("p", "participation", ".4f")]))
        if d.get("actuation"):
            ns = len(next(iter((d.get("actuation_static") or {"": []}).values())))
            lines.append(f"actuation (piezo FEM, modal force per volt of the {len(d['modes'])} modes"
                         + (f" + {ns} static pseudo-modes" if ns else "") + f"): electrodes {', '.join(d['actuation'])}")
        if d.get("file"):
            lines.append(f"written: {d['file']}")
        return "\n".join(lines)

    emit(res, as_json, human)
