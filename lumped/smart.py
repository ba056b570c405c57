"""Lumped models of the smart probes assembled automatically from FEM modes, and the studies
built on them (source eqs 3.1-3.4, 3.20, 3.37; sections 3.4.1 and 3.5.1).

Body parameters from FEM (eqs 3.1-3.3 generalised to the holder attachment)
---------------------------------------------------------------------------
The probe body with its holder (no tip) is solved by FEM. For every direction d of the lumped
model (duo-bimorph: y, z as in eq 3.4; piezotube: x, y, z as in eq 3.20) the first body mode
whose holder displacement is dominated by d is taken; with ``U[d, j]`` the displacement of the
holder attachment (the face-averaged holder end face, where the tip spring acts) in mode j
(mass-normalised), the modal coordinates are ``eta = U^-1 q_p`` and

    J = U^-T U^-1,   K_2 = U^-T diag(omega_j^2) U^-1,   C_2 = U^-T diag(c_j) U^-1,

the mass, stiffness and damping matrices of eq 3.37 referred to the holder displacement
``q_p``. For a symmetric body U is diagonal and ``J_dd = 1 / U_dd^2 = M_d`` is eq 3.1 with the
mode normalised at the holder, ``K_2,dd = M_d omega_d^2`` is eq 3.3; for a degenerate pair the
choice of eigenvectors does not matter (J, K_2 are invariant), and an eccentric tube gives the
off-diagonal coupling the FEM finds. Damping (3.2), ``c = mu int phi^2 dx``, is
mass-proportional along the body: ``c_j = (mu / (rho A)) beta_j`` with ``beta_j`` the share of
the modal mass in the PZT body (the holder and the point masses carry no distributed drag).

The tip adds ``m`` on the holder springs ``K_t = diag(k_t,d)``:
``M = [[J, 0], [0, m I]]``, ``K = [[K_2 + K_t, -K_t], [-K_t, K_t]]`` (eq 3.37 with D = m I).

Accuracy (the tolerance of the lumped-vs-FEM comparison)
--------------------------------------------------------
The lumped model keeps one body mode per direction. The truncated modes respond to the tip
force quasi-statically, as a residual flexibility at the holder
``r_d = 1/k_static,d - (K_2^-1)_dd`` (``k_static`` from a static FEM solve with a unit load
on the holder end face). Putting ``r_d`` in series with the holder spring gives a corrected
lumped model; the relative difference of the two, ``e_pred``, estimates the truncation
error, and the comparison passes when ``|f_lumped - f_FEM| / f_FEM <= 2 e_pred + 1e-3``
(factor 2: the quasi-static residual underestimates the truncated modes' dynamic response
near their resonances; 1e-3: the ARPACK/mesh-independent floor, the lumped and FEM models use
the same mesh). A lumped mode whose frequency exceeds half the frequency of the second body mode of its
direction is flagged "outside validity": there the truncated mode is no longer quasi-static.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np
from scipy.linalg import eigh

from probedyn.core.errors import ParameterError, SolverError
from probedyn.fem.assembly import rigid_body_properties as mesh_rigid_body_properties
from probedyn.fem.augmented import LumpedTip
from probedyn.fem.model import ElasticModel
from probedyn.lumped.smart_analytic import end_body_first_mode_at, end_body_frequencies, rigid_body_properties

AX = {"x": 0, "y": 1, "z": 2}


# ---------------------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------------------


def body_modes(model, n_modes: int = 8):
    """Modes of the FE model **without** its lumped tip (body + holder + point masses)."""
    return ElasticModel.modes(model, n_modes)


def beamlike(mode) -> bool:
    """A bending or axial mode of the body: its family, or (a bending pair tilted at 45 degrees
    by an eccentric bore is classified "other", flapwise and lateral shares 0.5 each) bending
    shares summing to more than one half."""
    if mode.family in ("lateral", "flapwise", "axial"):
        return True
    sh = mode.family_shares or {}
    return sh.get("flapwise", 0.0) + sh.get("lateral", 0.0) > 0.5


def holder_displacements(model, result, attach: str) -> np.ndarray:
    """(k, 3) displacement of the attachment ``attach`` in every mode of ``result``."""
    A = model.attachment(attach)
    Phi = np.column_stack([m.shape for m in result.modes])
    return np.asarray((A @ Phi).T)


# ---------------------------------------------------------------------------------------------
# the lumped model
# ---------------------------------------------------------------------------------------------


@dataclass
class SmartLumpedModel:
    """Lumped probe model, eq 3.37: body (J, K_2, C_2 at the holder) + tip (m, K_t).

    ``directions``: the modelled directions (order of the matrices); ``body_modes``: the FEM
    body modes used (index, frequency_hz, direction); ``second_body_hz``: per direction the
    frequency of the next body mode (validity limit); ``residual``: the residual flexibility
    r_d [m/N] of the truncated modes.
    """

    directions: list[str]
    J: np.ndarray
    K2: np.ndarray
    C2: np.ndarray
    m: float
    kt: np.ndarray
    body_modes: list[dict[str, Any]] = field(default_factory=list)
    second_body_hz: dict[str, float] = field(default_factory=dict)
    residual: dict[str, float] = field(default_factory=dict)

    def matrices(self, residual: bool = False) -> tuple[np.ndarray, np.ndarray]:
        n = len(self.directions)
        kt = np.array(self.kt, dtype=float)
        if residual:
            r = np.array([max(self.residual.get(d, 0.0), 0.0) for d in self.directions])
            kt = 1.0 / (1.0 / kt + r)
        Kt = np.diag(kt)
        M = np.block([[self.J, np.zeros((n, n))], [np.zeros((n, n)), self.m * np.eye(n)]])
        K = np.block([[self.K2 + Kt, -Kt], [-Kt, Kt]])
        return M, K

    def modes(self, residual: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """(frequencies [Hz], mass-normalised eigenvectors (2n, 2n)) of the undamped model."""
        M, K = self.matrices(residual)
        lam, V = eigh(K, M)
        return np.sqrt(np.maximum(lam, 0.0)) / (2 * math.pi), V

    def mode_directions(self) -> list[str]:
        _, V = self.modes()
        n = len(self.directions)
        out = []
        for j in range(V.shape[1]):
            e = V[:n, j] ** 2 + V[n:, j] ** 2
            out.append(self.directions[int(np.argmax(e))])
        return out

    def body_parameters(self) -> list[dict[str, Any]]:
        """Diagonal entries M_i, k_i, c_i and f_i = sqrt(k_i/M_i)/2pi per direction (3.1-3.3)."""
        rows = []
        for i, d in enumerate(self.directions):
            rows.append({"direction": d, "M": float(self.J[i, i]), "k": float(self.K2[i, i]),
                         "c": float(self.C2[i, i]), "k_t": float(self.kt[i]), "m": self.m,
                         "f_body_hz": math.sqrt(self.K2[i, i] / self.J[i, i]) / (2 * math.pi)})
        return rows

    def to_dict(self) -> dict[str, Any]:
        f, _ = self.modes()
        return {"directions": self.directions, "J": self.J, "K2": self.K2, "C2": self.C2, "m": self.m,
                "kt": self.kt, "frequencies_hz": f, "mode_directions": self.mode_directions(),
                "body_modes": self.body_modes, "second_body_hz": self.second_body_hz,
                "residual_flexibility": self.residual, "parameters": self.body_parameters()}


def reduce_from_fem(model, directions: Sequence[str], attach: str, *, mu: float = 0.0,
                    rho_A: float | None = None, body_regions: Sequence[str] = (), n_body: int = 12,
                    body_result=None, residual: bool = True) -> SmartLumpedModel:
    """Assemble the lumped model of ``model`` (a :class:`~probedyn.fem.augmented.AugmentedModel`
    with a lumped tip) from its FEM body modes (module docstring). The probe passes what the
    reduction needs: the ``directions`` of the lumped model, the attachment ``attach`` of the
    tip springs, the drag ``mu`` with the body's ``rho_A`` and ``body_regions``."""
    lt = getattr(model, "lumped_tip", None)
    if lt is None:
        raise ParameterError("the lumped model needs a probe with tip = 'lumped' (mass m on the holder spring)")
    dirs = list(directions)
    res = body_result if body_result is not None else body_modes(model, n_body)
    uh = holder_displacements(model, res, attach)
    chosen: dict[str, int] = {}
    second: dict[str, float] = {}
    for i, mode in enumerate(res.modes):
        if not beamlike(mode):
            continue
        u2 = np.array([uh[i][AX[d]] ** 2 for d in dirs])
        if u2.sum() <= 0:
            continue
        share = u2 / u2.sum()
        # first modes: the unassigned direction with the largest share (a pair tilted by an
        # eccentric bore has equal y and z shares: its two modes take one direction each)
        free = [k for k, d in enumerate(dirs) if d not in chosen]
        if free:
            k = max(free, key=lambda k: share[k])
            if share[k] >= 0.25:
                chosen[dirs[k]] = i
                continue
        d = dirs[int(np.argmax(share))]
        if d not in second:
            second[d] = mode.frequency_hz
    missing = [d for d in dirs if d not in chosen]
    if missing:
        raise SolverError(
            f"lumped model: no FEM body mode found along {', '.join(missing)} among the first {len(res.modes)} modes; "
            "solve more modes")
    idx = [chosen[d] for d in dirs]
    U = np.array([[uh[j][AX[d]] for j in idx] for d in dirs])
    if abs(np.linalg.det(U)) < 1e-12 * np.prod(np.abs(np.diag(U))):
        raise SolverError("lumped model: the chosen body modes do not span the lumped directions")
    Ui = np.linalg.inv(U)
    om2 = np.array([res.modes[j].omega ** 2 for j in idx])
    J = Ui.T @ Ui
    K2 = Ui.T @ np.diag(om2) @ Ui
    if mu > 0:
        if not rho_A:
            raise ParameterError("damping (3.2) needs rho A of the body")
        beta = np.array([sum(res.modes[j].kinetic_energy_share.get(r, 0.0) for r in body_regions) for j in idx])
        C2 = Ui.T @ np.diag(mu / rho_A * beta) @ Ui
    else:
        C2 = np.zeros_like(J)
    kt = np.array([lt.stiffness[AX[d]] for d in dirs], dtype=float)
    r = {}
    if residual:
        Kinv = np.linalg.inv(K2)
        for i, d in enumerate(dirs):
            e = np.zeros(3)
            e[AX[d]] = 1.0
            ks = model.static_stiffness(attach, e)
            r[d] = float(1.0 / ks - Kinv[i, i])
    bm = [{"direction": d, "index": res.modes[j].index, "frequency_hz": res.modes[j].frequency_hz,
           "family": res.modes[j].family} for d, j in zip(dirs, idx)]
    return SmartLumpedModel(dirs, J, K2, C2, float(lt.mass), kt, bm, second, r)


