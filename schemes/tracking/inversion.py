"""Open-loop voltages from a desired tip path: inverse models of the plant (sections 3.2.3, 3.3.3).

* **Quasi-static inverse**: ``u = G0^-1 r`` with ``G0 = Cq K^-1 B`` the static tip stroke per
  volt; it ignores inertia and damping, so the tip lags and rings at the plant's modes (the
  residual oscillations of section 3.4.1).
* **Dynamic inverse of the two-body model (3.37)**, exact in the time domain: with ``q1 = r``
  the tip equation gives the holder ``q2 = r + K1^-1 (D r'' + C1 r' - F)`` (F: a known tip force,
  0 for the feedforward), and the body equation the voltages
  ``Gamma u = J q2'' + C2 q2' + K2 q2 + K1 (q2 - r)``: it needs ``r''''`` (relative degree 4 per
  axis), which every smooth path provides.
* **Dynamic inverse of any linear plant** (the retained modes of a reduced probe, several per
  direction): stable inversion in the frequency domain (Devasia-type), ``U(w) = G(iw)^-1 R(w)``,
  written as ``u = G0^-1 r + Q * r'`` with ``Q(s) = (G(s)^-1 - G0^-1) / s`` applied by FFT to the
  path velocity (zero before and after a rest-to-rest path, so zero padding is exact up to
  aliasing); non-minimum-phase zeros give a non-causal (pre-actuating) inverse, which the padding
  before t = 0 holds. ``Q(0) = -G0^-1 G'(0) G0^-1`` with ``G'(0) = -Cq K^-1 C K^-1 B``.
"""

from __future__ import annotations

import math

import numpy as np

from probedyn.core.errors import ParameterError, SolverError
from probedyn.schemes.tracking.plants import AX, MechanicalPlant


def path_on_outputs(plant: MechanicalPlant, R: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """Restrict path derivatives ``R`` (k, n, 3) to the plant's output axes; a path component on
    an axis the probe cannot move raises."""
    idx = [AX[a] for a in plant.outputs]
    other = [i for i in range(3) if i not in idx]
    if other:
        big = float(np.max(np.abs(R[0]))) or 1.0
        off = float(np.max(np.abs(R[0][:, other])))
        if off > tol * big:
            names = ", ".join("xyz"[i] for i in other)
            raise ParameterError(f"the path moves along {names}, which the {plant.provenance.get('probe', 'probe')} "
                                 f"cannot actuate (its tip axes: {', '.join(plant.outputs)})")
    return R[..., idx]


def quasi_static(plant: MechanicalPlant, r: np.ndarray) -> np.ndarray:
    """``u = G0^-1 r`` (n, n_in) for tip displacements ``r`` (n, n_out)."""
    G0 = plant.static_gain()
    if G0.shape[0] != G0.shape[1]:
        return r @ np.linalg.pinv(G0).T
    return np.linalg.solve(G0, r.T).T


def two_body_inverse(plant: MechanicalPlant, R: np.ndarray, f_tip: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Exact voltages (n, n_in) and holder displacements (n, n_out) that make the tip of the
    two-body plant follow ``R`` = (r, r', r'', r''', r'''') (5, n, n_out) (module docstring)."""
    b = plant.blocks
    if not b or "Gamma" not in b:
        raise ParameterError("the exact dynamic inverse needs a two-body plant (3.37)")
    if R.shape[0] < 5:
        raise ParameterError("the dynamic inverse needs the path's derivatives up to the fourth")
    D, C1, K1, J, C2, K2, Gam = (b[k] for k in ("D", "C1", "K1", "J", "C2", "K2", "Gamma"))
    K1i = np.linalg.inv(K1)
    r, r1, r2, r3, r4 = R[:5]
    f = np.zeros_like(r) if f_tip is None else f_tip
    q2 = r + (r2 @ D.T + r1 @ C1.T - f) @ K1i.T
    q2d = r1 + (r3 @ D.T + r2 @ C1.T) @ K1i.T
    q2dd = r2 + (r4 @ D.T + r3 @ C1.T) @ K1i.T
    rhs = q2dd @ J.T + q2d @ C2.T + q2 @ K2.T + (q2 - r) @ K1.T
    u = np.linalg.solve(Gam, rhs.T).T
    return u, q2


def fft_inverse(plant: MechanicalPlant, t: np.ndarray, r: np.ndarray, rdot: np.ndarray, pad: float = 0.5) -> np.ndarray:
    """Stable-inversion voltages on the uniform grid ``t`` for any square linear plant (module
    docstring). ``r``, ``rdot``: (n, n_out) on ``t``; the path must start and end at rest
    (``rdot`` = 0 at both ends). ``pad``: zero padding on each side, as a fraction of the
    duration (holds the pre- and post-actuation of the non-causal inverse)."""
    t = np.asarray(t, dtype=float)
    dt = np.diff(t)
    if t.size < 8 or np.max(np.abs(dt - dt[0])) > 1e-9 * dt[0]:
        raise ParameterError("the frequency-domain inverse needs a uniform time grid")
    scale = float(np.max(np.abs(rdot))) or 1.0
    if np.max(np.abs(rdot[[0, -1]])) > 1e-6 * scale:
        raise ParameterError("the frequency-domain inverse needs a path that starts and ends at rest")
    h = float(dt[0])
    n = t.size
    npad = int(math.ceil(pad * n))
    N = 1 << int(math.ceil(math.log2(n + 2 * npad)))
    x = np.zeros((N, rdot.shape[1]))
    x[npad:npad + n] = rdot
    X = np.fft.rfft(x, axis=0)
    w = 2 * math.pi * np.fft.rfftfreq(N, h)
    K, C, M, B, Cq = plant.K, plant.C, plant.M, plant.B, plant.Cq
    G0 = plant.static_gain()
    G0i = np.linalg.inv(G0)
    Kinv_B = np.linalg.solve(K, B)
    dG0 = -Cq @ np.linalg.solve(K, C @ Kinv_B)
    Y = np.empty((w.size, B.shape[1]), dtype=complex)
    for i, wi in enumerate(w):
        if wi == 0:
            Q = -G0i @ dG0 @ G0i
        else:
            s = 1j * wi
            G = Cq @ np.linalg.solve(s * s * M + s * C + K, B)
            try:
                Gi = np.linalg.inv(G)
            except np.linalg.LinAlgError:
                raise SolverError(f"the plant's frequency response is singular at {wi / (2 * math.pi):.6g} Hz "
                                  "(an undamped transmission zero): add damping") from None
            Q = (Gi - G0i) / s
        Y[i] = Q @ X[i]
    ydyn = np.fft.irfft(Y, n=N, axis=0)[npad:npad + n]
    return quasi_static(plant, r) + ydyn
