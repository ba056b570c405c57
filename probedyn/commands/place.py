"""``probedyn place approach|capture|release|landing|multi PROBE``: vibrational nano-placing
(section 4.2). Thin commands over :mod:`probedyn.schemes.placing`; PROBE is ``fem`` (the Table
4.4 cantilever's FEM, default), ``beam``, ``table-4.4`` or a probe name / TOML file
(:mod:`probedyn.probes.placing`). Figures (``--out``) come from :mod:`probedyn.report.placing`."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, List, Optional

import typer

from probedyn.commands._apps import app
from probedyn.commands._common import JSON_OPT, OUT_OPT, SET_OPT, emit, format_table

place_app = typer.Typer(help="Vibrational nano-placing (section 4.2): approach, capture, release, landing, "
                             "several samples.", no_args_is_help=True)
app.add_typer(place_app, name="place")

PROBE_ARG = typer.Argument("fem", help="fem (Table 4.4 cantilever, FEM), beam, table-4.4, a probe name/TOML, "
                                        "or a saved reduced probe (.json, probedyn reduced-probe --out).")
MASS_OPT = typer.Option("geometric", "--mass-source",
                        help="geometric (the beam's own mass) or table (Table 4.4's m = 2e-12 kg).")


def _probe(spec: str, sets: Optional[List[str]], mass_source: str, n_modes: int = 4):
    from probedyn.core.params import parse_sets
    from probedyn.probes.placing import placing_probe

    return placing_probe(spec, parse_sets(sets), mass_source=mass_source, n_modes=n_modes)


def _save_plots(out: Optional[Path], kind: str, res: dict[str, Any]) -> None:
    if out is None:
        return
    from probedyn.core.io import write_json
    from probedyn.report import placing as rp

    out = Path(out)
    write_json(out / f"place_{kind}.json", res)
    rp.plot_for_command(kind, res, out)


def _rows(rows, cols):
    return format_table(rows, cols)


# ------------------------------------------------------------------------------------------


@place_app.command("approach")
def approach(probe: str = PROBE_ARG, sets: Optional[List[str]] = SET_OPT, mass_source: str = MASS_OPT,
             speed: Optional[List[float]] = typer.Option(None, "--speed", help="Approach speed(s) [m/s] of the "
                                                         "slow-approach simulation (default 1e-5 and 1e-6)."),
             amplitude: Optional[List[float]] = typer.Option(None, "--amplitude", help="Oscillation amplitude(s) [m] "
                                                             "of the frequency-shift comparison."),
             as_json: bool = JSON_OPT, out: Optional[Path] = OUT_OPT) -> None:
    """Approach (4.13-4.21): jump into contact, response vs gap, frequency shift."""
    from probedyn.core.errors import ParameterError
    from probedyn.schemes.placing.studies import approach_study

    for v in (speed or []):
        if not (v > 0 and math.isfinite(v)):
            raise ParameterError(f"--speed must be positive, got {v}")
    for v in (amplitude or []):
        if not (v > 0 and math.isfinite(v)):
            raise ParameterError(f"--amplitude must be positive, got {v}")
    pr = _probe(probe, sets, mass_source)
    res = approach_study(pr, amplitudes=tuple(amplitude) if amplitude else (0.05e-9, 0.2e-9, 0.5e-9),
                         speeds=tuple(speed) if speed else (1e-5, 1e-6))
    _save_plots(out, "approach", res)

    def human(r):
        j = r["jump"]
        lines = [f"probe: {r['probe']['source']} ({r['probe']['mass_source']} mass), k = {r['k_n_per_m']:.4g} N/m, "
                 f"m = {r['m_kg']:.4g} kg, f0 = {r['f0_hz']:.6g} Hz",
                 f"jump into contact (force balance): z0* = {j['z0_star_m'] * 1e9:.4f} nm "
                 f"(gap s* = {j['s_star_m'] * 1e9:.4f} nm, deflection {j['w_star_m'] * 1e9:.4f} nm)"]
        for s in r["jump_simulations"]:
            lines.append(f"  slow approach at {s['speed_m_s']:.3g} m/s: jump at z0 = {s['z0_jump_m'] * 1e9:.4f} nm "
                         f"(delay {s['delay_m'] * 1e12:.3g} pm)")
        rows = [{"z0": x["z0_m"] * 1e9, "A": x["A_m"] * 1e9, "small": x["df_small_hz"], "g1": x["df_giessibl_hz"],
                 "gs": x["df_giessibl_sqrt_hz"], "ex": x["df_exact_hz"], "sim": x["df_sim_hz"]} for x in r["shift_rows"]]
        lines.append(_rows(rows, [("z0", "z0 [nm]", ".4f"), ("A", "A [nm]", ".3g"), ("small", "df (4.21) [Hz]", ".5g"),
                                  ("g1", "Giessibl [Hz]", ".5g"), ("gs", "Giessibl sqrt [Hz]", ".5g"),
                                  ("ex", "exact orbit [Hz]", ".5g"), ("sim", "simulated [Hz]", ".5g")]))
        return "\n".join(lines)

    emit(res, as_json, human)


@place_app.command("capture")
def capture(probe: str = PROBE_ARG, sets: Optional[List[str]] = SET_OPT, mass_source: str = MASS_OPT,
            K: Optional[List[float]] = typer.Option(None, "--K", help="k1 L^3 / EI values (default 0 3 30 300 3000)."),
            mu: Optional[List[float]] = typer.Option(None, "--mu", help="M / (rho A L) values (default 0 0.1 1)."),
            fem_check: bool = typer.Option(False, "--fem-check", help="Check against full FEM re-solves "
                                                                      "(else the FEM-mode Ritz model)."),
            as_json: bool = JSON_OPT, out: Optional[Path] = OUT_OPT) -> None:
    """Capture (4.22-4.41): frequency equation with the corrected sign, FEM check, MD linearisation."""
    from probedyn.core.errors import ParameterError
    from probedyn.schemes.placing.studies import capture_ritz_basis, capture_study

    for v in list(K or []) + list(mu or []):
        if not (v >= 0 and math.isfinite(v)):
            raise ParameterError(f"--K and --mu must be >= 0 and finite, got {v}")
    pr = _probe(probe, sets, mass_source)
    basis = capture_ritz_basis(pr.model) if (pr.model is not None and not fem_check) else None
    res = capture_study(pr, K_values=tuple(K) if K else (0.0, 3.0, 30.0, 300.0, 3000.0),
                        mu_values=tuple(mu) if mu else (0.0, 0.1, 1.0), basis=basis, fem_check=fem_check)
    _save_plots(out, "capture", res)

    def human(r):
        lines = [f"end condition EI U''' = (k1 - M w^2) U (departure 25): a sample mass lowers the frequency"]
        rows = [{"K": x["K"], "mu": x["mu"], "n": x["mode"], "bL": x["bL"], "bLp": x["bL_printed"], "b": x["beta_L3"]}
                for x in r["rows"]]
        lines.append(_rows(rows, [("K", "K = k1 L^3/EI", ".4g"), ("mu", "mu = M/(rho A L)", ".3g"), ("n", "mode", ""),
                                  ("bL", "bL corrected", ".6f"), ("bLp", "bL printed", ".6f"), ("b", "beta L^3", ".5g")]))
        if r["check"]:
            lines.append(f"check against {r['check_method']}: max |rel. difference| = {r['check_max_abs_rel']:.2e} "
                         f"for bL in [{r['check_bL_range'][0]:.3f}, {r['check_bL_range'][1]:.3f}]")
        md = r["md"]
        lines.append(f"MD at zero load: k1 = {md['k1_n_per_m']:.4g} N/m, k0 = {md['k0_n']:.4g} N, "
                     f"pull-off {md['pull_off_n']:.4g} N; piecewise-linear max-error order: uniform "
                     f"{r['pl_orders']['uniform']:.2f}, graded {r['pl_orders']['graded']:.2f}")
        return "\n".join(lines)

    emit(res, as_json, human)


@place_app.command("release")
def release(probe: str = PROBE_ARG, sets: Optional[List[str]] = SET_OPT, mass_source: str = MASS_OPT,
            mass: Optional[float] = typer.Option(None, "--mass", help="Sample mass [kg] (Table 4.4: 2e-18)."),
            amplitude: Optional[float] = typer.Option(None, "--amplitude", help="Tip amplitude [m]."),
            force: Optional[float] = typer.Option(None, "--force", help="Drive force at the tip [N] (Table 4.4: 5e-7)."),
            omega: Optional[float] = typer.Option(None, "--omega", help="Drive frequency [rad/s] (Table 4.4: 2.5e3)."),
            height: Optional[float] = typer.Option(None, "--height", help="Release height D [m] (Table 4.4: 5e-6)."),
            modes: int = typer.Option(1, "--modes", help="Retained probe modes in the run."),
            map_: Optional[str] = typer.Option(None, "--map", help="Outcome map instead of one run: omega_A, "
                                                                   "M_omega or D_omega (NetCDF under --out)."),
            n: int = typer.Option(16, "--n", help="Map resolution (n x n cells)."),
            workers: int = typer.Option(2, "--workers", help="Dask workers for a map."),
            as_json: bool = JSON_OPT, out: Optional[Path] = OUT_OPT) -> None:
    """Release (4.42) on the full Maugis-Dugdale contact: one run, or an outcome map on Dask."""
    from probedyn.core.errors import ParameterError
    from probedyn.schemes.placing import release as rel
    from probedyn.schemes.placing.studies import release_maps

    pr = _probe(probe, sets, mass_source, n_modes=max(1, modes))
    if map_ is not None:
        if map_ not in ("omega_A", "M_omega", "D_omega"):
            raise ParameterError(f"--map must be omega_A, M_omega or D_omega, got {map_!r}")
        if not (2 <= n <= 512):
            raise ParameterError(f"--n must lie in 2..512, got {n}")
        res = release_maps(pr, n=n, workers=workers, out_dir=out, which=(map_,))
        _save_plots(out, "release_map", res)

        def human_map(r):
            m = r[map_]
            return (f"{map_} map {n}x{n}: {m['counts']} in {m['elapsed_s']:.1f} s"
                    + (f"; NetCDF: {m['path']}" if m["path"] else ""))

        emit(res, as_json, human_map)
        return
    st = rel.setup_release(pr, M=mass, A=amplitude, F0=force, omega=omega, D=height, n_modes=modes)
    r = rel.simulate(st, record=out is not None)
    res = r.to_dict()
    if out is not None:
        res["trajectory"] = r.trajectory
    _save_plots(out, "release", res)

    def human(d):
        p = d["physics"]
        lines = [f"outcome: {d['outcome']}  (M = {d['inputs']['M_kg']:.3g} kg, tip amplitude "
                 f"{d['inputs']['A_m']:.3g} m, omega = {d['inputs']['omega_rad_s']:.4g} rad/s, F0 = {d['inputs']['F0_n']:.3g} N)",
                 f"inertial force M w^2 A = {p['inertial_force_n']:.3g} N against the pull-off force "
                 f"{abs(p['F_pull_off_n']):.3g} N; linear threshold amplitude {p['A_threshold_linear_m']:.3g} m",
                 f"max contact tension {d['max_tension_n']:.3g} N; separation at "
                 f"{d['t_separation_s']:.4g} s; {d['n_steps']} steps, {d['wall_s'] * 1e3:.2f} ms"]
        return "\n".join(lines)

    emit(res, as_json, human)


@place_app.command("landing")
def landing(probe: str = PROBE_ARG, sets: Optional[List[str]] = SET_OPT, mass_source: str = MASS_OPT,
            mass: Optional[float] = typer.Option(None, "--mass", help="Sample mass [kg] (Table 4.4: 2e-18)."),
            amplitude: float = typer.Option(0.5e-6, "--amplitude", help="Tip amplitude [m]."),
            omega: float = typer.Option(1e8, "--omega", help="Drive frequency [rad/s] (default: where a 2e-18 kg "
                                                             "sample is released)."),
            height: Optional[float] = typer.Option(None, "--height", help="Release height D [m]."),
            law: str = typer.Option("derjaguin", "--law", help="derjaguin (the print) or hamaker (full sphere laws)."),
            tilt: str = typer.Option("amplitude", "--tilt", help="amplitude: atan(A/L); slope: first-mode end slope."),
            study: bool = typer.Option(False, "--study", help="The full landing study (Figs 4.23, 4.27, 4.28)."),
            as_json: bool = JSON_OPT, out: Optional[Path] = OUT_OPT) -> None:
    """Flight and landing (4.43-4.44): landing radius after a release."""
    from probedyn.schemes.placing import landing as ld
    from probedyn.schemes.placing import release as rel
    from probedyn.schemes.placing.studies import landing_study

    pr = _probe(probe, sets, mass_source)
    if study:
        res = landing_study(pr, law=law)
        _save_plots(out, "landing", res)
        emit(res, as_json, lambda r: (f"reference: R_L = {r['reference']['R_L_m']:.4g} m, release velocity "
                                      f"{r['reference']['release_velocity_m_s']:.4g} m/s; gravity exceeds the "
                                      f"substrate pull beyond {r['gravity_crossover_m'][law]:.3g} m ({law})"))
        return
    st = rel.setup_release(pr, M=mass, A=amplitude, omega=omega, D=height)
    L_ = ld.land(rel.simulate(st), tilt=tilt, law=law)
    res = L_.to_dict()
    if out is not None:  # one run: its numbers (the figures are those of the --study)
        from probedyn.core.io import write_json

        write_json(Path(out) / "place_landing.json", res)

    def human(d):
        if d["outcome"] != "released":
            return f"outcome: {d['outcome']} (no flight): raise the amplitude or the frequency"
        return (f"released; tilt {d['theta_rad']:.3g} rad; landing radius R_L = {d['R_L_m']:.4g} m after "
                f"{d['flight']['t_flight_s']:.4g} s ({d['flight']['status']})")

    emit(res, as_json, human)


@place_app.command("multi")
def multi(probe: str = PROBE_ARG, sets: Optional[List[str]] = SET_OPT, mass_source: str = MASS_OPT,
          l1: float = typer.Option(0.5, "--l1", help="Position of sample 1 as a fraction of L."),
          l2: float = typer.Option(1.0, "--l2", help="Position of sample 2 as a fraction of L."),
          m1: Optional[float] = typer.Option(None, "--m1", help="Mass of sample 1 [kg] (Table 4.4: 2e-18)."),
          m2: Optional[float] = typer.Option(None, "--m2", help="Mass of sample 2 [kg] (Table 4.4: 2e-18)."),
          n_shape: int = typer.Option(12, "--n-shape", help="Polynomial shape functions."),
          as_json: bool = JSON_OPT, out: Optional[Path] = OUT_OPT) -> None:
    """Several samples (4.45-4.55): Rayleigh-Ritz frequencies, identifiability, selective release."""
    from probedyn.core.errors import ParameterError
    from probedyn.schemes.placing import multi as mu
    from probedyn.schemes.placing.probe import TABLE

    for name, v in (("--l1", l1), ("--l2", l2)):
        if not (0 < v <= 1):
            raise ParameterError(f"{name} must lie in (0, 1] (a fraction of the length), got {v}")
    if not (1 <= n_shape <= 40):
        raise ParameterError(f"--n-shape must lie in 1..40, got {n_shape}")
    pr = _probe(probe, sets, mass_source)
    M1 = float(TABLE["M1"] if m1 is None else m1)
    M2 = float(TABLE["M2"] if m2 is None else m2)
    ms = [(l1 * pr.L, M1), (l2 * pr.L, M2)]
    rr = mu.PolynomialRitz.from_probe(pr, n_shape)
    om = rr.solve(ms)["omega"][:4]
    om0 = rr.solve([])["omega"][:4]
    ex = mu.exact_frequencies(pr.L, pr.EI, pr.rhoA, ms, 4)
    ident = mu.identifiability(pr, l=(l1, l2), M=[M1, M2], n_shape=n_shape)
    res = {"probe": pr.describe(), "samples": [{"position_m": l, "mass_kg": m} for l, m in ms],
           "omega_ritz_rad_s": om, "omega_exact_rad_s": ex, "omega_bare_rad_s": om0,
           "relative_shift": om / om0 - 1.0, "identifiability": ident}
    _save_plots(out, "multi", res)

    def human(r):
        rows = [{"n": i + 1, "f": r["omega_exact_rad_s"][i] / (2 * math.pi), "rr": r["omega_ritz_rad_s"][i] / (2 * math.pi),
                 "sh": r["relative_shift"][i]} for i in range(4)]
        t1 = _rows(rows, [("n", "mode", ""), ("f", "exact beam [Hz]", ".8g"), ("rr", f"Ritz n={n_shape} [Hz]", ".8g"),
                          ("sh", "f/f0 - 1", ".4e")])
        idr = [{"u": x["unknowns"], "nf": x["n_frequencies"], "ok": "yes" if x["identifiable"] else "no",
                "sd": max(x["sd_per_unit_noise"].values()) if x["identifiable"] else None} for x in r["identifiability"]]
        t2 = _rows(idr, [("u", "unknowns", ""), ("nf", "frequencies", ""), ("ok", "determined", ""),
                         ("sd", "max sd per unit rel. noise", ".3g")])
        return t1 + "\n\n" + t2

    emit(res, as_json, human)