def group_of(vec2: np.ndarray, groups: dict[str, Sequence[str]], share: float = 0.6) -> str | None:
    """The group (e.g. ``"lateral": ("y", "z")``) carrying more than ``share`` of the squared
    components ``vec2`` (3,), else None."""
    tot = float(np.sum(vec2))
    if tot <= 0:
        return None
    best, val = None, -1.0
    for g, ds in groups.items():
        v = sum(float(vec2[AX[d]]) for d in ds)
        if v > val:
            best, val = g, v
    return best if val / tot >= share else None


def fem_mode_groups(model, result, attach: str, groups: dict[str, Sequence[str]]) -> list[str | None]:
    """Group of each FEM mode from ``|u_holder|^2 + |q_tip|^2`` (torsion modes: None)."""
    uh = holder_displacements(model, result, attach)
    out = []
    for i, m in enumerate(result.modes):
        v = uh[i] ** 2 + np.asarray(m.tip_displacement, dtype=float) ** 2
        tip_share = m.kinetic_energy_share.get("tip", 0.0)
        is_beam = beamlike(m) or tip_share > 0.5
        out.append(group_of(v, groups) if is_beam else None)
    return out


def compare_lumped_fem(model, lumped: SmartLumpedModel, result, attach: str,
                       groups: dict[str, Sequence[str]] | None = None, per_group: int = 2) -> list[dict[str, Any]]:
    """Rows comparing the first ``per_group`` lumped and FEM frequencies per direction group.

    ``groups``: e.g. ``{"lateral": ("y", "z"), "axial": ("x",)}`` for a tube whose y/z pair is
    degenerate (frequencies are pooled and compared in order); default one group per direction.
    """
    groups = groups or {d: (d,) for d in lumped.directions}
    f_l, V = lumped.modes()
    f_c, _ = lumped.modes(residual=True)
    n = len(lumped.directions)
    g_l = []
    for j in range(V.shape[1]):
        v2 = np.zeros(3)
        for i, d in enumerate(lumped.directions):
            v2[AX[d]] = V[i, j] ** 2 + V[n + i, j] ** 2
        g_l.append(group_of(v2, groups, share=0.0))
    g_f = fem_mode_groups(model, result, attach, groups)
    rows = []
    for g, ds in groups.items():
        cnt = per_group * len(ds)
        L = [(f, fc) for f, fc, gg in zip(f_l, f_c, g_l) if gg == g][:cnt]
        F = [m for m, gg in zip(result.modes, g_f) if gg == g][:cnt]
        limit = min(lumped.second_body_hz.get(d, math.inf) for d in ds) / 2.0
        for k in range(min(len(L), len(F))):
            f, fc = L[k]
            e_pred = abs(fc - f) / f
            tol = 2 * e_pred + 1e-3
            rel = (f - F[k].frequency_hz) / F[k].frequency_hz
            rows.append({"group": g, "order": k + 1, "fem_mode": F[k].index, "fem_hz": F[k].frequency_hz,
                         "lumped_hz": f, "lumped_residual_hz": fc, "rel_diff": rel,
                         "predicted_error": e_pred, "tolerance": tol, "within": bool(abs(rel) <= tol),
                         "valid": bool(f <= limit), "validity_limit_hz": limit})
    return rows


