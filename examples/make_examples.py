"""Regenerate the synthetic examples of ``examples/measurements`` from the independent truth paths.

Usage: ``python examples/make_examples.py [OUTDIR] [NAME ...]`` (default OUTDIR: ``examples/measurements``;
names: ``afm_cantilever_modes``, ``ffm_stickslip_speeds``; default both). Deterministic (fixed seeds).

The truths are the ones of the rate studies (``tests/diagnose_truth.py``: a path independent of the
diagnosis, never imported by probedyn), with ONE stated hidden effect each and the noise the sidecar
states; the sidecar holds what an experimentalist has (nominal spec, values, stated noise) and, in
comments the diagnosis does not read, how the file was made and what is hidden:

* ``afm_cantilever_modes`` -- six modes (flapwise 1-4, lateral 1, torsion 1) and their Q of the
  default cantilever (300 x 30 x 10 um silicon) in vacuum: probedyn's 3D FEM on the truth mesh (4 layers of 20-node
  hexahedra through the thickness, unstretched; the diagnosis meshes 3 layers thick and stretches
  them back) solved directly (shift-invert on the full matrices, no Ritz reduction), with a point
  mass on the mesh vertex nearest to x/L = 0.85 on the centre line: a 15 um silica sphere
  (2200 kg/m^3, 3.9 ng, 1.9 % of the lever's mass) picked up from the sample; it lowers f1 by
  ~1.5 %, 15x the stated noise. Noise: 1e-3
  relative on the frequencies, 5 % on Q (the sidecar's [noise]).
* ``ffm_stickslip_speeds`` -- three friction loops (trace and retrace, interval-mean samples, 8
  lattice periods): speed v and 10 v at 5 nN, v at 10 nN, from the Langevin Prandtl-Tomlinson tip
  with inertia and thermal noise at the declared temperature (Gronbech-Jensen-Farago integrator),
  not the diagnosis' FFM integrator; hidden: a viscous tip-substrate friction gamma = 1e-3 N s/m
  (a lubricant or water layer: at 0.5 um/s it adds 0.5 nN, 100x the stated 5 pN noise, yet
  looks like a calibration or load change in a single loop; the speed dependence separates it).
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import diagnose_truth as dt  # noqa: E402

#: the modal example's lever: the default cantilever (``probedyn params cantilever``), where the diagnosis'
#: FEM is meshed unstretched (a thin lever's stretched mesh: see docs/diagnose.md section 5)
LEVER = dict(length=300e-6, width=30e-6, thickness=10e-6)
#: the hidden particle: a silica sphere of diameter D on the lever's centre line at x/L = XI
SILICA_RHO, PARTICLE_D, PARTICLE_XI = 2200.0, 15e-6, 0.85
MODAL_SEED, FRICTION_SEED = 1, 2
GAMMA_VISC = 1e-3  # N s/m


def particle_mass() -> float:
    import math

    return SILICA_RHO * math.pi / 6 * PARTICLE_D**3


def _provenance(toml: Path, lines: list[str]) -> None:
    toml.write_text("".join(f"# {s}\n" for s in lines) + toml.read_text())


def make_modal(outdir: Path) -> Path:
    m = particle_mass()
    toml, truth = dt.make_modal_case(outdir, MODAL_SEED, "point-mass", LEVER, with_Q=True, declared_medium="vacuum",
                                     params={"mass": m, "xi": PARTICLE_XI}, name="afm_cantilever_modes")
    lever_mass = dt.probe_mass(LEVER)
    _provenance(toml, [
        "Synthetic modal measurement: 6 modes + Q of the default cantilever (300 x 30 x 10 um silicon) in vacuum.",
        "Made by examples/make_examples.py (seed %d) from tests/diagnose_truth.py: probedyn's 3D FEM on the truth" % MODAL_SEED,
        "mesh (4 hex-s2 layers through the thickness, unstretched), solved directly, with the effect in the matrices.",
        "HIDDEN (not declared; the diagnosis must find it): a point mass %.3g kg (%.2f %% of the lever's %.3g kg;"
        % (m, 100 * m / lever_mass, lever_mass),
        "a %.0f um silica sphere picked up) on the mesh vertex at x/L = %.4f (nearest to %.2f) on the centre line."
        % (PARTICLE_D * 1e6, truth.get("xi_node", PARTICLE_XI), PARTICLE_XI),
        "Noise as stated in [noise]: frequencies 1e-3 relative, Q 5 %% (intrinsic Q %.0f)." % truth["Q_int"],
    ])
    return toml


def _compact_friction_csv(csv: Path) -> None:
    """Rewrite the friction CSV with the digits the data carry (keeps the file well under 100 kB): positions
    and times to 6 significant digits (1e-6 of a scan; a sample spans 1/40 of a period = 3e-3 of the scan),
    forces to 5 (1e-14 N on nN forces, far below the 5 pN noise)."""
    head, *rows = csv.read_text().splitlines()
    out = [head]
    for r in rows:
        sid, x, f, t = r.split(",")
        out.append(f"{sid},{float(x):.6g},{float(f):.5g},{float(t):.6g}")
    csv.write_text("\n".join(out) + "\n")


def make_friction(outdir: Path) -> Path:
    toml, truth = dt.make_friction_case(outdir, FRICTION_SEED, "viscous-friction", params={"gvisc": GAMMA_VISC},
                                        name="ffm_stickslip_speeds")
    _compact_friction_csv(toml.with_suffix(".csv"))
    _provenance(toml, [
        "Synthetic friction measurement: three FFM friction loops (trace and retrace, interval-mean samples).",
        "Made by examples/make_examples.py (seed %d) from tests/diagnose_truth.py: a Langevin Prandtl-Tomlinson"
        % FRICTION_SEED,
        "tip with inertia and thermal noise (Gronbech-Jensen-Farago integrator; not the diagnosis' FFM integrator),",
        "lattice a = %.4g m (declared 5e-10), corrugation eta = %.3f at the first scan's load, T = %g K."
        % (truth["a"], truth["eta"], truth["T"]),
        "HIDDEN (not declared; the diagnosis must find it): viscous tip-substrate friction gamma = %g N s/m" % GAMMA_VISC,
        "(%.2g N at the fastest scan). Noise as stated in [noise]: 5 pN white." % (GAMMA_VISC * 10 * truth["v_lo"]),
    ])
    return toml


MAKERS = {"afm_cantilever_modes": make_modal, "ffm_stickslip_speeds": make_friction}


def main(argv: list[str]) -> int:
    outdir = Path(argv[0]) if argv else ROOT / "examples" / "measurements"
    for name in argv[1:] or list(MAKERS):
        print(MAKERS[name](outdir))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
