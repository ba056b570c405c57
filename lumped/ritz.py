"""Rayleigh–Ritz reduction of an FE probe: the lowest modes plus static correction shapes.

This is probedyn's one reduced-model mechanism (reduced probes, nano-placing with several
attached samples, holder-stiffness studies, diagnose's model extensions all use it).

Basis
-----
For an :class:`~probedyn.fem.model.ElasticModel` with stiffness ``K`` and mass ``M`` (free DOFs,
clamped ones eliminated) the basis is

    T0 = [ Phi_n | Psi ],     K Phi = M Phi Lambda  (the n lowest FEM modes),
                              K Psi = A^T D        (static correction shapes),

where every column of ``A^T D`` is a unit load along a requested direction d at a named
attachment (``A`` the (3, ndofs) attachment operator of :meth:`ElasticModel.attachment`: P2
interpolation at a point, area average over a face).  ``Psi`` is made M-orthogonal to
``Phi_n`` and M-orthonormalised (linearly dependent load shapes are dropped, with a relative
threshold on the Gram matrix's eigenvalues), and the reduced eigenproblem on ``span(T0)`` is
solved once, so the stored basis ``T`` satisfies

    T^T M T = I,   T^T K T = diag(omega_j^2)   (r x r, r = n + number of kept static shapes).

Its first n columns are the FEM modes themselves (the exact eigenvectors lie in the span, and
the static block lives in their M-orthogonal complement, whose Ritz values are >= lambda_{n+1}),
so the Ritz frequencies of the bare probe equal the FEM's to solver precision; the remaining
columns ("static" pseudo-modes) carry the residual flexibility of the discarded modes at the
attachments.  This is the mode-acceleration / residual-flexibility correction (Craig & Kurdila,
*Fundamentals of Structural Dynamics*, 2nd ed., sections 14.3-14.4; MacNeal 1971): with the
static shapes in the span, the reduced static compliance at the attachments equals the FEM's
exactly, ``A T (T^T K T)^-1 T^T A^T = A K^-1 A^T``, and so does the static response to any
spring or load acting at those attachments (the solution stays in ``span(K^-1 A^T)``).

Additions without a FEM re-solve
--------------------------------
Point masses and springs (at attachments or anywhere: ``operator(where)`` works for any named
point, face or coordinates of the model) enter as low-rank updates of the reduced matrices,

    M_r' = I + sum_m m B_m^T B_m,     K_r' = diag(omega^2) + sum_s k B_s^T D_s B_s,

with ``B = A T`` (3, r) (``B_a - B_b`` for a spring between two attachments), exactly as
:meth:`ElasticModel.assemble` adds them to the full matrices; the dense r x r generalised
eigenproblem is then solved (:meth:`RitzBasis.solve`).  Rayleigh–Ritz frequencies are upper
bounds of the FEM's with the same additions (minimax principle).  ``with_stiffness`` adds a
projected FEM matrix ``s T^T K_x T`` (a geometric stiffness for prestress, a root-spring matrix).

Accuracy (docs/reduced-probes.md has the measured numbers): an addition at an attachment whose
static shapes are in the basis is exact in the static limit and its frequency error falls with
the retained modes like the dynamic part of the residual flexibility, ~(omega/omega_{n+1})^2;
an addition elsewhere converges only through the modes (algebraically with n).

A model with a lumped tip on a spring (duck-typed: attribute ``lumped_tip`` and method
``augmented()``, the smart probes) is reduced in its augmented coordinates; the three tip DOFs
are the attachment ``"lumped_tip"``.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping, Sequence, Union

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from probedyn.core.errors import DataFormatError, GeometryError, ParameterError, SolverError
from probedyn.fem.eigen import TO_FLOOR, factorize, shift_invert_eigsh
from probedyn.fem.model import PointMass, Spring

Where = Union[str, Sequence[float], np.ndarray]
LUMPED_TIP = "lumped_tip"
_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}
#: relative threshold on the eigenvalues of the static shapes' Gram matrix below which a shape
#: is considered linearly dependent on the others (and on the modes) and dropped
GRAM_RTOL = 1e-10


def _key(where: Where) -> Any:
    return where if isinstance(where, str) else tuple(float(v) for v in np.asarray(where, dtype=float).ravel())


def _directions(spec: Any) -> list[np.ndarray]:
    """'xyz' / 'z' / a vector / a list of vectors -> list of unit vectors."""
    if spec is None:
        spec = "xyz"
    if isinstance(spec, str):
        bad = [c for c in spec if c not in _AXES]
        if bad or not spec:
            raise ParameterError(f"attachment directions must be a string of x, y, z or vectors, got {spec!r}")
        return [np.array(_AXES[c]) for c in spec]
    arr = np.asarray(spec, dtype=float)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ParameterError(f"attachment direction vectors must have 3 components, got shape {arr.shape}")
    out = []
    for d in arr:
        n = np.linalg.norm(d)
        if not (np.isfinite(n) and n > 0):
            raise ParameterError("attachment direction must be a non-zero vector")
        out.append(d / n)
    return out


def _attachment_specs(attachments: Iterable[Any]) -> list[tuple[Where, list[np.ndarray]]]:
    """Normalise ``attachments``: each item is ``where`` or ``(where, directions)``."""
    specs = []
    for a in attachments:
        if isinstance(a, tuple) and len(a) == 2 and (isinstance(a[1], str) or np.ndim(a[1]) >= 1):
            specs.append((a[0], _directions(a[1])))
        else:
            specs.append((a, _directions(None)))
    return specs


class _System:
    """The model's K, M restricted to its unknowns (free mesh DOFs [+ 3 lumped-tip DOFs]) and
    the attachment operators in those unknowns."""

    def __init__(self, model: Any) -> None:
        self.model = model
        self.ndofs_total = int(model.ndofs_total)
        free = np.asarray(model.free_dofs)
        self.free = free
        lt = getattr(model, "lumped_tip", None)
        if lt is not None:
            Ka, Ma, free_a, _ = model.augmented()
            self.K, self.M = Ka.tocsr(), Ma.tocsr()
            self.n_extra = 3
        else:
            K, M = model.assemble()
            self.K = K[free][:, free].tocsr()
            self.M = M[free][:, free].tocsr()
            self.n_extra = 0
        self.n = self.K.shape[0]

    def attachment(self, where: Where) -> sp.csr_matrix:
        """(3, n) operator in the unknowns."""
        if isinstance(where, str) and where == LUMPED_TIP:
            if not self.n_extra:
                raise GeometryError("this model has no lumped tip (attachment 'lumped_tip')")
            A = sp.lil_matrix((3, self.n))
            for c in range(3):
                A[c, self.n - 3 + c] = 1.0
            return A.tocsr()
        A = self.model.attachment(where).tocsr()[:, self.free]
        if self.n_extra:
            A = sp.hstack([A, sp.csr_matrix((3, self.n_extra))], format="csr")
        return A

    def embed(self, X: np.ndarray) -> np.ndarray:
        """Unknowns (n, k) -> full vectors (ndofs_total + n_extra, k), clamped DOFs zero."""
        X = np.asarray(X)
        out = np.zeros((self.ndofs_total + self.n_extra,) + X.shape[1:])
        nf = self.free.size
        out[self.free] = X[:nf]
        if self.n_extra:
            out[self.ndofs_total:] = X[nf:]
        return out


@dataclass
class RitzSolution:
    """Eigenpairs of a (modified) reduced model: ``omega`` [rad/s] ascending, ``shapes``
    (r, k) reduced coordinates, mass-normalised with the modified reduced mass matrix."""

    omega: np.ndarray
    shapes: np.ndarray
    basis: "RitzBasis" = field(repr=False)
    K: np.ndarray = field(repr=False, default=None)
    M: np.ndarray = field(repr=False, default=None)

    @property
    def frequencies_hz(self) -> np.ndarray:
        return self.omega / (2 * np.pi)

    def at(self, where: Where) -> np.ndarray:
        """(3, k) displacement of every mode at an attachment."""
        return self.basis.operator(where) @ self.shapes

    def effective_mass(self, where: Where, direction: Sequence[float]) -> np.ndarray:
        """``1 / (d . u)^2`` per mode [kg] (inf where the mode does not move ``where`` along d)."""
        d = np.asarray(direction, dtype=float)
        u = (d / np.linalg.norm(d)) @ self.at(where)
        with np.errstate(divide="ignore"):
            return np.where(np.abs(u) > 0, 1.0 / u**2, np.inf)

    def expand(self, i: int | None = None) -> np.ndarray:
        """Full FEM field of mode ``i`` (or all modes, (ndofs, k))."""
        a = self.shapes if i is None else self.shapes[:, i]
        return self.basis.expand(a)


class RitzBasis:
    """A Ritz basis of an FE model (module docstring).  Build with :meth:`from_model`.

    Attributes: ``K``, ``M`` (r, r) reduced matrices; ``omega`` (r,) the Ritz frequencies of
    the bare model [rad/s]; ``kinds`` ("mode" or "static" per column); ``n_modes``;
    ``attachments`` (the static-correction attachments and directions); ``T`` (ndofs, r) the
    basis in full FEM coordinates (None after loading without it); ``meta`` (DOFs, timings).
    """

    def __init__(self, K: np.ndarray, M: np.ndarray, omega: np.ndarray, kinds: Sequence[str], n_modes: int,
                 T: np.ndarray | None = None, operators: Mapping[Any, np.ndarray] | None = None,
                 attachments: Sequence[tuple[Any, list]] = (), model: Any = None, system: _System | None = None,
                 meta: Mapping[str, Any] | None = None) -> None:
        self.K = np.asarray(K, dtype=float)
        self.M = np.asarray(M, dtype=float)
        self.omega = np.asarray(omega, dtype=float)
        self.kinds = list(kinds)
        self.n_modes = int(n_modes)
        self.T = T
        self._ops: dict[Any, np.ndarray] = {k: np.asarray(v, dtype=float) for k, v in (operators or {}).items()}
        self.attachments = [(w, [list(map(float, d)) for d in dirs]) for w, dirs in attachments]
        self.model = model
        self._sys = system
        self.meta = dict(meta or {})
        self.static_coeffs = np.zeros((self.K.shape[0], 0))

    # ---- construction -------------------------------------------------------------------
    @classmethod
    def from_model(cls, model: Any, n_modes: int, attachments: Iterable[Any] = (), solver: str = "auto",
                   keep_basis: bool = True) -> "RitzBasis":
        """Reduce ``model`` to its ``n_modes`` lowest modes plus static correction shapes.

        ``attachments``: items ``where`` (unit loads along x, y and z) or ``(where, dirs)`` with
        ``dirs`` a string of axes (``"z"``, ``"yz"``) or direction vectors; ``where`` is a named
        point, a boundary name (area average), coordinates, or ``"lumped_tip"``.  The model must
        be held (clamp or grounded spring): static shapes need a non-singular stiffness.
        """
        if int(n_modes) != n_modes or n_modes < 1:
            raise ParameterError(f"n_modes must be a positive integer, got {n_modes}")
        n_modes = int(n_modes)
        specs = _attachment_specs(attachments)
        if not getattr(model, "clamp", None) and not getattr(model, "springs", None):
            raise SolverError("Ritz reduction needs a held model (a clamp or a grounded spring)")
        if hasattr(model, "check_resolution"):
            model.check_resolution(n_modes)
        t0 = time.perf_counter()
        sysm = _System(model)
        t1 = time.perf_counter()
        # tol: the reduction takes the modes as exact eigenvectors (diagonal K_r, static shapes
        # K-orthogonal to them), so their residuals are driven to the round-off floor
        res = shift_invert_eigsh(sysm.K, sysm.M, n_modes, sigma=0.0 if getattr(model, "clamp", None) else None,
                                 solver=solver, tol=TO_FLOOR)
        Phi = res.vectors
        lam = res.eigenvalues
        t2 = time.perf_counter()
        # static correction shapes K^-1 A^T d
        loads = []
        for where, dirs in specs:
            A = sysm.attachment(where)
            for d in dirs:
                loads.append(np.asarray(A.T @ d).ravel())
        s_kept = 0
        static_response: dict[str, Any] = {}
        Psi_raw = None
        if loads:
            F = np.column_stack(loads)
            fac = factorize(sysm.K, spd=True, solver=solver)
            try:
                Psi = np.asarray(fac.solve(F)).reshape(sysm.n, -1)
            finally:
                fac.release()
            if not np.all(np.isfinite(Psi)):
                raise SolverError("static correction shapes are not finite (singular stiffness)")
            Psi_raw = Psi
            j = 0
            for where, dirs in specs:  # the FEM static solves themselves: displacement at the attachment
                U = np.asarray(sysm.attachment(where) @ Psi_raw[:, j:j + len(dirs)])
                static_response[str(_key(where))] = {"directions": np.array(dirs).T, "displacement": U}
                j += len(dirs)
            MPsi = sysm.M @ Psi
            Psi = Psi - Phi @ (Phi.T @ MPsi)          # M-orthogonal to the modes
            Psi = Psi - Phi @ (Phi.T @ (sysm.M @ Psi))  # second pass (Gram-Schmidt re-orthogonalisation)
            G = Psi.T @ (sysm.M @ Psi)
            G = 0.5 * (G + G.T)
            g, V = np.linalg.eigh(G)
            gmax = float(g.max()) if g.size else 0.0
            keep = g > GRAM_RTOL * gmax if gmax > 0 else np.zeros_like(g, dtype=bool)
            Psi = Psi @ (V[:, keep] / np.sqrt(g[keep]))
            s_kept = int(keep.sum())
            # reduced eigenproblem in the static block (M-orthonormal there, M-orthogonal to Phi)
            Kss = Psi.T @ (sysm.K @ Psi)
            Kss = 0.5 * (Kss + Kss.T)
            mu, Q = np.linalg.eigh(Kss)
            Psi = Psi @ Q
            Tf = np.hstack([Phi, Psi])
            w2 = np.concatenate([lam, mu])
        else:
            Tf = Phi
            w2 = lam
        t3 = time.perf_counter()
        if np.any(w2 < -1e-8 * max(float(np.max(np.abs(w2))), 1.0)):
            raise SolverError("negative Ritz eigenvalue: the stiffness is not positive definite")
        w2 = np.maximum(w2, 0.0)
        kinds = ["mode"] * n_modes + ["static"] * s_kept
        r = Tf.shape[1]
        K = np.diag(w2)
        M = np.eye(r)
        ops: dict[Any, np.ndarray] = {}
        for where, _ in specs:
            ops[_key(where)] = np.asarray(sysm.attachment(where) @ Tf)
        # coefficients of the raw static shapes K^-1 A^T d in the basis (they lie in its span):
        # what :meth:`truncate` needs to rebuild the static block for fewer modes
        coeffs = Tf.T @ (sysm.M @ Psi_raw) if Psi_raw is not None else np.zeros((Tf.shape[1], 0))
        T = sysm.embed(Tf) if keep_basis else None
        meta = dict(static_response=static_response, dofs=int(sysm.n), ndofs_total=int(sysm.ndofs_total), n_extra=int(sysm.n_extra),
                    n_static_requested=len(loads), n_static_kept=s_kept,
                    mesh_key=getattr(getattr(model, "bundle", None), "key", ""),
                    timings=dict(system_s=t1 - t0, modes_s=t2 - t1, static_s=t3 - t2, total_s=t3 - t0),
                    eigen_backend=res.backend)
        out = cls(K, M, np.sqrt(w2), kinds, n_modes, T=T, operators=ops,
                  attachments=[(w if isinstance(w, str) else list(map(float, np.ravel(w))), dirs) for w, dirs in specs],
                  model=model, system=sysm, meta=meta)
        out.static_coeffs = coeffs
        return out

    # ---- basic properties -----------------------------------------------------------------
    @property
    def r(self) -> int:
        return int(self.K.shape[0])

    @property
    def frequencies_hz(self) -> np.ndarray:
        """Ritz frequencies of the bare model [Hz] (first ``n_modes`` = the FEM modes)."""
        return self.omega / (2 * np.pi)

    def operator(self, where: Where) -> np.ndarray:
        """(3, r) reduced attachment operator: the displacement at ``where`` of the basis columns
        (named point: P2 interpolation; face name: area average; coordinates; "lumped_tip")."""
        k = _key(where)
        if k in self._ops:
            return self._ops[k]
        if self._sys is None:
            if self.model is None:
                raise GeometryError(
                    f"attachment {where!r} is not stored in this Ritz basis (stored: "
                    f"{', '.join(map(str, self._ops)) or 'none'}); coordinates and other names need the FEM model")
            self._sys = _System(self.model)
        if self.T is None:
            raise GeometryError(f"attachment {where!r} needs the full basis T, which was not kept")
        sysm = self._sys
        Tf = self.T[sysm.free] if not sysm.n_extra else np.vstack([self.T[sysm.free], self.T[sysm.ndofs_total:]])
        op = np.asarray(sysm.attachment(where) @ Tf)
        self._ops[k] = op
        return op

    def truncate(self, n_modes: int, static: bool = True) -> "RitzBasis":
        """The basis :meth:`from_model` would give with ``n_modes`` (<= this basis's) and the
        same attachments, without a new FEM solve: the first ``n_modes`` modes plus (``static``)
        the static shapes ``K^-1 A^T d``, which lie in this basis's span (their coefficients are
        kept in ``static_coeffs``), M-orthogonalised to the kept modes and M-orthonormalised.
        ``static=False``: the modes only."""
        if not 1 <= int(n_modes) <= self.n_modes:
            raise ParameterError(f"truncate: n_modes must lie in 1..{self.n_modes}, got {n_modes}")
        if not np.allclose(self.M, np.eye(self.r), atol=1e-10) or np.count_nonzero(self.K - np.diag(np.diag(self.K))):
            raise ParameterError("truncate needs the bare basis (no with_stiffness)")
        k = int(n_modes)
        E = np.eye(self.r)[:, :k]
        Q = E
        kinds = ["mode"] * k
        C = self.static_coeffs if static else np.zeros((self.r, 0))
        if C.shape[1]:
            P = C - E @ (E.T @ C)
            P = P - E @ (E.T @ P)
            G = 0.5 * (P.T @ P + (P.T @ P).T)
            g, V = np.linalg.eigh(G)
            keep = g > GRAM_RTOL * g.max() if g.size and g.max() > 0 else np.zeros(g.shape, dtype=bool)
            P = P @ (V[:, keep] / np.sqrt(g[keep]))
            Kss = P.T @ self.K @ P
            mu, W = np.linalg.eigh(0.5 * (Kss + Kss.T))
            Q = np.hstack([E, P @ W])
            kinds += ["static"] * int(keep.sum())
        Kn = Q.T @ self.K @ Q
        Kn = 0.5 * (Kn + Kn.T)
        out = RitzBasis(Kn, np.eye(Q.shape[1]), np.sqrt(np.maximum(np.diag(Kn), 0.0)), kinds, k,
                        T=None if self.T is None else self.T @ Q,
                        operators={w: op @ Q for w, op in self._ops.items()},
                        attachments=self.attachments if static else [], model=self.model, system=self._sys,
                        meta=dict(self.meta, n_static_kept=len(kinds) - k))
        out.static_coeffs = Q.T @ C if static else np.zeros((Q.shape[1], 0))
        return out

    def leading(self, n_modes: int) -> "RitzBasis":
        """The first ``n_modes`` FEM modes only (``truncate(n_modes, static=False)``)."""
        return self.truncate(n_modes, static=False)

    def expand(self, a: np.ndarray) -> np.ndarray:
        """Full FEM field(s) ``T a`` for reduced coordinates ``a`` (r,) or (r, k)."""
        if self.T is None:
            raise GeometryError("this Ritz basis was stored without its full basis T: cannot expand")
        a = np.asarray(a, dtype=float)
        if a.shape[0] != self.r:
            raise ParameterError(f"expand: expected {self.r} reduced coordinates, got {a.shape[0]}")
        return self.T @ a

    def project(self, A_full: sp.spmatrix | np.ndarray) -> np.ndarray:
        """``T^T A T`` (r, r) of a full FEM matrix (ndofs_total square; rows/columns of clamped
        DOFs are ignored since T vanishes there)."""
        if self.T is None:
            raise GeometryError("projection needs the full basis T")
        n = self.T.shape[0]
        A = sp.csr_matrix(A_full)
        if A.shape[0] != A.shape[1] or A.shape[0] not in (n, n - int(self.meta.get("n_extra", 0))):
            raise ParameterError(f"matrix of shape {A.shape} does not match the model's {n} DOFs")
        T = self.T[: A.shape[0]]
        P = T.T @ (A @ T)
        return 0.5 * (P + P.T)

    def with_stiffness(self, K_extra_full: sp.spmatrix | np.ndarray, scale: float = 1.0) -> "RitzBasis":
        """A new basis whose reduced stiffness is ``K + scale T^T K_extra T`` (same vectors).

        For prestress (``K_extra`` = geometric stiffness per unit load), a root spring, ...
        The reduced frequencies of the result come from :meth:`solve`."""
        if not np.isfinite(scale):
            raise ParameterError(f"scale must be finite, got {scale}")
        Kx = self.project(K_extra_full)
        out = RitzBasis(self.K + scale * Kx, self.M.copy(), self.omega, self.kinds, self.n_modes, T=self.T,
                        operators=self._ops, attachments=[], model=self.model, system=self._sys, meta=self.meta)
        out.attachments = list(self.attachments)
        return out

    # ---- modified systems -----------------------------------------------------------------
    def matrices(self, point_masses: Iterable[Any] = (), springs: Iterable[Any] = ()) -> tuple[np.ndarray, np.ndarray]:
        """Reduced (K, M) with point masses ``(where, m)`` / :class:`PointMass` and springs
        ``(where_a, where_b_or_None, k, direction_or_None)`` / :class:`Spring` added."""
        K = self.K.copy()
        M = self.M.copy()
        for pm in point_masses:
            where, m = (pm.point, pm.mass) if isinstance(pm, PointMass) else pm
            PointMass(where, float(m))  # validates
            B = self.operator(where)
            M += float(m) * (B.T @ B)
        for s in springs:
            s = s if isinstance(s, Spring) else Spring(*s)
            B = self.operator(s.point_a)
            if s.point_b is not None:
                B = B - self.operator(s.point_b)
            if s.direction is None:
                K += s.stiffness * (B.T @ B)
            else:
                d = np.asarray(s.direction, dtype=float)
                b = (d / np.linalg.norm(d)) @ B
                K += s.stiffness * np.outer(b, b)
        return 0.5 * (K + K.T), 0.5 * (M + M.T)

    def solve(self, point_masses: Iterable[Any] = (), springs: Iterable[Any] = (), n: int | None = None) -> RitzSolution:
        """Frequencies and reduced shapes with additions (low-rank updates, no FEM re-solve)."""
        K, M = self.matrices(point_masses, springs)
        try:
            w2, V = sla.eigh(K, M)
        except np.linalg.LinAlgError as exc:
            raise SolverError(f"reduced eigenproblem failed: {exc}") from None
        scale = max(float(np.max(np.abs(w2))), 1.0)
        if np.any(w2 < -1e-9 * scale):
            raise SolverError("reduced stiffness is not positive semi-definite (negative spring or prestress "
                              "beyond buckling?)")
        k = self.r if n is None else int(n)
        if not 1 <= k <= self.r:
            raise ParameterError(f"n must lie in 1..{self.r}, got {n}")
        return RitzSolution(np.sqrt(np.maximum(w2[:k], 0.0)), V[:, :k], self, K, M)

    def static_compliance(self, where: Where, point_masses: Iterable[Any] = (), springs: Iterable[Any] = ()) -> np.ndarray:
        """(3, 3) static compliance [m/N] at ``where`` of the reduced model (with additions)."""
        K, _ = self.matrices(point_masses, springs)
        B = self.operator(where)
        return B @ np.linalg.solve(K, B.T)

    def residual_check(self, point_masses: Iterable[Any] = (), springs: Iterable[Any] = (), n: int = 4,
                       solver: str = "auto") -> dict[str, Any]:
        """Ritz vs a full FEM re-solve with the same additions (matrix-level: the additions are
        assembled into the full K, M as :meth:`ElasticModel.assemble` does).  Returns the
        frequencies of both and the relative differences of the lowest ``n`` modes."""
        if self.model is None:
            raise GeometryError("residual_check needs the FEM model")
        pms = [p if isinstance(p, PointMass) else PointMass(*p) for p in point_masses]
        sps = [s if isinstance(s, Spring) else Spring(*s) for s in springs]
        sysm = self._sys or _System(self.model)
        K, M = sysm.K.copy(), sysm.M.copy()
        for p in pms:
            A = sysm.attachment(p.point)
            M = M + p.mass * (A.T @ A)
        for s in sps:
            A = sysm.attachment(s.point_a)
            if s.point_b is not None:
                A = A - sysm.attachment(s.point_b)
            if s.direction is None:
                K = K + s.stiffness * (A.T @ A)
            else:
                d = np.asarray(s.direction, dtype=float)
                a = sp.csr_matrix((d / np.linalg.norm(d)) @ A)
                K = K + s.stiffness * (a.T @ a)
        t0 = time.perf_counter()
        res = shift_invert_eigsh(K.tocsr(), M.tocsr(), n, sigma=0.0 if getattr(self.model, "clamp", None) else None,
                                 solver=solver)
        fem_s = time.perf_counter() - t0
        t0 = time.perf_counter()
        sol = self.solve(pms, sps, n=n)
        ritz_s = time.perf_counter() - t0
        f_fem = np.sqrt(res.eigenvalues) / (2 * np.pi)
        f_ritz = sol.frequencies_hz
        return dict(fem_hz=f_fem, ritz_hz=f_ritz, rel_diff=(f_ritz - f_fem) / f_fem, fem_s=fem_s, ritz_s=ritz_s)

    # ---- persistence ----------------------------------------------------------------------
    def to_arrays(self, include_basis: bool = True, extra_attachments: Iterable[Where] = ()) -> dict[str, np.ndarray]:
        """Arrays for an ``.npz`` file: K, M, omega, kinds, the stored attachment operators (plus
        ``extra_attachments``, evaluated now) and, optionally, the full basis T."""
        for w in extra_attachments:
            self.operator(w)
        arr: dict[str, np.ndarray] = {"K": self.K, "M": self.M, "omega": self.omega,
                                      "kinds": np.array(self.kinds), "n_modes": np.array(self.n_modes)}
        names = []
        for i, (k, op) in enumerate(self._ops.items()):
            arr[f"op{i}"] = op
            names.append(k if isinstance(k, str) else list(k))
        arr["op_names"] = np.array(json.dumps(names))
        arr["attachments"] = np.array(json.dumps(self.attachments))
        arr["static_coeffs"] = self.static_coeffs
        if include_basis and self.T is not None:
            arr["T"] = self.T
        return arr

    @classmethod
    def from_arrays(cls, arr: Mapping[str, np.ndarray], model: Any = None, meta: Mapping[str, Any] | None = None) -> "RitzBasis":
        try:
            names = json.loads(str(arr["op_names"]))
            ops = {(n if isinstance(n, str) else tuple(n)): np.asarray(arr[f"op{i}"]) for i, n in enumerate(names)}
            b = cls(arr["K"], arr["M"], arr["omega"], [str(k) for k in arr["kinds"]], int(arr["n_modes"]),
                    T=np.asarray(arr["T"]) if "T" in arr else None, operators=ops, model=model, meta=meta)
            b.attachments = json.loads(str(arr["attachments"]))
            if "static_coeffs" in arr:
                b.static_coeffs = np.asarray(arr["static_coeffs"])
        except (KeyError, ValueError, TypeError) as exc:
            raise DataFormatError(f"not a probedyn Ritz basis ({exc})") from None
        return b

    def describe(self) -> dict[str, Any]:
        return dict(r=self.r, n_modes=self.n_modes, n_static=self.kinds.count("static"),
                    frequencies_hz=self.frequencies_hz, attachments=self.attachments, **self.meta)


def direct_compliance(model: Any, where: Where, direction: Sequence[float], frequencies_hz: Sequence[float],
                      solver: str = "auto") -> np.ndarray:
    """The FEM's own undamped frequency response at an attachment: ``d . A u`` with
    ``(K - omega^2 M) u = A^T d`` solved directly (sparse symmetric indefinite factorisation per
    frequency) [m/N].  The reference for modal truncation checks of reduced models."""
    sysm = _System(model)
    A = sysm.attachment(where)
    d = np.asarray(direction, dtype=float)
    d = d / np.linalg.norm(d)
    f = np.asarray(A.T @ d).ravel()
    out = []
    for fz in np.atleast_1d(np.asarray(frequencies_hz, dtype=float)):
        w2 = (2 * np.pi * fz) ** 2
        fac = factorize((sysm.K - w2 * sysm.M).tocsr(), spd=(w2 == 0.0), solver=solver)
        try:
            u = np.asarray(fac.solve(f)).ravel()
        finally:
            fac.release()
        out.append(float(d @ (A @ u)))
    return np.array(out)


def direct_compliances(model: Any, where: Where, directions: Sequence[Sequence[float]],
                       frequencies_hz: Sequence[float], solver: str = "auto") -> np.ndarray:
    """:func:`direct_compliance` for several directions at once, shape (directions,
    frequencies): the matrix ``K - omega^2 M`` does not depend on the direction, so it is
    assembled once and factorised once per frequency, and the directions are right-hand sides
    of one solve (the same factorisation and the same numbers as one call per direction, at a
    third of the factorisations for the three axes)."""
    sysm = _System(model)
    A = sysm.attachment(where)
    D = np.atleast_2d(np.asarray(directions, dtype=float))
    D = D / np.linalg.norm(D, axis=1)[:, None]
    F = np.asarray(A.T @ D.T)  # (n, k)
    out = []
    for fz in np.atleast_1d(np.asarray(frequencies_hz, dtype=float)):
        w2 = (2 * np.pi * fz) ** 2
        fac = factorize((sysm.K - w2 * sysm.M).tocsr(), spd=(w2 == 0.0), solver=solver)
        try:
            U = np.asarray(fac.solve(F)).reshape(F.shape)
        finally:
            fac.release()
        AU = np.asarray(A @ U)  # (3, k)
        out.append([float(D[j] @ AU[:, j]) for j in range(D.shape[0])])
    return np.array(out).T


__all__ = ["RitzBasis", "RitzSolution", "LUMPED_TIP", "direct_compliance", "direct_compliances"]