# ---------------------------------------------------------------------------------------------
# Section 3.4.1: holder-stiffness sweep (localisation of the lowest modes)
# ---------------------------------------------------------------------------------------------


def localisation_sweep(model, stiffnesses: Sequence[float], directions: Sequence[str], n_modes: int = 4,
                       body_regions: Sequence[str] = (), groups: dict[str, Sequence[str]] | None = None,
                       solve=None) -> list[dict[str, Any]]:
    """FEM modes of the assembled probe for holder spring ``k`` in ``stiffnesses`` (applied in
    ``directions``; the other components keep their value). Per mode: frequency, direction,
    kinetic-energy share of the tip, of holder + tip (holder regions, point masses, tip), of
    the body, and the strain-energy share of the holder spring. ``solve(model, n_modes)``
    returns the modes of the model with its current holder spring (default ``model.modes``;
    :func:`probedyn.probes.studies.study_localisation` passes a reduced-model solver)."""
    lt0 = model.lumped_tip
    if lt0 is None:
        raise ParameterError("the holder-stiffness sweep needs tip = 'lumped'")
    rows = []
    try:
        for k in stiffnesses:
            ks = list(lt0.stiffness)
            for d in directions:
                ks[AX[d]] = float(k)
            model.lumped_tip = LumpedTip(lt0.mass, tuple(ks), lt0.attach)
            res = model.modes(n_modes) if solve is None else solve(model, n_modes)
            dirs = fem_mode_groups(model, res, lt0.attach, groups or {"x": ("x",), "y": ("y",), "z": ("z",)})
            for m, d in zip(res.modes, dirs):
                ke = m.kinetic_energy_share
                body = sum(ke.get(r, 0.0) for r in body_regions)
                rows.append({"k_t": float(k), "mode": m.index, "frequency_hz": m.frequency_hz, "direction": d or "-",
                             "ke_tip": ke.get("tip", 0.0), "ke_holder_tip": 1.0 - body, "ke_body": body,
                             "se_holder_spring": m.family_shares.get("holder_spring_strain", float("nan"))})
    finally:
        model.lumped_tip = lt0
    return rows


