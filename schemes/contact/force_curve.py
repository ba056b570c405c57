"""Force curves of a cantilever of normal stiffness ``k`` over a contact model: jump-to-contact
and jump-out (quasi-static, displacement-controlled base).

The base of the cantilever is at ``s`` (an approach coordinate in the units of the penetration:
``s`` grows towards the sample), the tip at penetration ``delta`` (``delta < 0``: a gap, see
:mod:`probedyn.schemes.contact.base`).  The spring pulls the tip towards the sample with
``k (s - delta)``, the sample pushes back with the contact load ``P`` (positive repulsive), so the
equilibria are the curve

    s(delta) = delta + P(delta) / k,

followed along the whole equilibrium path of the contact model (the non-contact tail up to the
end point ``D0``, then the contact curve parametrised by the contact radius, its unstable part
included).  An equilibrium is stable where ``ds/ddelta = 1 + P'/k > 0``.  On approach the tip
follows the path while ``s`` grows; at a maximum of ``s`` (``P' = -k``: the attraction's gradient
beats the spring) it **jumps into contact**, to the next point of the path with the same ``s``.
On retraction it follows the path back while ``s`` falls; at a minimum it **jumps out**.

For the van der Waals sphere–flat tail ``P = -H R / (6 d^2)`` (eq 2.23, ``d`` the gap) the fold is at

    d* = (H R / (3 k))^(1/3),     base at   s* - s_touch = ...,

(``|dP/dd| = H R / (3 d^3) = k``): the jump-to-contact distance predicted from the normal
stiffness alone.  If ``d*`` is below the tail's end gap the approach reaches the contact
without a jump in the tail (a stiff cantilever).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from probedyn.core.errors import ParameterError


def tail_jump_gap(H: float, R: float, k: float) -> float:
    """``(H R / (3 k))^(1/3)`` [m]: gap at which a spring ``k`` [N/m] becomes unstable in the
    sphere–flat van der Waals field of Hamaker constant ``H`` [J] and radius ``R`` [m]."""
    if not (k > 0 and math.isfinite(k)):
        raise ParameterError(f"normal stiffness must be positive, got {k!r} N/m")
    return (H * R / (3.0 * k)) ** (1.0 / 3.0)


def equilibrium_path(model: Any, gap_max: float | None = None, n_tail: int = 4000,
                     delta_max: float | None = None) -> dict[str, np.ndarray]:
    """The model's equilibrium path (dimensional): penetration ``delta`` [m], load ``P`` [N]
    and contact radius ``a`` [m], from a gap ``gap_max`` (default 30 zeta_0) through the tail
    and along the contact curve up to ``delta_max`` (default 30 zeta_0 of penetration)."""
    s = model.scales
    if s.W == 0:
        raise ParameterError("force curves need adhesion (W > 0): without it there is no jump")
    D0, P0 = model.nd_endpoint()
    z0 = s.z0
    gap_max = 30.0 * z0 if gap_max is None else float(gap_max)
    delta_max = 30.0 * z0 if delta_max is None else float(delta_max)
    if model.has_noncontact_branch:
        Dn, Pn = model.nd_noncontact_path(n_tail)
        # a law with its own non-contact branch (Maugis-Dugdale): free (P = 0) out to the gap max, then the branch
        # in the Dugdale zone's radius, its unstable part included, to the end point
        Df = np.linspace(min(Dn[0], -gap_max / s.d_unit), Dn[0], n_tail)[:-1]
        Dt, Pt = np.concatenate([Df, Dn]), np.concatenate([np.zeros_like(Df), Pn])
    else:  # the tail: gaps log-spaced so that the fold is resolved whatever k is
        Dt = np.sort(D0 - np.geomspace(gap_max / s.d_unit, 1e-6 * z0 / s.d_unit, n_tail))
        Pt, _ = model.nd_tail(Dt)
    cur = model.nd_curves(D_range=(D0 - 1.0, delta_max / s.d_unit), n=10)
    A, Dc, Pc = cur["A"], cur["D"], cur["P"]
    order = np.argsort(A)
    A, Dc, Pc = A[order], Dc[order], Pc[order]
    delta = np.concatenate([Dt, Dc]) * s.d_unit
    P = np.concatenate([Pt, Pc]) * s.P_unit
    a = np.concatenate([np.zeros_like(Dt), A * s.a_unit])
    return dict(delta=delta, P=P, a=a, n_tail=np.array(Dt.size))


def force_curve(model: Any, k: float, **path_kw: Any) -> dict[str, Any]:
    """Approach and retraction of a cantilever of normal stiffness ``k`` [N/m] (module doc).

    Returns the path (``delta``, ``P``, base ``s``), the jump-in (``s``, gap before, penetration
    after, loads before/after; ``None`` if the approach is continuous), the jump-out likewise,
    and the tail prediction ``d*``."""
    if not (k > 0 and math.isfinite(k)):
        raise ParameterError(f"normal stiffness must be positive, got {k!r} N/m")
    if "gap_max" not in path_kw:  # the jump-out lands ~ |pull-off| / k away: keep it on the path
        path_kw["gap_max"] = max(30.0 * model.scales.z0, 3.0 * abs(model.pull_off_force()) / k)
    p = equilibrium_path(model, **path_kw)
    d, P = p["delta"], p["P"]
    s = d + P / k
    ds = np.diff(s)
    sc = model.scales
    D0, P0 = model.nd_endpoint()
    # the tail's gap (eq 2.23) is d = d0 + (D0 - D) in Maugis units, d0 = z0_bar sqrt(2 / -P0); on Maugis-Dugdale's
    # own non-contact branch the gap is the undeformed one, -delta
    d0 = sc.z0_bar * math.sqrt(2.0 / -P0) if P0 < 0 else 0.0
    predicted, rule = tail_jump_gap(sc.H, sc.R, k), "(H R/3k)^(1/3)"
    if model.has_noncontact_branch:
        from .maugis_dugdale import dugdale_range

        # the free state ends where the gap reaches the Dugdale range h0 = 2 / (pi lam) Maugis units, and the branch
        # turns back there (dD/dC = -C_* < 0): the approach jumps at h0 whatever k is
        d0, predicted, rule = -D0, dugdale_range(model.lam) * sc.d_unit, "h0 = W/sigma_0 (Dugdale range)"
    gap_at = lambda delta: (d0 + D0) * sc.d_unit - delta  # noqa: E731
    out: dict[str, Any] = dict(k=k, delta=d, P=P, s=s, jump_in=None, jump_out=None,
                               predicted_tail_jump_gap=predicted, predicted_jump_rule=rule,
                               jumps_at_range=model.has_noncontact_branch,
                               tail_end_penetration=D0 * sc.d_unit, tail_end_gap=d0 * sc.d_unit)
    # approach: first local maximum of s along the path
    down = np.nonzero(ds < 0)[0]
    if down.size:
        i = int(down[0])
        s_in = s[i]
        later = np.nonzero((s[i + 1:] >= s_in) & (np.r_[ds[i:], 1.0][1:] > 0))[0]
        if later.size:
            j = i + 1 + int(later[0])
            f = (s_in - s[j - 1]) / (s[j] - s[j - 1]) if s[j] != s[j - 1] else 1.0
            d_after = d[j - 1] + f * (d[j] - d[j - 1])
            P_after = P[j - 1] + f * (P[j] - P[j - 1])
            out["jump_in"] = dict(s=float(s_in), delta_before=float(d[i]), P_before=float(P[i]),
                                  gap_before=float(gap_at(d[i])), delta_after=float(d_after),
                                  P_after=float(P_after), in_tail=bool(i < int(p["n_tail"])))
    # retraction: from the far end back, the first local minimum of s
    up_back = np.nonzero(ds > 0)[0]
    rising_end = up_back[-1] if up_back.size else None
    if rising_end is not None:
        # walk back while s decreases (ds > 0 seen backwards); the turn is where ds <= 0 first
        k_idx = len(ds) - 1
        while k_idx >= 0 and ds[k_idx] > 0:
            k_idx -= 1
        if k_idx >= 0:
            i = k_idx + 1  # s has a local minimum here
            s_out = s[i]
            earlier = np.nonzero(s[:i] <= s_out)[0]
            if earlier.size:
                j = int(earlier[-1])
                f = (s_out - s[j]) / (s[j + 1] - s[j]) if s[j + 1] != s[j] else 0.0
                out["jump_out"] = dict(s=float(s_out), delta_before=float(d[i]), P_before=float(P[i]),
                                       delta_after=float(d[j] + f * (d[j + 1] - d[j])),
                                       P_after=float(P[j] + f * (P[j + 1] - P[j])))
    return out


__all__ = ["tail_jump_gap", "equilibrium_path", "force_curve"]
