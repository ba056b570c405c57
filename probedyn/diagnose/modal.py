"""The modal diagnosis problem: measured modes against the probe's own FEM.

Residuals are whitened: ``(f_meas - f_model) / sigma_f`` for every mode, with
``sigma_f^2 = sigma_meas^2 + e_FEM^2`` (the stated noise and the FEM's discretisation estimate,
:class:`~probedyn.diagnose.modal_model.FEMBaseline`), and ``(ln Q_meas - ln Q_model) / (sigma_Q / Q)``
for every measured Q. Cross-validation groups are the modes (a mode's f and Q together).

**Model-form floor** (derived per probe). The 3D FEM and any real lever -- or another model of
it, e.g. a 1D Timoshenko beam -- differ in what the FEM idealises: the rigid clamp restrains the
anticlastic curvature of the root (a wide lever's bending stiffness lies between the beam value
``E I`` and the plate value ``E I / (1 - nu^2)`` depending on that restraint) and the warping of
the root section in torsion, the clamp's 3D boundary layer, the shear deformation of short
levers. How much these 3D details move each mode *of this probe* is computable: the gap
``g_i = ln(f_FEM,i / f_beam,i)`` between the FEM and probedyn's own beam theory of the same prism
(:meth:`FEMBaseline._beam_gap`: Timoshenko bending with ``E``, Saint-Venant torsion without
warping; the FEM lies between that beam and the plate-modulus beam, a bracket the tests check).
The noise model carries that gap as one nuisance direction, ``ln f_i`` moving by ``a g_i``. The
amplitude has a physical range: a real root restrains the anticlastic curvature and the warping
of its section at most as fully as the FEM's rigid clamp (``a = 0``) and at least not at all, as
the beam (``a = -1``); softer than the beam is a compliant clamp (a cause), stiffer than the
rigid-clamp FEM is no model form at all (a geometry or material cause). The prior is
``a ~ N(MF_CENTRE, MF_SCALE^2)`` = ``N(-0.5, 0.35^2)`` -- both limits at 1.43 sigma -- truncated at
``MF_BOUND`` = 3 sigmas (``-1.55 <= a <= 0.55``; a larger discrepancy is not model form and is left
to the causes). Until session 32 the prior was ``N(0, 1)``, symmetric about the FEM: a length error
(every bending mode ``-2 dL / L``, torsion ``-dL / L``) plus a model form 0.8 gap stiffer than the
rigid clamp then imitated a compliant clamp (bending ``-2 c``, torsion nearly unchanged;
``tests/test_clamp_mass_duality.py``), the gap being largest on torsion.
The floor is thus as large as beam theory and 3D elasticity disagree on this probe, mode by mode
(1.36-1.55 % flapwise, 0.64 % lateral, 8.9 % torsion on a 100 x 40 x 10 um lever; 0.43-0.73 %,
0.21 % and 1.8 % on 300 x 30 x 10 um), and shrinks where they agree (long, narrow levers), keeping
the sensitivity there; a uniform modulus change is not absorbed, because the gap is not uniform
over the families. Probes without a beam model (a meshed tip, several materials, an anisotropic
crystal) keep a uniform stiffness direction of prior sigma ``MF_UNIFORM`` = 0.5 %.

**A declared fluid** (water, ethanol; not air on a silicon lever, where it is below a tenth of the noise) adds three
directions of the same kind (:meth:`ModalProblem._hydro_setup`): the size of the 2D load (Sader's, Green & Sader's)
(:data:`HYDRO_Q_ASPECT` w / L), the section's thickness (both functions are thin-section limits; a real section of
t/w = 0.1 carries 4-12 % more fluid, :func:`~probedyn.diagnose.hydrodynamics.section_thickness_change`), and whether
the load acts on the 3D mode's transverse motion or, as the uniform-beam form does, on its whole modal mass; a
fluid model's flapwise and torsion Q carry the first two as a floor. The third (and the thickness's Q floor)
follows the model's own fluid, evaluated with every solve (its added-mass ratio and top-face share per mode): a
fitted fluid (no medium declared) carries it too. **A measured static spring
constant** (``[static]``) is one more row of the same profile (:meth:`ModalProblem._static_setup`).

The amplitude enters linearly and is profiled in closed form in every residual evaluation
(ridge least squares on the fitted data only, the prior as a pseudo-residual
``(a - MF_CENTRE) / MF_SCALE`` that belongs to no cross-validation group; the amplitude is reported
in those prior sigmas), which equals fitting it jointly with its Gaussian prior.

**Ranking** (``rank_by_heldout``): claimed causes are ranked, and confounding is judged, by their
leave-one-mode-out evidence: whether a cause fitted to the other modes predicts a mode's
frequency (a torsion mode after the bending modes, the fourth flapwise after the first three) is
what separates a length error (bending ~ 1/L^2, torsion ~ 1/L) from a modulus error (all ~
sqrt(E)) or a compliant clamp (mode 1 most); when several causes reach the evidence cap of the
in-sample likelihood ratio, the cap alone would rank their in-sample fits and favour the cause
with more parameters.

Baseline: the probe's FEM with its declared parameters, the declared medium (Sader loading of
the flapwise modes) and a declared known mass; calibrated parameters: the intrinsic quality
factor (one loss factor for every mode) when Q values are given, and the quantities listed in
``[baseline] free``. Causes that change a quantity the sidecar declares known or calibrates
are not tried. The fits run on the Ritz reduction of each FEM; the final model is re-solved
with the FEM.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from probedyn.core.errors import DataFormatError, GeometryError
from probedyn.diagnose.causes import CauseParam, catalog
from probedyn.diagnose.fem_terms import face_mass_scalar
from probedyn.diagnose.formats import ModalData
from probedyn.diagnose.hydrodynamics import MEDIA, section_thickness_change
from probedyn.diagnose.modal_model import (FAMILIES, FEMBaseline, ModalState, ReducedModal, full_solve,
                                           full_static_stiffness)

__all__ = ["ModalProblem", "MF_UNIFORM", "MF_BOUND", "MF_CENTRE", "MF_SCALE", "STATIC_K_SEPARATING", "GEOMETRY_SEPARATING"]

MF_UNIFORM = 0.005  # prior sigma of the uniform relative frequency shift of a probe without a beam model
#: mode-to-mode scatter of the intrinsic quality factor (1 sigma of ln Q_int,i about the one fitted Q_int):
#: the intrinsic losses of a lever in vacuum are not one loss factor -- thermoelastic damping falls as 1/f
#: below the Zener frequency (Q_TED of flapwise 2 about 6 x lower than of flapwise 1 in a thin silicon lever),
#: clamping loss falls with the mode number, surface loss is about mode-independent (Yasumura et al.,
#: J. Microelectromech. Syst. 9, 117 (2000)); probedyn has no model of them, so a vacuum Q is held to one
#: Q_int only within a factor of 2 per mode (a blind generator's spectra, Q_int drawn per mode: 3 of its first 8
#: nulls 'unexplained' with every frequency within its noise, docs 9.17)
Q_INT_SCATTER = math.log(2.0)
#: the hydrodynamic model's accuracy on a fluid-damped Q, per unit width-to-length ratio: Sader's function is the
#: two-dimensional flow across an infinitely long plate; the three-dimensional flow about the free end, over a
#: length of about one width, is left out, and the flapwise modes move most there. Taken as 0.25 w / L (1 sigma
#: of ln Q; 2.5 % on a 300 x 30 um lever, 10 % on 100 x 40 um) -- an assumption of this order, not a measured
#: coefficient (no 3D hydrodynamic reference here). Held constant for every model that has a fluid (declared or
#: fitted): a sigma that followed the fluid's share of the damping would let a fit widen its own error bars
HYDRO_Q_ASPECT = 0.25
MF_BOUND = 3.0  # the priors are truncated at 3 sigma: model form is bounded, a larger discrepancy is not model form
#: the model-form amplitude's prior, in units of the probe's own 1D-3D gap (module docstring): the real root
#: lies between the beam (anticlastic curvature and warping free, -1) and the FEM's rigid clamp (both
#: restrained, 0), so the prior is centred between them with both limits at 1.43 sigma; truncated at MF_BOUND
#: sigmas it reaches 0.55 gap beyond either limit (the beam's own approximations: Cowper's kappa, Saint-Venant
#: torsion) and no further. Session 32: a prior N(0, 1) let a length error plus a model form 0.8 gap *stiffer*
#: than the rigid-clamp FEM imitate a compliant clamp (rate study seed 1049; blind m13, m23, m30).
MF_CENTRE = -0.5
MF_SCALE = 0.35
#: relative uncertainty of a static spring constant named as a separating measurement (a calibration against
#: a force standard or a precise reference lever; a reference-lever calibration is often 5-10 %): the
#: separation the report promises is the one such a measurement resolves at 3 sigma
STATIC_K_SEPARATING = 0.02
#: relative uncertainty of a lever dimension named as a separating measurement (optical or electron microscopy of
#: length and width, of the cross-section or a profilometer for the thickness): a length error and a compliant
#: clamp shift every bending mode alike (-2 dL/L, -2 c) and the static stiffness alike (-3 dL/L, -3 c); only
#: the geometry itself tells them apart
GEOMETRY_SEPARATING = {"length": 0.005, "width": 0.01, "thickness": 0.02}

_FREE = {  # [baseline] free quantity -> calibration parameter
    "thickness": CauseParam("cal_thickness", "1", 0.5, 2.0, 1.0, "thickness / nominal (calibrated)"),
    "width": CauseParam("cal_width", "1", 0.5, 2.0, 1.0, "width / nominal (calibrated)"),
    "length": CauseParam("cal_length", "1", 0.5, 2.0, 1.0, "length / nominal (calibrated)"),
    "modulus": CauseParam("cal_modulus", "1", 0.25, 4.0, 1.0, "elastic constants / nominal (calibrated)"),
    "density": CauseParam("cal_density", "1", 0.25, 4.0, 1.0, "density / nominal (calibrated)"),
}


class ModalProblem:
    kind = "modal"
    unit = "relative frequency"
    reduced = True
    #: rank claimed causes by their held-out (leave-one-mode-out) evidence: which mode pattern a
    #: cause predicts for a mode it was not fitted to is what tells causes apart (see docs/diagnose.md)
    rank_by_heldout = True
    #: within a confounded group the cause with the fewest parameters is named first (engine:
    #: ``_fewest_parameters_lead``; the spectra's modal problems inherit it)
    occam_within_group = True
    #: the folds (one mode left out) start from the null and from the full-data optimum of the
    #: cause's parameters (engine: ``cv_warm``). A cause located by several modes (a point mass: mass
    #: and position) has several (mass, position) pairs that fit the training modes about equally
    #: well; from the declared starts alone a fold ends in whichever basin the optimizer's path
    #: reaches, and the held-out mode then condemns the cause for that path, not for its physics
    #: (seed 1048: a point mass at chi2 0.6 for 6 modes scored 227.6 or 129.7 held-out nats depending
    #: on a 1e-12 change of the noise floor, and lost to a modulus error at chi2 5.3). The fold's
    #: optimum is still the best fit of its training modes (the held-out mode only chooses between
    #: basins the training data cannot); single-basin causes are unaffected (both starts reach the
    #: same optimum). The spectra's modal problems (``spectrum.py``) inherit it.
    cv_warm = True
    #: a held-out mode is scored by its predictive density with the fold's parameter uncertainty
    #: (engine: ``CrossValidation.heldout``): a mode can be the only one that informs a cause (the
    #: torsion mode the shear modulus of a crystal, the lateral mode a width error), and the other
    #: modes' noise then sets the fold's value of it; leave-one-mode-out with the fold's optimum taken
    #: as exact ranked a cubic-silicon lever's crystal cause (chi2 1.0 for 7 residuals) below a
    #: thickness error (chi2 36.7), whose torsion prediction the bending modes fix. The spectra's modal
    #: problems inherit it.
    heldout_predictive = True
    #: the likelihood carries the model's own error (the FEM's discretisation estimate in sigma, the 1D-3D and
    #: hydrodynamic model-form directions profiled with their priors): under the baseline the residuals are
    #: N(0, I), and a catalog cause's likelihood-ratio test alone may open a discrepancy (engine, step 2)
    model_error_in_likelihood = True

    def __init__(self, data: ModalData, *, bases: dict | None = None) -> None:
        self.data = data
        self.path = data.path
        d = data
        unsupported = [q for q in d.free if q not in _FREE]
        if unsupported:
            raise DataFormatError(f"{d.path}: [baseline] free: {', '.join(unsupported)} cannot be calibrated in a modal "
                                  f"measurement (possible: {', '.join(_FREE)})")
        self.known = set(d.known) | set(d.free)
        self.declared_medium = d.medium
        self.medium_name = d.medium_name
        # a baseline whose damping is intrinsic only (vacuum declared, or no medium declared) holds each
        # mode's Q to one intrinsic Q within its mode-to-mode scatter (Q_INT_SCATTER); in a declared fluid
        # the fluid's computed damping dominates the flapwise, torsion and lateral modes' Q, held to the
        # measurement's sigma (and the hydrodynamic model's accuracy), an axial mode's within the intrinsic scatter
        self.q_int_scatter = d.medium is None or d.medium[0] == 0.0
        self.n = len(d.freq)
        if self.n == 0:
            raise DataFormatError(f"{d.path}: no mode frequency to diagnose")
        # one FEM (and reduction) per free length
        self.lengths = sorted(set(np.round(d.length, 15).tolist())) if np.all(np.isfinite(d.length)) else [None]
        self.rows_of: dict[Any, np.ndarray] = {}
        self.need_of: dict[Any, list[tuple[str, int]]] = {}
        self.bases: dict[Any, FEMBaseline] = {}
        self.reds: dict[Any, ReducedModal] = {}
        for L in self.lengths:
            rows = np.nonzero(np.round(d.length, 15) == L)[0] if L is not None else np.arange(self.n)
            self.rows_of[L] = rows
            self.need_of[L] = [(d.family[i], int(d.order[i])) for i in rows]
        for L in self.lengths:
            if bases is not None and L in bases:
                b = bases[L]
            else:
                vals = dict(d.probe_values)
                if L is not None:
                    vals["length"] = L
                needed: dict[str, int] = {}
                noise: dict[tuple[str, int], float] = {}
                for i, (fa, o) in zip(self.rows_of[L], self.need_of[L]):
                    needed[fa] = max(needed.get(fa, 0), o)
                    noise[(fa, o)] = min(noise.get((fa, o), math.inf), float(d.freq_sigma[i]))
                # the mesh is refined for the stated noise (modal_model.DISC_NOISE_FRACTION)
                b = FEMBaseline(d.probe, d.probe.resolve(_probe_overrides(d.probe, vals)), needed, noise=noise)
            self.bases[L] = b
        self.reference_baseline = self.bases[self.lengths[-1]]
        self._check_units()
        # the stated noise plus the FEM's discretisation estimate, in quadrature
        self.disc = np.zeros(self.n)
        for L in self.lengths:
            b = self.bases[L]
            for i, (fa, o) in zip(self.rows_of[L], self.need_of[L]):
                self.disc[i] = b.disc_err[b.index(fa, o)]
        self.sigma_f = np.sqrt(d.freq_sigma**2 + self.disc**2)
        self.q_idx = np.nonzero(np.isfinite(d.Q))[0]
        # the model-form direction (relative frequency per unit prior sigma), see the module docstring
        self.beam_gap, self.mf_floor = self._model_form_gap()
        # the prior's centre as a fixed relative shift, its sigma in the direction (a uniform stiffness
        # direction has no physical bracket: centred on the FEM, MF_UNIFORM per sigma)
        centre, scale = (MF_CENTRE, MF_SCALE) if self.mf_floor == "beam" else (0.0, 1.0)
        self.mf_offset = centre * self.beam_gap
        self.mf_dirs = scale * self.beam_gap[:, None]
        self.mf_names = ("1D-3D model form" if self.mf_floor == "beam" else "uniform stiffness",)
        self.train_mask = None  # set by the engine during fits: the profile sees the fitted data only
        # the candidates' and the folds' fits through the engine's pool of forked processes (engine.WORKERS): each
        # job's numbers are those of the fit in turn (docs/diagnose.md 9.62)
        from probedyn.diagnose.engine import WORKERS

        self.workers = WORKERS
        b0 = self.reference_baseline
        self.hydro_q = HYDRO_Q_ASPECT * b0.w / b0.L if b0.L > 0 else 0.0
        self.gap_col = None  # the column of the fluid's 3D-mode vs uniform-beam direction, if any
        self._hydro_setup()
        self._static_setup()
        # groups: modes, the static spring constant, the modes' Q, and the model-form prior (-1: never held out)
        self.groups = np.concatenate([np.arange(self.n_f), self.q_idx, -np.ones(len(self.mf_names), int)])
        self.group_labels = [f"{fa} {o}" + (f" @ L = {L:.4g} m" if len(self.lengths) > 1 else "")
                             for fa, o, L in zip(d.family, d.order, d.length)]
        if self.static is not None:
            self.group_labels.append("static spring constant")
        base: list[CauseParam] = []
        # the Q rows a fluid model damps (flapwise: Sader; torsion: Green & Sader; lateral: the faces' Stokes layers)
        self.q_fluid = (np.isin(np.asarray(d.family)[self.q_idx], ("flapwise", "torsion", "lateral")) if len(self.q_idx)
                       else np.zeros(0, bool))
        self.q_torsion = np.asarray(d.family)[self.q_idx] == "torsion" if len(self.q_idx) else np.zeros(0, bool)
        if len(self.q_idx):
            q0 = float(np.median(d.Q[self.q_idx]))
            base.append(CauseParam("Q_int", "1", 1.0, 1e9, q0, "intrinsic quality factor (one loss factor for all modes)",
                                   scale="log", starts=(10 * q0,)))
        for q in d.free:
            base.append(_FREE[q])
        self.base_params = base
        m0 = self.reference_baseline.model
        self.probe_mass = float(m0.total_mass())
        self.shortest_length = min(b.L for b in self.bases.values())
        self.causes = []
        for cls in catalog("modal"):
            c = cls().constrain(self)
            if c is not None:
                self.causes.append(c)
        self.defect = None
        self._reds_built = False

    # -- set-up -------------------------------------------------------------------------------
    def supports(self, what: str) -> bool:
        b = self.reference_baseline
        if what == "fluid":
            return b.has_top
        if what == "mass":
            # the point mass rides on the mass path (the line through the clamp face's centroid): a hollow
            # section (a tube) has no material there to attach it to
            if not hasattr(self, "_mass_path_ok"):
                try:
                    b.model.points_operator(b.mass_path(np.linspace(0.02, 1.0, 8)))
                    self._mass_path_ok = True
                except (GeometryError, ValueError):
                    self._mass_path_ok = False
            return self._mass_path_ok
        if what == "overlap":
            # a lever bonded over an overlap: its clamp face is the lever's rectangular section, across the axis
            n = np.abs(np.asarray(b.clamp_normal, float))
            area = float(face_mass_scalar(b.model, b.clamp_face).sum())
            return bool(n[b.axis] > 0.999 and abs(area / (b.w * b.t) - 1.0) < 0.01)
        return True

    def _red(self, L) -> ReducedModal:
        r = self.reds.get(L)
        if r is None:
            b = self.bases[L]
            # the reduction depends on the FEM only: kept with the baseline, so that measurements
            # of the same probe (a shared ``bases``) reuse its factorisation and Ritz basis
            r = getattr(b, "reduced", None) or ReducedModal(b)
            b.reduced = r
            self.reds[L] = r
        return r

    def _hydro_setup(self) -> None:
        """A declared fluid's load on the flapwise frequencies is uncertain in two ways, each a model-form
        direction profiled with the 1D-3D amplitude (``ln f_i`` moving linearly, Gaussian priors):

        * *its size*: Sader's 2D function leaves out the 3D flow about the free end, as for the damping
          (:data:`HYDRO_Q_ASPECT` w / L, 1 sigma of the relative load): ``ln f_i`` moves by
          ``-share_i / 2`` per unit relative load, ``share_i = 1 - (f_fluid,i / f_vacuum,i)^2`` the fluid's
          part of mode i's effective mass in the declared medium (0 for the other families), prior N(0, 1);
        * *where it acts*: the diagnosis loads the transverse motion of the top face of the 3D mode (Rayleigh
          quotient); the uniform-beam form of Sader's method, ``f_v / sqrt(1 + T Gamma_r)``, loads the whole
          modal mass, including the in-plane motion of the section's rotation (rotary inertia: 3 % of
          flapwise 2's modal mass, 7 % of flapwise 3's on a 100 x 40 x 10 um lever). The gap
          ``g_i = ln(f_uniform,i / f_3D,i) = -ln((1 + x_i / r_i) / (1 + x_i)) / 2`` (``x_i`` the added-mass
          ratio, ``r_i`` the top face's share of the modal mass) is bracketed like the 1D-3D gap: prior
          N(MF_CENTRE, MF_SCALE^2) with the sign turned (between the 3D load, 0, and the uniform beam's, 1).

        * *the section's thickness*: both functions are the zero-thickness limits; the real section (t/w of the probe)
          changes Gamma_r by ``dGamma_r(Re_i, t/w)`` (:func:`~.hydrodynamics.section_thickness_change`, probedyn's
          2D Stokes table at each mode's Re), moving ``ln f_i`` by ``-ln((1 + x_i (1 + dGamma_r)) / (1 + x_i)) / 2``
          (:meth:`_thickness`): bracketed like the gap, N(MF_CENTRE, MF_SCALE^2) with the sign turned (0: the thin
          section, 1: the real one). The damping's change (and the added mass's share of it) is the fluid-damped Q
          rows' floor beside ``HYDRO_Q_ASPECT w / L``, in every fluid model, evaluated in the model's own fluid
          (declared or fitted) with each solve (:meth:`predict`'s ``q_thickness``).

        In water a few % of load error moves flapwise frequencies by percents, far beyond their noise: without
        these every declared liquid would read as an excess load or a mass. Each is added only where it can
        matter (its largest shift at least a tenth of the median relative frequency noise: not for air on a
        silicon lever, ~1e-5). The load's size is a declared medium's only (a fitted fluid's density is that
        size). The gap follows the model's own fluid -- the declared one, a fitted liquid (no medium declared:
        sized for water here), an excess load -- and is evaluated with each solve (:meth:`predict`'s ``gap``): a
        model without a fluid has none, and its prior pseudo-residual is then zero."""
        d = self.data
        self.gap_col = None
        if not self.reference_baseline.has_top:
            return
        declared = d.medium is not None and d.medium[0] > 0
        # the largest fluid a model of this problem can carry: the declared one; undeclared, a liquid (the
        # fluid-loading cause fits density and viscosity); a declared vacuum, its residual gas (air, 1.2 bar)
        probe_fluid = (d.medium if declared else MEDIA["water"] if d.medium is None
                       else (1.2 * MEDIA["air"][0], MEDIA["air"][1]))
        load = np.zeros(self.n)
        gap = np.zeros(self.n)
        thick = np.zeros(self.n)
        for L in self.lengths:
            s_f = self.state({}, (), L)
            s_f.medium = tuple(probe_fluid)
            h: dict = {}
            ff, _ = self._red(L).solve(s_f, self.need_of[L], hydro=h)
            x = np.nan_to_num(h.get("x", np.zeros(len(self.need_of[L]))))
            load[self.rows_of[L]] = -0.5 * x / (1.0 + x) * self.hydro_q
            gap[self.rows_of[L]] = self._gap(self.bases[L], x, h.get("r"))
            thick[self.rows_of[L]] = self._thickness(self.bases[L], self.need_of[L], ff, x, probe_fluid)[0]
        floor = 0.1 * float(np.median(self.sigma_f / d.freq))
        if declared and np.max(np.abs(load)) >= floor:
            self.mf_dirs = np.column_stack([self.mf_dirs, load])
            self.mf_names = self.mf_names + ("hydrodynamic load (Sader 2D)",)
        if declared and np.max(np.abs(thick)) >= floor:
            # bracketed like the gap below: 0 the thin section (Sader's, Green & Sader's), 1 the real one
            self.mf_offset = self.mf_offset - MF_CENTRE * thick
            self.mf_dirs = np.column_stack([self.mf_dirs, MF_SCALE * thick])
            self.mf_names = self.mf_names + ("section thickness in the fluid load",)
        if np.max(np.abs(gap)) >= floor:
            # its size follows the model's own fluid (declared or fitted): filled in each evaluation
            self.gap_col = self.mf_dirs.shape[1]
            self.mf_dirs = np.column_stack([self.mf_dirs, np.zeros(self.n)])
            self.mf_names = self.mf_names + ("fluid on the 3D mode or the uniform beam",)

    @staticmethod
    def _thickness(b, need, f: np.ndarray, x: np.ndarray, fluid) -> tuple[np.ndarray, np.ndarray]:
        """What the section's thickness does to each mode in ``fluid`` (:func:`~.hydrodynamics.section_thickness_change`
        at the mode's Re and the probe's t/w; flapwise: Sader's function, torsion: Green & Sader's; 0 for the
        other families): the shift of ``ln f``, ``-ln((1 + x (1 + dGamma_r)) / (1 + x)) / 2`` (``x`` the fluid's
        added-mass ratio of the thin-section load), and the relative change of the fluid's Q,
        ``|(1 + dGamma_r x / (1 + x)) / (1 + dGamma_i) - 1|`` (``Q_fluid ~ (m + m_a) / (c / omega)``)."""
        shift = np.zeros(len(need))
        dq = np.zeros(len(need))
        rho_f, eta_f = fluid
        if b.w <= 0 or b.t <= 0 or rho_f <= 0 or eta_f <= 0:
            return shift, dq
        re = rho_f * 2.0 * math.pi * np.asarray(f, float) * b.w**2 / (4.0 * eta_f)
        for motion, fam in (("flexure", "flapwise"), ("torsion", "torsion")):
            m = np.array([fa == fam for fa, _ in need]) & np.isfinite(re) & (x > 0)
            if not m.any():
                continue
            dr, di = section_thickness_change(re[m], b.t / b.w, motion)
            shift[m] = -0.5 * np.log((1.0 + x[m] * (1.0 + dr)) / (1.0 + x[m]))
            dq[m] = np.abs((1.0 + dr * x[m] / (1.0 + x[m])) / (1.0 + di) - 1.0)
        return shift, dq

    @staticmethod
    def _gap(b, x: np.ndarray, r: np.ndarray | None) -> np.ndarray:
        """``g_i = ln(f_uniform,i / f_3D,i) = -ln((1 + x_i / r_i) / (1 + x_i)) / 2`` per mode (``x_i`` the fluid's
        added-mass ratio, ``r_i`` the top face's share of the modal mass; :meth:`_hydro_setup`); 0 where there is no
        fluid load or the probe is not a plain prism (the share needs the section's one density and thickness)."""
        g = np.zeros(len(x))
        if r is None or getattr(b, "prism", None) is None:
            return g
        ok = np.isfinite(x) & (x > 0) & np.isfinite(r) & (r > 0)
        g[ok] = -0.5 * np.log((1.0 + x[ok] / r[ok]) / (1.0 + x[ok]))
        return g

    def _static_setup(self) -> None:
        """A measured static spring constant (``[static]``; :func:`~probedyn.diagnose.modal_model.end_stiffness`'s
        definition: an end load on the free-end face, along the thickness) is one more observable, held out
        like a mode: ``(k_meas - k_model (1 + c g_s)) / sigma_k`` with the model-form amplitude shared with the
        frequencies, ``g_s = ln(k_FEM / k_beam)`` the probe's own 1D-3D gap of the end stiffness (Timoshenko
        beam, ``3 E I / L^3`` with shear; twice the uniform direction without a beam, k ~ f^2) and ``sigma_k^2``
        the stated uncertainty plus the FEM's discretisation estimate (twice the relative one of flapwise 1:
        ``k = m_1 (2 pi f_1)^2`` at fixed mass) in quadrature. It separates causes the frequencies confound:
        a compliant clamp softens it (``k / (1 + 3 c)`` in beam theory), a point mass leaves it unchanged (the
        exact duality of the bending frequencies, ``tests/test_clamp_mass_duality.py``), a thickness error
        moves it as ``t^3`` where the frequencies move as ``t``, a modulus error as ``E`` against ``sqrt(E)``."""
        d = self.data
        self.static = d.static
        self.n_f = self.n
        if d.static is None:
            return
        L = d.probe_values.get("length")
        L = None if L is None or self.lengths == [None] else round(float(L), 15)
        if L not in self.bases:
            raise DataFormatError(f"{d.path}: [static] spring_constant: the modes are at lengths "
                                  f"{', '.join(f'{x:g}' for x in self.lengths)} m, none of them the probe's declared "
                                  "length, at which the static spring constant is taken")
        b = self.bases[L]
        red = self._red(L)
        if red.end_op is None:
            raise DataFormatError(f"{d.path}: [static] spring_constant: probe '{b.probe.name}' has no free-end face "
                                  "to load (the static spring constant is an end load)")
        self.static_L = L
        self.n_f = self.n + 1
        k0 = red.static_stiffness(self.state({}, (), L))
        if getattr(b, "prism", None) is not None:
            from probedyn.lumped import beam as bm

            g = math.log(k0 / bm.static_tip_stiffness(bm.RectBeam(*b.prism), "flapwise", shear=True))
            centre, scale = MF_CENTRE, MF_SCALE
        else:
            g, centre, scale = 2 * MF_UNIFORM, 0.0, 1.0
        if self.mf_floor != "beam":  # the frequencies carry the uniform direction: the same for k
            g, centre, scale = 2 * MF_UNIFORM, 0.0, 1.0
        self.static_gap = g
        self.static_offset = centre * g
        self.static_dir = scale * g
        try:
            i1 = b.index("flapwise", 1)
            disc_rel = 2.0 * float(b.disc_err[i1] / b.freqs[i1])
        except DataFormatError:
            disc_rel = 0.0
        self.static_disc = disc_rel * k0
        self.static_sigma = math.hypot(d.static[1], self.static_disc)

    def _static_model(self, values, causes, full: bool = False) -> float:
        s = self.state(values, causes, self.static_L)
        if full:
            return full_static_stiffness(self.bases[self.static_L], s)
        return self._red(self.static_L).static_stiffness(s)

    def _model_form_gap(self) -> tuple[np.ndarray, str]:
        """The first model-form direction (relative frequency per prior sigma, one entry per
        measured mode): the probe's own 1D-3D gap ``ln(f_FEM / f_beam)`` of each measured mode
        (:meth:`FEMBaseline._beam_gap`), so that the floor is as large as beam theory and the 3D FEM
        disagree on *this* probe, mode by mode, and vanishes where they agree; a mode the beam has
        no value for takes the largest gap of its family (else of all measured modes). Probes
        without a beam (a tip, several materials, an anisotropic crystal) keep a uniform stiffness
        direction of ``MF_UNIFORM``."""
        gap = np.full(self.n, np.nan)
        for L in self.lengths:
            b = self.bases[L]
            if b.beam_gap is None:
                return np.full(self.n, MF_UNIFORM), "uniform"
            for i, (fa, o) in zip(self.rows_of[L], self.need_of[L]):
                gap[i] = b.beam_gap[b.index(fa, o)]
        ok = np.isfinite(gap)
        if not ok.any():
            return np.full(self.n, MF_UNIFORM), "uniform"
        for i in np.nonzero(~ok)[0]:
            same = ok & (self.data.family == self.data.family[i])
            gap[i] = np.max(np.abs(gap[same if same.any() else ok]))
        return gap, "beam"

    def _check_units(self) -> None:
        """kHz typed as Hz (or the reverse), or a wrong probe: the measured frequencies are orders
        of magnitude from the FEM's."""
        d = self.data
        ratios = []
        for L in self.lengths:
            b = self.bases[L]
            for i, (fa, o) in zip(self.rows_of[L], self.need_of[L]):
                ratios.append(d.freq[i] / b.freqs[b.index(fa, o)])
        r = float(np.median(ratios))
        if r < 1 / 30 or r > 30:
            hint = ""
            if 3e-4 < r < 3e-3:
                hint = " (kHz typed as Hz?)"
            elif 300 < r < 3000:
                hint = " (Hz typed as kHz?)"
            elif 3e-7 < r < 3e-6:
                hint = " (MHz typed as Hz?)"
            raise DataFormatError(f"{d.path}: the measured frequencies are {r:.3g} times the probe model's "
                                  f"(f1 model {self.reference_baseline.freqs[0]:.4g} Hz){hint}; check the units and "
                                  "the probe parameters")

    # -- model --------------------------------------------------------------------------------
    def state(self, values: dict[str, float], causes=(), L=None) -> ModalState:
        d = self.data
        b = self.bases[L]
        s = ModalState(medium=d.medium if d.medium is not None else (0.0, 1.8e-5),
                       axes={"length": b.length_axis, "width": b.width_axis, "thickness": b.thickness_axis},
                       length=b.L)
        if d.known_mass is not None:
            s.masses = [(d.known_mass[1], d.known_mass[0])]
        s.Q_int = values.get("Q_int", math.inf)
        sc = np.ones(3)
        for q, ax in (("thickness", b.thickness_axis), ("width", b.width_axis), ("length", b.length_axis)):
            if f"cal_{q}" in values:
                sc[ax] *= values[f"cal_{q}"]
        s.scale = sc
        s.E_factor = values.get("cal_modulus", 1.0)
        s.rho_factor = values.get("cal_density", 1.0)
        for c in causes:
            c.effect(values, s)
        return s

    def predict(self, values, causes=(), full: bool = False, gap: np.ndarray | None = None,
                q_thickness: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Frequencies and Q of the measured rows; ``gap`` (an array of n, filled when given): the model's own
        fluid's 3D-mode vs uniform-beam gap per row (:meth:`_gap`); ``q_thickness`` (likewise): the relative
        change of the model's own fluid's Q by the section's thickness per row (:meth:`_thickness`)."""
        f = np.full(self.n, np.nan)
        Q = np.full(self.n, np.nan)
        want = gap is not None or q_thickness is not None  # the solve's fluid quantities (added mass, top share)
        for L in self.lengths:
            s = self.state(values, causes, L)
            h: dict = {}
            if full:
                ff, qq, info = full_solve(self.bases[L], s, self.need_of[L])
                h = info["hydro"]
            else:
                ff, qq = self._red(L).solve(s, self.need_of[L], hydro=h if want else None)
            f[self.rows_of[L]] = ff
            Q[self.rows_of[L]] = qq
            x = np.asarray(h.get("x", np.full(len(ff), np.nan)), float) if want else None
            if gap is not None:
                gap[self.rows_of[L]] = self._gap(self.bases[L], x, h.get("r"))
            if q_thickness is not None:
                fluid = s.medium if s.fluid_factor > 0 else (0.0, 0.0)
                q_thickness[self.rows_of[L]] = self._thickness(self.bases[L], self.need_of[L], ff, np.nan_to_num(x),
                                                               fluid)[1]
        return f, Q

    def _residuals(self, f, Q, intrinsic_only: bool = False, k: float | None = None, fluid: bool = False,
                   gap: np.ndarray | None = None, q_thickness: np.ndarray | None = None,
                   q_share: np.ndarray | None = None) -> np.ndarray:
        d = self.data
        offset, dirs = self.mf_offset, self.mf_dirs
        if self.gap_col is not None and gap is not None:
            # the fluid's 3D-mode vs uniform-beam gap of this model's own fluid: prior N(MF_CENTRE, MF_SCALE^2)
            # with the sign turned (0: the 3D load, 1: the uniform beam's)
            offset = offset - MF_CENTRE * gap
            dirs = dirs.copy()
            dirs[:, self.gap_col] = MF_SCALE * gap
        r = (d.freq - f * (1.0 + offset)) / self.sigma_f
        B = dirs * (f / self.sigma_f)[:, None]
        if self.static is not None:  # the static spring constant: one more row of the same linear profile
            r = np.append(r, (self.static[0] - k * (1.0 + self.static_offset)) / self.static_sigma)
            row = np.zeros((1, B.shape[1]))
            row[0, 0] = self.static_dir * k / self.static_sigma  # the fluid does not load a static deflection
            B = np.vstack([B, row])
        r = np.where(np.isfinite(r), r, 1e6)
        a = self._profile(r, B)
        r = r - np.where(np.isfinite(B), B, 0.0) @ a
        if self.train_mask is not None:
            # held-out modes: the residual is whitened by its predictive sigma, which includes the
            # model-form amplitude's uncertainty left after the training modes (posterior covariance
            # (B_t^T B_t + I)^-1 of the ridge profile): a mode the training data constrain poorly
            # in that direction is not held to the bare noise (diagonal; one mode per fold here)
            held = ~np.asarray(self.train_mask)[: self.n_f]
            if held.any():
                Bt = np.where(np.isfinite(B), B, 0.0)
                P = np.linalg.inv(Bt[~held].T @ Bt[~held] + np.eye(B.shape[1]))
                var = 1.0 + np.einsum("ij,jk,ik->i", Bt[held], P, Bt[held])
                r[held] = r[held] / np.sqrt(var)
        if len(self.q_idx):
            i = self.q_idx
            sig = d.Q_sigma_rel[i]
            if intrinsic_only:
                # the intrinsic loss is not one number for every mode (Q_INT_SCATTER): a model whose damping
                # is intrinsic only holds each Q to its one Q_int within that scatter
                sig = np.sqrt(sig**2 + Q_INT_SCATTER**2)
            elif fluid:
                # a fluid in the model damps its flapwise modes by Sader's 2D function, accurate to HYDRO_Q_ASPECT
                # w/L, its torsion modes by Green & Sader's -- both thin-section limits, held also within the
                # section's thickness (q_thickness, _hydro_setup) -- and its lateral ones by the faces' Stokes layers
                # (held alike); an axial mode's damping is the one Q_int, held within the intrinsic scatter as in a vacuum
                qt = 0.0 if q_thickness is None else q_thickness[i]
                if q_share is None:
                    sig_f = np.sqrt(sig**2 + self.hydro_q**2 + qt**2)
                else:
                    # a rarefied gas damps about as much as the intrinsic loss (s = Q / Q_int its share of the
                    # mode's damping): d ln Q is s times the intrinsic scatter plus (1 - s) times the fluid
                    # model's error -- the intrinsic-only baseline's sigma at the null (p -> 0, s -> 1), so the
                    # cause nests it; in a liquid or a gas at 1 bar s ~ 0.01-0.05 and this is the fluid's sigma
                    sf = 1.0 - q_share
                    sig_f = np.sqrt(sig**2 + sf**2 * (self.hydro_q**2 + qt**2) + (q_share * Q_INT_SCATTER) ** 2)
                sig = np.where(self.q_fluid, sig_f, np.sqrt(sig**2 + Q_INT_SCATTER**2))
            r = np.concatenate([r, (np.log(d.Q[i]) - np.log(Q[i])) / sig])
        r = np.concatenate([r, a])
        return np.where(np.isfinite(r), r, 1e6)

    def model_form(self, r: np.ndarray, f: np.ndarray) -> np.ndarray:
        """The model-form amplitude(s) (in prior sigmas) that best explain the whitened frequency
        residuals ``r`` of the fitted modes (ridge least squares = Gaussian prior N(0, 1))."""
        return self._profile(r, self.mf_dirs * (f / self.sigma_f)[:, None])

    def _profile(self, r: np.ndarray, B: np.ndarray) -> np.ndarray:
        """:meth:`model_form` on the rows of ``r`` (frequencies, then the static spring constant if
        measured) with their directions ``B`` (per prior sigma, whitened)."""
        B = np.where(np.isfinite(B), B, 0.0)
        m = np.ones(len(r), bool) if self.train_mask is None else np.asarray(self.train_mask)[: len(r)]
        Bm, rm = B[m], r[m]
        A = Bm.T @ Bm + np.eye(B.shape[1])
        a = np.linalg.solve(A, Bm.T @ rm)
        # the model-form range is bounded (truncated prior, |a| <= MF_BOUND sigmas): beyond it a
        # discrepancy is not model form and must be left to the causes
        for _ in range(2):
            out = np.abs(a) > MF_BOUND
            if not out.any():
                break
            a[out] = np.clip(a[out], -MF_BOUND, MF_BOUND)
            free = ~out
            if free.any():
                a[free] = np.linalg.solve(A[np.ix_(free, free)], Bm[:, free].T @ (rm - Bm[:, out] @ a[out]))
                a[free] = np.clip(a[free], -MF_BOUND, MF_BOUND)
        return a

    def residuals(self, values, causes=()) -> np.ndarray:
        k = self._static_model(values, causes) if self.static is not None else None
        gap = np.zeros(self.n) if self.gap_col is not None else None
        qt = np.zeros(self.n) if len(self.q_idx) else None
        f, Q = self.predict(values, causes, gap=gap, q_thickness=qt)
        r = self._residuals(f, Q, self._intrinsic_only(values, causes), k, self._fluid(values, causes), gap, qt,
                            self._q_share(values, causes, Q))
        if self.defect is not None:
            r = r + self.defect
        return r

    def full_residuals(self, values, causes=()) -> np.ndarray:
        k = self._static_model(values, causes, full=True) if self.static is not None else None
        gap = np.zeros(self.n) if self.gap_col is not None else None
        qt = np.zeros(self.n) if len(self.q_idx) else None
        f, Q = self.predict(values, causes, full=True, gap=gap, q_thickness=qt)
        return self._residuals(f, Q, self._intrinsic_only(values, causes), k, self._fluid(values, causes), gap, qt,
                               self._q_share(values, causes, Q))

    def _q_share(self, values, causes, Q: np.ndarray) -> np.ndarray | None:
        """The intrinsic loss's share ``Q / Q_int`` of each Q row's damping in a model whose fluid is a rarefied
        gas (a residual gas in a declared vacuum, ``ModalState.gas``); None otherwise (a continuum fluid's damping
        dominates, or there is no fluid)."""
        if not len(self.q_idx) or "Q_int" not in values or self.state(values, causes, self.lengths[0]).gas is None:
            return None
        return np.clip(Q[self.q_idx] / values["Q_int"], 0.0, 1.0)

    def inactive_rows(self, values, causes) -> int:
        """The fluid-gap direction's prior pseudo-residual in a model without a fluid: its column and amplitude
        are zero there (the engine leaves the row out of the count of data)."""
        if self.gap_col is None:
            return 0
        s = self.state(values, causes, self.lengths[0])
        return int(not (s.medium[0] > 0 and s.fluid_factor > 0))

    def _intrinsic_only(self, values, causes) -> bool:
        """Whether the model's damping is intrinsic only (a Q_int, no fluid: its Q residuals carry the intrinsic
        loss's mode-to-mode scatter). A fluid model's Q is the fluid's, computed, and is held to the measurement's
        sigma: a scatter weighted by the intrinsic share Q / Q_int would let a fit lower Q_int to widen its own
        error bars."""
        return (self.q_int_scatter and "Q_int" in values
                and self.state(values, causes, self.lengths[0]).medium[0] == 0.0)

    def _fluid(self, values, causes) -> bool:
        """Whether the model's flapwise modes are damped by a fluid (declared or a cause's)."""
        if not len(self.q_idx):
            return False
        s = self.state(values, causes, self.lengths[0])
        return s.medium[0] > 0 and s.fluid_factor > 0

    def physical_rms(self, r: np.ndarray) -> float:
        """RMS relative frequency error of the frequency part of a whitened residual."""
        rel = np.asarray(r[: self.n]) * self.sigma_f / self.data.freq
        return float(np.sqrt(np.mean(rel**2)))

    # -- structure of the residuals -------------------------------------------------------------
    def structure(self, r: np.ndarray) -> dict[str, Any]:
        d = self.data
        rf = np.asarray(r[: self.n])
        out: dict[str, Any] = {"rows": [], "by_family": {}}
        for k in range(self.n):
            out["rows"].append({"mode": self.group_labels[k], "f_meas_Hz": float(d.freq[k]),
                                "sigma_Hz": float(self.sigma_f[k]), "fem_discretisation_Hz": float(self.disc[k]),
                                "residual_sigma": float(rf[k]), "residual_rel": float(rf[k] * self.sigma_f[k] / d.freq[k])})
        for fam in FAMILIES:
            sel = d.family == fam
            if not sel.any():
                continue
            x = d.order[sel].astype(float)
            y = rf[sel]
            item: dict[str, Any] = {"n": int(sel.sum()), "mean_sigma": float(np.mean(y))}
            if sel.sum() >= 3 and np.ptp(x) > 0:
                A = np.vstack([np.ones_like(x), x - x.mean()]).T
                coef = np.linalg.lstsq(A, y, rcond=None)[0]
                item["slope_per_order_sigma"] = float(coef[1])
                item["slope_t"] = float(coef[1] * math.sqrt(np.sum((x - x.mean()) ** 2)))
            out["by_family"][fam] = item
        if self.static is not None:
            out["static"] = {"k_meas_N_per_m": float(self.static[0]), "sigma_N_per_m": float(self.static_sigma),
                             "fem_discretisation_N_per_m": float(self.static_disc),
                             "residual_sigma": float(r[self.n]),
                             "residual_rel": float(r[self.n] * self.static_sigma / self.static[0])}
        if len(self.q_idx):
            out["Q_residual_sigma"] = [float(v) for v in r[self.n_f:self.n_f + len(self.q_idx)]]
        out["model_form"] = {nm: {"amplitude_prior_sigmas": float(a),
                                  "relative_frequency_shift_mode1": float((self.mf_offset[0] if k == 0 else 0.0)
                                                                          + a * self.mf_dirs[0, k])}
                             for k, (nm, a) in enumerate(zip(self.mf_names, r[len(r) - len(self.mf_names):]))}
        return out

    # -- observables that would separate confounded causes --------------------------------------
    def predict_observables(self, values, causes) -> list[dict[str, Any]]:
        """Frequencies of the FEM modes not measured (at the reference length), Q of the
        flapwise modes if no Q was measured, the static spring constant at the free end if not
        measured (to :data:`STATIC_K_SEPARATING`) and the lever's dimensions that are neither known
        nor calibrated (to :data:`GEOMETRY_SEPARATING`)."""
        d = self.data
        L = self.lengths[-1]
        b = self.bases[L]
        have = {(fa, int(o)) for fa, o, LL in zip(d.family, d.order, d.length)
                if (L is None or round(LL, 15) == L)}
        cnt: dict[str, int] = {}
        cand = []
        for fa in b.families:
            if fa not in FAMILIES:
                continue
            cnt[fa] = cnt.get(fa, 0) + 1
            if (fa, cnt[fa]) not in have:
                cand.append((fa, cnt[fa]))
        s = self.state(values, causes, L)
        out = []
        red = self._red(L)
        if self.static is None and red.end_op is not None:
            k0 = red.static_stiffness(self.state({}, (), L))
            out.append({"measure": "static spring constant (end load)", "value": red.static_stiffness(s),
                        "sigma": STATIC_K_SEPARATING * k0, "unit": "N/m"})
        nominal = {"length": b.L, "width": b.w, "thickness": b.t}
        axis = {"length": b.length_axis, "width": b.width_axis, "thickness": b.thickness_axis}
        for q, rel in GEOMETRY_SEPARATING.items():
            # a known or calibrated dimension is no cause's to change; a probe without it (a tube's width) has none
            if q not in self.known and q in b.probe.params:
                out.append({"measure": f"lever {q} (microscopy)", "value": nominal[q] * float(s.scale[axis[q]]),
                            "sigma": rel * nominal[q], "unit": "m"})
        if not cand:
            return out
        f, Q = red.solve(s, cand)
        rel = float(np.median(d.freq_sigma / d.freq))
        for (fa, o), ff, qq in zip(cand, f, Q):
            out.append({"measure": f"{fa} mode {o} frequency", "value": float(ff), "sigma": rel * float(ff), "unit": "Hz"})
            if not len(self.q_idx) and fa == "flapwise" and np.isfinite(qq):
                out.append({"measure": f"Q of {fa} mode {o}", "value": float(math.log(qq)), "sigma": 0.05, "unit": "ln Q"})
        return out

    def describe(self) -> dict[str, Any]:
        d = self.data
        b = self.reference_baseline
        return {"kind": "modal", "modes": self.n, "with_Q": int(len(self.q_idx)),
                "families": sorted(set(d.family.tolist())),
                "lengths_m": [float(x) for x in self.lengths if x is not None],
                "noise_stated": d.noise_stated, "medium": self.medium_name or "not declared",
                "known": sorted(self.data.known), "calibrated": list(d.free),
                "static_spring_constant_N_per_m": None if self.static is None else list(self.static),
                "probe": b.probe.name, "probe_mass_kg": self.probe_mass, "group_labels": list(self.group_labels),
                "residual_labels": (list(self.group_labels[: self.n_f]) + [f"Q {self.group_labels[i]}" for i in self.q_idx]
                                    + [f"prior: {nm}" for nm in self.mf_names])}

    def model_description(self) -> dict[str, Any]:
        out = []
        for L in self.lengths:
            b = self.bases[L]
            out.append({"length_m": L, "fem_dofs": b.model.dofs, "fem_modes": len(b.families),
                        "fem_families": b.families, "fem_frequencies_hz": [float(x) for x in b.freqs],
                        "fem_solve_s": b.solve_s, "discretisation": b.disc_note, "thickness_stretch": b.stretch,
                        "reduced_basis": self.reds[L].r if L in self.reds else None})
        elem = type(self.reference_baseline.model.basis.elem).__name__
        return {"baseline": f"3D FEM of probe '{self.reference_baseline.probe.name}' ({elem})",
                "fits": "Ritz reduction of the FEM (modes, stretch sensitivities, clamp-support, mass and prestress "
                        "shapes); final model re-solved with the FEM", "fems": out}


def _probe_overrides(probe, values: dict) -> dict:
    """Resolved values back to overrides (drop None and defaults that resolve re-derives)."""
    return {k: v for k, v in values.items() if v is not None and k in probe.params}