# ---------------------------------------------------------------------------------------------
# Analytic reference rows for `probedyn compare`
# ---------------------------------------------------------------------------------------------


def _holder_body(model, regions: Sequence[str], pm_mass: float = 0.0):
    """(mass, centre x, inertia tensor about the centre) of the meshed holder regions."""
    mesh = model.mesh
    sel = np.concatenate([mesh.subdomains[r] for r in regions if r in (mesh.subdomains or {})])
    if sel.size == 0:
        return pm_mass, None, np.zeros((3, 3))
    dens = model.elem_density[sel]
    if mesh.t.shape[0] != 4:  # hexahedra: by quadrature
        return mesh_rigid_body_properties(mesh, sel, dens)
    m, c, J = rigid_body_properties(mesh.p, mesh.t[:, sel], dens)
    return m, c, J


def _rows_by_direction(result, model, attach, groups, refs: dict[tuple[str, str], np.ndarray], source: dict) -> list[dict]:
    d_f = fem_mode_groups(model, result, attach, groups)
    count: dict[str, int] = {}
    rows = []
    for m, d in zip(result.modes, d_f):
        if d is None:
            continue
        count[d] = count.get(d, 0) + 1
        k = count[d]
        for (dd, formula), vals in refs.items():
            if dd != d or k > len(vals) or not np.isfinite(vals[k - 1]):
                continue
            ref = float(vals[k - 1])
            rows.append({"mode": m.index, "family": m.family, "direction": d, "order": k, "formula": formula,
                         "fem_hz": m.frequency_hz, "value_hz": ref, "rel_diff": (m.frequency_hz - ref) / ref,
                         "note": source.get(formula, "")})
    return rows


