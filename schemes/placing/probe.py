"""The probe as vibrational nano-placing sees it (section 4.2, Table 4.4).

Every phase of nano-placing needs a few numbers of the probe along the normal to the sample:

* the static stiffness ``k`` at the tip (jump-into-contact, eq 4.17; the capture equilibrium 4.28);
* the first bending mode: frequency ``omega_1`` and the equivalent point mass
  ``m = k / omega_1^2`` of the one-DOF model (4.13): with this choice the 1-DOF model has the
  probe's first frequency **and** its static tip compliance (the usual "effective mass" of AFM;
  the first-mode *modal* stiffness ``m_1 omega_1^2`` of a uniform beam is 3.0 % larger than
  ``3 EI / L^3``);
* the damping ratio ``zeta`` of that mode (Table 4.4's ``mu = 0.1``, read as a damping ratio:
  docs/source-departures.md);
* for the distributed models (capture 4.22-4.41, several samples 4.45-4.55) the beam's length
  ``L``, bending stiffness ``EI`` and mass per length ``rho A``; and the retained normal modes
  (frequency, tip-normalised modal mass) for the forced response (4.41).

Sources of these numbers (``source``):

* ``"FEM"``: :meth:`PlacingProbe.from_fem` reads them from a clamped 3D FE model
  (:class:`probedyn.fem.model.ElasticModel`): ``k`` from a static solve with a unit force on
  the free-end face, the flapwise modes from the shift-invert eigen-solution.  ``EI`` and
  ``rho A`` are the beam-equivalent values that reproduce the FEM's static stiffness
  (``EI = k L^3 / 3``) and mass (``rho A = M_total / L``);
* ``"beam"``: :meth:`PlacingProbe.from_beam` from Euler-Bernoulli formulas of a
  :class:`probedyn.lumped.beam.RectBeam` (the analytic reference);
* ``"Table 4.4"``: :meth:`PlacingProbe.table` with the table's ``k = 1 N/m``, ``m = 2e-12 kg``,
  ``L = 2 mm`` only.
* a reduced probe of ``lumped/reduced.py`` (issue 10) enters through
  :meth:`PlacingProbe.from_reduced` (duck-typed: static stiffness and normal modes).

Table 4.4 plausibility (SOURCE-NOTES 10): Table 4.4 gives no cross-section. A silicon beam of
``L = 2 mm`` and ``k = 1 N/m`` with the project's default width ``w = 30 um`` needs
``t = (4 k L^3 / (E w))^(1/3) = 18.5 um`` (:func:`table_beam_geometry`) and weighs
``rho w t L = 2.6e-9 kg``; its first-mode equivalent mass is ``0.2427 x`` that, 6.3e-10 kg:
**313 times** the table's ``m = 2e-12 kg``. No 2 mm cantilever of any plausible section is
that light (``m/(rho L) = 4.3e-7 kg/m`` would need a 0.43 um^2 section whose stiffness would be
far below 1 N/m). ``mass_source`` chooses which mass drives a simulation:

* ``"geometric"`` (default): the beam's own mass (FEM or formula);
* ``"table"``: all masses of the probe are scaled by one factor so that the first-mode
  equivalent mass is the table's ``m`` (frequencies scale by ``sqrt(m_geo / m_table)``; mode
  shapes, stiffnesses and everything static are unchanged).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any, Literal

import numpy as np

from probedyn.core.errors import ParameterError, SolverError
from probedyn.core.presets import preset
from probedyn.lumped import beam as bm

MassSource = Literal["geometric", "table"]
MASS_SOURCES = ("geometric", "table")

#: Table 4.4 (section 4.2), the one place the placing package reads it
TABLE = preset("table-4.4")

#: silicon as in probedyn.fem.materials ("silicon": isotropic E along <110>)
SILICON_E = 169e9
SILICON_RHO = 2330.0
SILICON_NU = 0.28

#: first clamped-free root of (2.40) and the first-mode equivalent-mass ratio k/(omega_1^2 rho A L)
BETA1_L = 1.8751040687119611
EQUIV_MASS_RATIO = 3.0 / BETA1_L**4  # 0.24267...


def table_beam_geometry(width: float = 30e-6, E: float = SILICON_E, k: float | None = None,
                        L: float | None = None) -> dict[str, float]:
    """A rectangular cantilever with Table 4.4's length and stiffness: ``length``, ``width``,
    ``thickness`` [m] with ``3 E w t^3 / (12 L^3) = k`` (Euler-Bernoulli, section 2.3.1).

    Table 4.4 gives ``L = 2 mm`` and ``k = 1 N/m`` but no cross-section: the width is an
    assumption (default 30 um, the project's default cantilever width); the thickness
    follows (18.48 um for silicon)."""
    k = float(TABLE["k"] if k is None else k)
    L = float(TABLE["L"] if L is None else L)
    for name, v in (("width", width), ("E", E), ("k", k), ("L", L)):
        if not (math.isfinite(v) and v > 0):
            raise ParameterError(f"table beam: {name} must be positive, got {v}")
    t = (4.0 * k * L**3 / (E * width)) ** (1.0 / 3.0)
    return {"length": L, "width": float(width), "thickness": float(t)}


@dataclass(frozen=True)
class PlacingProbe:
    """Normal-direction description of a cantilever probe for nano-placing (SI units).

    ``k``: static tip stiffness [N/m]; ``omegas``: retained flapwise bending frequencies
    [rad/s] (ascending, ``omegas[0]`` the first mode); ``modal_masses``: their tip-normalised
    modal masses [kg] (``phi(tip) = 1``); ``zeta``: damping ratio of every retained mode;
    ``L``, ``EI``, ``rhoA``: the beam-equivalent length, bending stiffness and mass per length
    (the capture and Rayleigh-Ritz models); ``mass_source``: which mass is used
    (module docstring); ``source``: where the numbers come from; ``provenance``: details
    (model, parameters, DOFs, the geometric and table masses).
    """

    k: float
    omegas: tuple[float, ...]
    modal_masses: tuple[float, ...]
    zeta: float
    L: float
    EI: float
    rhoA: float
    mass_source: str = "geometric"
    source: str = "beam"
    provenance: dict[str, Any] = field(default_factory=dict, compare=False)
    model: Any = field(default=None, compare=False, repr=False)
    modal: Any = field(default=None, compare=False, repr=False)
    ritz: Any = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        if self.mass_source not in MASS_SOURCES:
            raise ParameterError(f"mass_source must be one of {', '.join(MASS_SOURCES)}, got {self.mass_source!r}")
        for name in ("k", "L", "EI", "rhoA"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ParameterError(f"probe {name} must be positive and finite, got {v!r}")
        if not (math.isfinite(self.zeta) and 0 <= self.zeta < 1):
            raise ParameterError(f"probe damping ratio must be in [0, 1), got {self.zeta}")
        if len(self.omegas) < 1 or len(self.omegas) != len(self.modal_masses):
            raise ParameterError("probe needs at least one mode with a frequency and a modal mass")
        if any(not (w > 0) for w in self.omegas) or any(not (m > 0) for m in self.modal_masses):
            raise ParameterError("probe modal frequencies and masses must be positive")

    # ---------------------------------------------------------------- derived numbers
    @property
    def omega1(self) -> float:
        """First bending frequency [rad/s]."""
        return float(self.omegas[0])

    @property
    def f1(self) -> float:
        return self.omega1 / (2 * math.pi)

    @property
    def m(self) -> float:
        """Equivalent point mass of the one-DOF model (4.13): ``k / omega_1^2`` [kg]."""
        return self.k / self.omega1**2

    @property
    def c(self) -> float:
        """Viscous coefficient of the one-DOF model: ``2 zeta sqrt(k m)`` [N s/m]."""
        return 2.0 * self.zeta * math.sqrt(self.k * self.m)

    @property
    def beam_mass(self) -> float:
        return self.rhoA * self.L

    def modal_stiffnesses(self) -> np.ndarray:
        return np.asarray(self.modal_masses) * np.asarray(self.omegas) ** 2

    def tip_compliance(self, omega: float | np.ndarray) -> np.ndarray:
        """Dynamic compliance at the tip [m/N] by modal superposition (4.41) over the retained
        modes, with a static correction so that ``omega = 0`` gives exactly ``1/k``:
        ``H = sum_n 1/(k_n - m_n w^2 + 2 i zeta k_n w/w_n) + (1/k - sum_n 1/k_n)``."""
        w = np.asarray(omega, dtype=float)
        kn = self.modal_stiffnesses()
        mn = np.asarray(self.modal_masses)
        wn = np.asarray(self.omegas)
        H = np.zeros(w.shape, dtype=complex)
        for a, b, c in zip(kn, mn, wn):
            H = H + 1.0 / (a - b * w**2 + 2j * self.zeta * a * w / c)
        return H + (1.0 / self.k - float(np.sum(1.0 / kn)))

    def with_mass_source(self, mass_source: MassSource) -> "PlacingProbe":
        """The same probe with its masses scaled to the table's ``m`` (``"table"``) or back to
        the geometric ones (``"geometric"``); static numbers unchanged."""
        if mass_source not in MASS_SOURCES:
            raise ParameterError(f"mass_source must be one of {', '.join(MASS_SOURCES)}, got {mass_source!r}")
        if mass_source == self.mass_source:
            return self
        m_geo = self.provenance.get("m_equivalent_geometric", self.m)
        if m_geo is None:
            raise ParameterError("Table 4.4 alone gives no geometry, so no geometric mass: use a FEM or beam probe")
        target = float(TABLE["m"]) if mass_source == "table" else m_geo
        s = target / self.m  # mass factor
        prov = dict(self.provenance)
        prov["mass_scale"] = prov.get("mass_scale", 1.0) * s
        return replace(self, omegas=tuple(w / math.sqrt(s) for w in self.omegas),
                       modal_masses=tuple(mm * s for mm in self.modal_masses), rhoA=self.rhoA * s,
                       mass_source=mass_source, provenance=prov)

    def describe(self) -> dict[str, Any]:
        return {"source": self.source, "mass_source": self.mass_source, "k_n_per_m": self.k,
                "f1_hz": self.f1, "omega1_rad_s": self.omega1, "m_equivalent_kg": self.m,
                "zeta": self.zeta, "L_m": self.L, "EI_n_m2": self.EI, "rhoA_kg_per_m": self.rhoA,
                "beam_mass_kg": self.beam_mass, "modes_hz": [w / (2 * math.pi) for w in self.omegas],
                "modal_masses_kg": list(self.modal_masses),
                "provenance": {k: v for k, v in self.provenance.items() if not callable(v)}}

    # ---------------------------------------------------------------- constructors
    @classmethod
    def from_beam(cls, beam, n_modes: int = 4, zeta: float | None = None,
                  mass_source: MassSource = "geometric") -> "PlacingProbe":
        """Euler-Bernoulli flapwise modes of a :class:`probedyn.lumped.beam.RectBeam`:
        ``omega_r = (b_r L)^2 sqrt(EI / (rho A L^4))`` (2.40-2.41); the tip-normalised modal
        mass of the clamped-free mode ``phi`` (2.39, ``phi(L)^2 = 4``, ``int phi^2 = L``) is
        ``rho A L / 4`` for every mode; ``k = 3 EI / L^3``."""
        zeta = float(TABLE["mu"]) if zeta is None else float(zeta)
        EI = beam.E * beam.I("flapwise")
        rhoA = beam.rho * beam.A
        roots = bm.eb_roots(int(n_modes))
        omegas = tuple(float(x * x * math.sqrt(EI / (rhoA * beam.L**4))) for x in roots)
        mm = tuple(rhoA * beam.L / 4.0 for _ in roots)
        k = 3.0 * EI / beam.L**3
        prov = {"beam": {"L": beam.L, "w": beam.w, "t": beam.t, "E": beam.E, "rho": beam.rho},
                "m_equivalent_geometric": k / omegas[0] ** 2, "beam_mass_geometric": rhoA * beam.L,
                "m_table": float(TABLE["m"]), "mass_scale": 1.0}
        p = cls(k, omegas, mm, zeta, beam.L, EI, rhoA, "geometric", "beam", prov)
        return p.with_mass_source(mass_source)

    @classmethod
    def table(cls, zeta: float | None = None, n_modes: int = 4) -> "PlacingProbe":
        """Table 4.4 alone: ``k = 1 N/m``, ``m = 2e-12 kg`` (equivalent mass of the first mode),
        ``L = 2 mm``; higher modes and ``EI``, ``rho A`` from a uniform Euler-Bernoulli beam with
        these numbers (``EI = k L^3 / 3``, ``rho A = m / (0.2427 L)``). ``mass_source = "table"``."""
        zeta = float(TABLE["mu"]) if zeta is None else float(zeta)
        k, m, L = float(TABLE["k"]), float(TABLE["m"]), float(TABLE["L"])
        EI = k * L**3 / 3.0
        rhoA = m / (EQUIV_MASS_RATIO * L)
        roots = bm.eb_roots(int(n_modes))
        omegas = tuple(float(x * x * math.sqrt(EI / (rhoA * L**4))) for x in roots)
        mm = tuple(rhoA * L / 4.0 for _ in roots)
        prov = {"table": TABLE.key, "m_equivalent_geometric": None, "m_table": m, "mass_scale": 1.0}
        return cls(k, omegas, mm, zeta, L, EI, rhoA, "table", "Table 4.4", prov)

    @classmethod
    def from_fem(cls, model, n_modes: int = 4, zeta: float | None = None,
                 mass_source: MassSource = "geometric", face: str = "free_end",
                 modal: Any = None) -> "PlacingProbe":
        """From a clamped :class:`~probedyn.fem.model.ElasticModel` of a cantilever along x.

        ``k``: static stiffness along z of the free-end face (uniform traction, face-averaged
        displacement: converges under refinement); modes: the first ``n_modes`` flapwise modes,
        their tip-normalised modal mass ``1 / phi_z(tip)^2`` (mass-normalised shapes) at the
        face-averaged free end; ``EI = k L^3 / 3``, ``rho A`` = FE mass / L. ``modal``: a
        :class:`~probedyn.fem.modes.ModalResult` already computed for ``model``.
        """
        zeta = float(TABLE["mu"]) if zeta is None else float(zeta)
        n_modes = int(n_modes)
        if n_modes < 1:
            raise ParameterError(f"n_modes must be >= 1, got {n_modes}")
        if modal is None:
            modal = model.modes(2 * n_modes + 2)
        A = model.attachment(face)
        flap = [md for md in modal.modes if md.family == "flapwise"][:n_modes]
        if not flap:
            raise SolverError("FEM probe: no flapwise mode among the computed modes")
        omegas, masses = [], []
        for md in flap:
            uz = float((A @ md.shape)[2])
            if abs(uz) == 0:
                raise SolverError(f"FEM probe: flapwise mode {md.index} does not move the free end")
            omegas.append(md.omega)
            masses.append(1.0 / uz**2)
        k = model.static_stiffness(face, (0.0, 0.0, 1.0))
        p = model.bundle.mesh.p
        L = float(np.ptp(p[0]))
        EI = k * L**3 / 3.0
        rhoA = model.total_mass() / L
        prov = {"model": model.name, "dofs": model.dofs, "face": face,
                "modes_fem": [md.index for md in flap], "m_equivalent_geometric": k / omegas[0] ** 2,
                "beam_mass_geometric": rhoA * L, "m_table": float(TABLE["m"]), "mass_scale": 1.0}
        probe = cls(k, tuple(omegas), tuple(masses), zeta, L, EI, rhoA, "geometric", "FEM", prov, model, modal)
        return probe.with_mass_source(mass_source)

    @classmethod
    def from_ritz(cls, basis, n_modes: int = 4, zeta: float | None = None, mass_source: MassSource = "geometric",
                  face: str = "free_end") -> "PlacingProbe":
        """From a :class:`probedyn.lumped.ritz.RitzBasis` of a clamped cantilever along x whose
        static shapes include ``face`` along z: the static stiffness ``1 / C_zz`` of the face
        (exact: the static shapes make the reduced static compliance the FEM's), the first
        ``n_modes`` flapwise FEM modes (the basis's leading columns) with their tip-normalised
        modal masses ``1 / phi_z(face)^2``; ``EI = k L^3 / 3``, ``rho A`` = FE mass / L. The basis
        is kept (``.ritz``) for the capture and multi-sample models."""
        zeta = float(TABLE["mu"]) if zeta is None else float(zeta)
        model = basis.model
        if model is None:
            raise ParameterError("the Ritz basis has no FE model attached")
        C = basis.static_compliance(face)
        k = float(1.0 / C[2, 2])
        sol = basis.solve()
        flap = [i for i in flapwise_indices(sol, model) if basis.kinds[i] == "mode"][: int(n_modes)]
        if not flap:
            raise SolverError("Ritz probe: no flapwise mode among the retained FEM modes")
        U = sol.at(face)
        omegas = tuple(float(sol.omega[i]) for i in flap)
        masses = tuple(float(1.0 / U[2, i] ** 2) for i in flap)
        L = float(np.ptp(model.bundle.mesh.p[0]))
        EI = k * L**3 / 3.0
        rhoA = model.total_mass() / L
        prov = {"model": model.name, "dofs": model.dofs, "face": face, "ritz_modes": basis.n_modes, "ritz_r": basis.r,
                "m_equivalent_geometric": k / omegas[0] ** 2, "beam_mass_geometric": rhoA * L,
                "m_table": float(TABLE["m"]), "mass_scale": 1.0}
        probe = cls(k, omegas, masses, zeta, L, EI, rhoA, "geometric", "FEM", prov, model, None, basis)
        return probe.with_mass_source(mass_source)

    @classmethod
    def from_reduced(cls, reduced, zeta: float | None = None, mass_source: MassSource = "geometric",
                     direction: str = "normal", length: float | None = None) -> "PlacingProbe":
        """From a :class:`probedyn.lumped.reduced.ReducedProbe` (issue 10): the FEM static
        stiffness along ``direction`` and the retained modes that move the point along it
        (:meth:`~probedyn.lumped.reduced.ReducedProbe.direction_modes`: modal mass ``1/phi^2``,
        frequency). ``L`` from the probe parameters (``length``) unless given; ``EI = k L^3/3``;
        ``rho A = m_1 / (0.2427 L)`` with ``m_1 = k / omega_1^2`` (exact for a uniform beam).
        ``zeta``: the table's 0.1 unless given (the reduced probe's own damping ratios are
        kept in the provenance)."""
        zeta = float(TABLE["mu"]) if zeta is None else float(zeta)
        try:
            k = float(reduced.static_stiffness(direction))
            osc = sorted(reduced.direction_modes(direction), key=lambda o: o.frequency_hz)
            prov = dict(getattr(reduced, "provenance", {}) or {})
        except (AttributeError, KeyError, TypeError, ValueError) as exc:
            raise ParameterError(f"reduced probe lacks what nano-placing needs ({exc})") from None
        if not osc:
            raise ParameterError(f"the reduced probe has no mode along {direction}")
        if length is None:
            length = (prov.get("parameters") or {}).get("length")
        if length is None:
            raise ParameterError("the reduced probe does not give the beam length: pass length=")
        L = float(length)
        omegas = tuple(2 * math.pi * float(o.frequency_hz) for o in osc)
        masses = tuple(float(o.mass) for o in osc)
        EI = k * L**3 / 3.0
        rhoA = (k / omegas[0] ** 2) / (EQUIV_MASS_RATIO * L)
        prov.update({"m_equivalent_geometric": k / omegas[0] ** 2, "beam_mass_geometric": rhoA * L,
                     "m_table": float(TABLE["m"]), "mass_scale": 1.0,
                     "reduced_damping_ratios": [float(o.damping_ratio) for o in osc]})
        probe = cls(k, omegas, masses, zeta, L, EI, rhoA, "geometric", str(prov.get("source", "FEM")), prov,
                    getattr(getattr(reduced, "ritz", None), "model", None), None)
        return probe.with_mass_source(mass_source)


def sample_point(model, l: float) -> tuple[float, float, float]:
    """Coordinates of a sample at ``x = l`` on the beam's mid-plane (centroid line)."""
    p = model.bundle.mesh.p
    y0 = 0.5 * (p[1].min() + p[1].max())
    z0 = 0.5 * (p[2].min() + p[2].max())
    return (float(min(l, p[0].max())), float(y0), float(z0))


def flapwise_indices(sol, model) -> list[int]:
    """Indices of the flapwise modes of a Ritz solution: displacement along the centroid line
    (at 1/4, 1/2, 3/4 and 1 of the length) mostly along z and not negligible (torsion modes do
    not move the centroid line, lateral and axial modes move it along y and x)."""
    L = float(np.ptp(model.bundle.mesh.p[0]))
    U = np.stack([sol.at(sample_point(model, f * L)) for f in (0.25, 0.5, 0.75, 1.0)])  # (4, 3, k)
    Ez = (U[:, 2, :] ** 2).sum(axis=0)
    E = (U**2).sum(axis=(0, 1))
    big = E > 1e-6 * E.max()
    return [i for i in range(U.shape[2]) if big[i] and Ez[i] > 0.9 * E[i]]


def mass_plausibility(probe: PlacingProbe) -> dict[str, Any]:
    """SOURCE-NOTES 10: Table 4.4's ``m`` against the probe's geometric masses.

    Returns the table mass, the beam's mass, its first-mode equivalent mass ``k / omega_1^2``,
    their ratios, and the first frequency with either mass."""
    m_tab = float(TABLE["m"])
    geo = probe.with_mass_source("geometric") if probe.provenance.get("m_equivalent_geometric") else None
    if geo is None:
        raise ParameterError("mass plausibility needs a probe with a geometry (FEM or beam), not Table 4.4 alone")
    tab = geo.with_mass_source("table")
    return {
        "m_table_kg": m_tab,
        "beam_mass_kg": geo.beam_mass,
        "m_equivalent_geometric_kg": geo.m,
        "ratio_equivalent_to_table": geo.m / m_tab,
        "ratio_beam_to_table": geo.beam_mass / m_tab,
        "f1_geometric_hz": geo.f1,
        "f1_table_hz": tab.f1,
        "rhoA_table_kg_per_m": tab.rhoA,
        "density_implied_by_table_kg_m3": tab.rhoA / (geo.rhoA / SILICON_RHO) if geo.rhoA > 0 else math.nan,
    }


__all__ = ["PlacingProbe", "sample_point", "flapwise_indices", "TABLE", "MASS_SOURCES", "table_beam_geometry", "mass_plausibility",
           "EQUIV_MASS_RATIO", "BETA1_L"]