def duo_bimorph_references(probe, values: dict[str, Any], result) -> list[dict[str, Any]]:
    """Duo-bimorph: per FEM mode (direction y lateral / z vertical, order within the direction)
    the corrected (3.10)+(3.18) with the holder as a point mass, the printed (3.10), the
    textbook Rayleigh tip-mass estimate, the end-body model with the holder's real offset and
    rotary inertia ("holder geometry"), and with a lumped tip the analytic 2-DOF (3.4)."""
    model = result.model
    b = probe.beam(values)
    lt = getattr(model, "lumped_tip", None)
    m_h, c, Jt = _holder_body(model, ["holder", "holder_piezolayer"])
    if c is None:
        m_h, e, J = probe.holder_mass(values), 0.0, {"y": 0.0, "z": 0.0}
    else:
        e = float(c[0] - values["length"])
        J = {"y": float(Jt[2, 2]), "z": float(Jt[1, 1])}  # lateral: rotation about z; vertical: about y
    refs: dict[tuple[str, str], np.ndarray] = {}
    notes = {
        "(3.10) corrected + (3.18), holder as point mass": "departures 1, 3; no holder offset/rotary inertia",
        "(3.10) as printed": "printed form, wrong (departure 1)",
        "Rayleigh tip mass 3EI/L^3, m_h + 33/140 m_b": "textbook one-mode estimate",
        "beam + holder rigid body (offset, rotary inertia)": "holder geometry from the mesh",
        "2-DOF (3.4): beam + holder body + tip on k_t": "analytic lumped model at the holder end",
    }
    for d in ("y", "z"):
        EI = b.EI(d)
        if lt is None:
            refs[(d, "(3.10) corrected + (3.18), holder as point mass")] = b.frequencies(d, m_h, 2)
            refs[(d, "(3.10) as printed")] = b.frequencies(d, m_h, 2, form="printed")
            refs[(d, "Rayleigh tip mass 3EI/L^3, m_h + 33/140 m_b")] = np.array([b.rayleigh_frequency(d, m_h)])
            refs[(d, "beam + holder rigid body (offset, rotary inertia)")] = end_body_frequencies(
                EI, b.rho * b.A, b.L, m_h, e, J[d])
        else:
            x_ref = 2 * e if c is not None else 0.0  # holder end face (the spring's attachment)
            Mb, kb = end_body_first_mode_at(EI, b.rho * b.A, b.L, m_h, e, J[d], x_ref)
            kt = lt.stiffness[AX[d]]
            lam = eigh(np.array([[kb + kt, -kt], [-kt, kt]]), np.diag([Mb, lt.mass]), eigvals_only=True)
            refs[(d, "2-DOF (3.4): beam + holder body + tip on k_t")] = np.sqrt(lam) / (2 * math.pi)
    attach = lt.attach if lt is not None else "holder_end"
    return _rows_by_direction(result, model, attach, {"y": ("y",), "z": ("z",)}, refs, notes)


def piezotube_references(probe, values: dict[str, Any], result) -> list[dict[str, Any]]:
    """Piezotube: lateral (y, z) with the thin-wall EI of (3.21) and the exact annulus, both
    with the holder as a point mass (3.10 corrected), the exact annulus with the holder's
    offset and rotary inertia and the Timoshenko shear compliance; axial with
    ``(omega L/a) tan(omega L/a) = rho A L / m_h`` (3.27-3.29)."""
    model = result.model
    t = probe.tube(values)
    lt = getattr(model, "lumped_tip", None)
    m_h, c, Jt = _holder_body(model, ["holder", "holder_piezolayer"])
    if c is None:
        m_h, e, J = probe.holder_mass(values), 0.0, 0.0
    else:
        e, J = float(c[0] - values["length"]), float(0.5 * (Jt[1, 1] + Jt[2, 2]))
    notes = {
        "(3.21) thin-wall EI, holder as point mass": "thin-wall approximation pi R^3 t",
        "exact annulus EI, holder as point mass": "exact I = pi (Re^4 - Ri^4)/4",
        "annulus + holder rigid body + shear (Timoshenko)": "holder geometry and shear of the wall",
        "(3.27-3.29) rod with holder mass": "holder as point mass, no lateral inertia",
        "rod, holder mass at its centre (offset)": "holder geometry",
    }
    refs: dict[tuple[str, str], np.ndarray] = {}
    if lt is None:
        cs = t.shear_compliance(probe.s66(values), nu=_nu(probe, values))
        d = "lateral"  # the y/z pair is degenerate: each frequency appears twice
        two = lambda f: np.repeat(np.asarray(f)[:2], 2)  # noqa: E731
        refs[(d, "(3.21) thin-wall EI, holder as point mass")] = two(t.lateral_frequencies(m_h, 2, exact=False))
        refs[(d, "exact annulus EI, holder as point mass")] = two(t.lateral_frequencies(m_h, 2, exact=True))
        refs[(d, "annulus + holder rigid body + shear (Timoshenko)")] = two(end_body_frequencies(
            t.I(True) / t.s11, t.rho * t.A, t.L, m_h, e, J, cs))
        refs[("x", "(3.27-3.29) rod with holder mass")] = t.axial_frequencies(m_h, 2)
    else:
        cs = t.shear_compliance(probe.s66(values), nu=_nu(probe, values))
        x_ref = 2 * e if c is not None else 0.0
        Mb, kb = end_body_first_mode_at(t.I(True) / t.s11, t.rho * t.A, t.L, m_h, e, J, x_ref, cs)
        two = lambda f: np.repeat(np.asarray(f)[:2], 2)  # noqa: E731
        name = "2-DOF (3.20): annulus + holder body + shear, tip on k_t"
        notes[name] = "analytic lumped model at the holder end"
        kt = lt.stiffness[1]
        lam = eigh(np.array([[kb + kt, -kt], [-kt, kt]]), np.diag([Mb, lt.mass]), eigvals_only=True)
        refs[("lateral", name)] = two(np.sqrt(lam) / (2 * math.pi))
        # axial: rod stiffness A/(s11 L), mass m_h + m_rod/3 (Rayleigh, exact in the heavy-holder limit)
        ka, Ma, kx = t.A / (t.s11 * t.L), m_h + t.mass / 3, lt.stiffness[0]
        lam = eigh(np.array([[ka + kx, -kx], [-kx, kx]]), np.diag([Ma, lt.mass]), eigvals_only=True)
        refs[("x", "2-DOF (3.20) axial: rod + holder mass, tip on k_t")] = np.sqrt(lam) / (2 * math.pi)
    return _rows_by_direction(result, model, lt.attach if lt else "holder_end",
                              {"x": ("x",), "lateral": ("y", "z")}, refs, notes)


def _nu(probe, values) -> float:
    S = probe.pzt(values).S
    return float(np.clip(-S[0, 1] / S[0, 0], 0.0, 0.49))


# ---------------------------------------------------------------------------------------------
# Mesh convergence
# ---------------------------------------------------------------------------------------------


def observed_order(f: Sequence[float], ratio: float) -> tuple[float, float]:
    """Observed convergence order p and Richardson-extrapolated value from three values on
    meshes refined by a constant ``ratio`` (h_k / h_(k+1)): ``p = ln((f1-f2)/(f2-f3)) / ln r``."""
    f1, f2, f3 = (float(x) for x in f[-3:])
    d1, d2 = f1 - f2, f2 - f3
    if d1 == 0 or d2 == 0 or d1 * d2 < 0:
        return float("nan"), f3
    p_ = math.log(abs(d1 / d2)) / math.log(ratio)
    return p_, f3 - d2 / (ratio**p_ - 1)
