"""A lever bonded to its chip over an overlap: the bonded segment as a beam on a two-parameter bond.

Many levers do not end at a rigid wall. A glued lever, a macroscopic beam pressed in a holder, or a
lever continued into a chip whose surface layer is compliant, rests over a length ``L_o`` behind the
chip edge on a thin bond (glue, an oxide, a contact) with a **normal stiffness per unit area**
``k_n`` and a **tangential (shear) stiffness per unit area** ``k_t``. The free lever starts at the
chip edge; the bonded segment bends, twists and slides on the bond.

Model (Euler-Bernoulli segment, Winkler bond on one face; Hetenyi, *Beams on Elastic Foundation*, 1946,
for the normal part): the segment ``-L_o <= x <= 0`` (chip edge at 0) has the lever's section
(width b, thickness t), axial ``u``, lateral ``v``, flapwise ``w`` and twist ``phi``. The bond acts on the
bonded face ``z = -t/2``, where the displacement is ``u + (t/2) w' - y v'`` along the axis,
``v + (t/2) phi`` across the width and ``w + y phi`` normal to it; integrated over the width,
per unit length:

    k_t b (u + t w'/2)^2 + k_t (b^3/12) v'^2 + k_t b (v + t phi/2)^2 + k_n b w^2 + k_n (b^3/12) phi^2

(halved in the energy). So the *same* bond holds flapwise bending by its normal stiffness and lateral
bending by its shear stiffness: for a thin glue layer ``k_n = M/h``, ``k_t = G/h`` (M the layer's
constrained modulus, ``M/G = 2(1 - nu)/(1 - 2 nu)``, 3.5 at nu = 0.3, 11 at 0.45), so a bonded lever's
lateral modes drop several times more than its flapwise ones -- the signature a support at the clamp
face (``clamp-compliance``: ``k_n t^3/12`` flapwise, ``k_n t w^3/12`` lateral) cannot give. Limits: a
rigid bond is the rigid clamp at the chip edge; a semi-infinite segment on the normal bond gives
Hetenyi's root compliances ``w_0 = 2 beta P / (k b) - 2 beta^2 M / (k b)``, ``theta_0 = ...`` with
``beta = (k b / 4 E I)^(1/4)`` (checked in the tests).

Discretisation: ``n_el`` elements, cubic Hermite for ``v`` and ``w``, linear for ``u`` and ``phi``,
consistent mass with rotary inertia; six DOFs per node in the order of the FEM's rigid motions about the
clamp-face centroid, ``(u_x, u_y, u_z, theta_x, theta_y, theta_z)`` in the beam's local frame (x along the
lever into the body, y across the width, z through the thickness): ``theta_x = phi``,
``theta_y = -w'``, ``theta_z = v'``. Node 0 is the chip edge; the diagnosis ties it to the clamp
face's rigid motion (:mod:`probedyn.diagnose.modal_model`).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from probedyn.lumped.beam import torsion_constant_rect

__all__ = ["segment_matrices", "segment_nodes", "hetenyi_root_compliance", "bond_stiffness", "N_ELEMENTS"]

#: elements of the bonded segment, graded geometrically from the chip edge (:func:`segment_nodes`)
N_ELEMENTS = 16

_G4 = np.polynomial.legendre.leggauss(4)


def _rows(xi: np.ndarray, h: np.ndarray) -> dict[str, np.ndarray]:
    """Row vectors (n_el, n_xi, 12) of the elements' fields at ``xi`` in [0, 1] (each element from its node a at
    xi = 0 to node b at xi = 1, local x increasing from a to b; ``h`` the elements' lengths)."""
    x = np.asarray(xi, float)[None, :]
    h = np.asarray(h, float)[:, None]
    one = np.ones_like(x * h)
    N = [one * (1.0 - x), one * x]
    dN = [-one / h, one / h]
    H = [one * (1 - 3 * x**2 + 2 * x**3), h * (x - 2 * x**2 + x**3), one * (3 * x**2 - 2 * x**3), h * (-x**2 + x**3)]
    dH = [(-6 * x + 6 * x**2) / h, one * (1 - 4 * x + 3 * x**2), (6 * x - 6 * x**2) / h, one * (-2 * x + 3 * x**2)]
    ddH = [(-6 + 12 * x) / h**2, (-4 + 6 * x) / h, (6 - 12 * x) / h**2, (-2 + 6 * x) / h]
    r = {k: np.zeros(one.shape + (12,)) for k in ("u", "du", "v", "dv", "ddv", "w", "dw", "ddw", "p", "dp")}
    for n, off in enumerate((0, 6)):
        r["u"][..., off + 0], r["du"][..., off + 0] = N[n], dN[n]
        r["p"][..., off + 3], r["dp"][..., off + 3] = N[n], dN[n]
        for f, d, sgn, slot in (("v", "", 1.0, 5), ("w", "", -1.0, 4)):
            i0 = off + (1 if f == "v" else 2)
            # v with v' = theta_z; w with w' = -theta_y
            for key, F in ((f, H), ("d" + f, dH), ("dd" + f, ddH)):
                r[key][..., i0] = F[2 * n]
                r[key][..., off + slot] = sgn * F[2 * n + 1]
    return r


def segment_nodes(L_o: float, h0: float, n_el: int = N_ELEMENTS) -> np.ndarray:
    """Element lengths (n_el,) from the chip edge: the first ``min(h0, L_o / n_el)``, growing geometrically
    to fill ``L_o`` (a stiff bond bends the segment within ``1/beta`` of the edge, a soft one all along)."""
    h0 = min(h0, L_o / n_el)
    if h0 >= L_o / n_el * (1 - 1e-12):
        return np.full(n_el, L_o / n_el)
    # ratio r with h0 (r^n - 1) / (r - 1) = L_o
    lo_r, hi_r = 1.0 + 1e-12, 10.0
    for _ in range(200):
        r = 0.5 * (lo_r + hi_r)
        if h0 * (r**n_el - 1.0) / (r - 1.0) > L_o:
            hi_r = r
        else:
            lo_r = r
    h = h0 * r ** np.arange(n_el)
    return h * (L_o / h.sum())


def segment_matrices(E: float, nu: float, rho: float, b: float, t: float, L_o: float, k_n: float, k_t: float,
                     n_el: int = N_ELEMENTS, h0: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and mass matrices ``(6 (n_el + 1))^2`` of the bonded segment (module docstring), node 0 at
    the chip edge (x = 0), node ``n_el`` at the segment's end (x = -L_o), DOFs
    ``(u, v, w, theta_x, theta_y, theta_z)`` per node; elements graded from ``h0`` at the chip edge (default:
    a quarter of the stiffer bond's ``1/beta``; :func:`segment_nodes`). SI units: E [Pa], rho [kg/m^3],
    lengths [m], k_n, k_t [N/m^3]."""
    if not (L_o > 0 and b > 0 and t > 0 and E > 0 and rho > 0 and k_n >= 0 and k_t >= 0):
        raise ValueError("segment_matrices: positive geometry and material, non-negative bond stiffnesses")
    G = E / (2.0 * (1.0 + nu))
    A, Iy, Iz = b * t, b * t**3 / 12.0, t * b**3 / 12.0
    J = torsion_constant_rect(b, t)
    if h0 is None:
        beta = (3.0 * max(k_n, k_t) / (E * t**3)) ** 0.25  # k b / (4 E I_y)
        h0 = 0.25 / beta if beta > 0 else L_o
    n = 6 * (n_el + 1)
    # element e runs from node e+1 (x = -(e+1) h, xi = 0) to node e (x = -e h, xi = 1): x increases a -> b
    Ke, Me = _elements(segment_nodes(float(L_o), float(h0), int(n_el)), E, G, rho, A, Iy, Iz, J, b, t, k_n, k_t)
    flat = _scatter(int(n_el))
    K = np.bincount(flat, Ke.ravel(), n * n).reshape(n, n)
    M = np.bincount(flat, Me.ravel(), n * n).reshape(n, n)
    return 0.5 * (K + K.T), 0.5 * (M + M.T)


@lru_cache(maxsize=8)
def _scatter(n_el: int) -> np.ndarray:
    """Flat indices into the ``(6 (n_el + 1))^2`` matrix of every entry of the elements' (n_el, 12, 12) matrices:
    element e's local node a (its first six DOFs) is the global node e+1, its node b the global node e."""
    n = 6 * (n_el + 1)
    loc = np.r_[6:12, 0:6]  # local DOF i -> offset from 6 e
    g = 6 * np.arange(n_el)[:, None] + loc[None, :]  # (n_el, 12) global DOFs
    return (g[:, :, None] * n + g[:, None, :]).ravel()


def _reference_terms() -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Each energy term's element matrix at h = 1 (4-point Gauss, exact for the cubic fields' products) and the
    DOFs that carry a length (the Hermite slopes): an element of length h has the term ``h^(1 - p - q)
    S_h T S_h`` for fields of derivative orders p and q, ``S_h`` the slopes scaled by h."""
    gx, gw = _G4
    r = {k: v[0] for k, v in _rows(0.5 * (gx + 1.0), np.ones(1)).items()}  # (n_g, 12)
    w = 0.5 * gw
    T = lambda a, b: np.einsum("g,gi,gj->ij", w, a, b)  # noqa: E731
    terms = {"du": T(r["du"], r["du"]), "ddw": T(r["ddw"], r["ddw"]), "ddv": T(r["ddv"], r["ddv"]),
             "dp": T(r["dp"], r["dp"]), "u": T(r["u"], r["u"]), "u_dw": T(r["u"], r["dw"]) + T(r["dw"], r["u"]),
             "dw": T(r["dw"], r["dw"]), "dv": T(r["dv"], r["dv"]), "v": T(r["v"], r["v"]),
             "v_p": T(r["v"], r["p"]) + T(r["p"], r["v"]), "p": T(r["p"], r["p"]), "w": T(r["w"], r["w"])}
    slope = np.zeros(12, bool)
    slope[[4, 5, 10, 11]] = True
    return terms, slope


_TERMS, _SLOPE = _reference_terms()
#: each term's power of h (1 minus the derivative orders of its two fields)
_POWER = {"du": -1, "ddw": -3, "ddv": -3, "dp": -1, "u": 1, "u_dw": 0, "dw": -1, "dv": -1, "v": 1, "v_p": 1, "p": 1,
          "w": 1}


def _elements(h, E, G, rho, A, Iy, Iz, J, b, t, k_n, k_t):
    """The elements' stiffness and mass (n_el, 12, 12) from the reference terms (:func:`_reference_terms`)."""
    h = np.asarray(h, float)
    kt, kn = k_t * b, k_n * b
    stiff = {"du": E * A, "ddw": E * Iy, "ddv": E * Iz, "dp": G * J,
             # bond: the axial slip (u + t w'/2)^2, the slip across the width (v + t phi/2)^2, normal w, phi
             "u": kt, "u_dw": kt * t / 2, "dw": kt * t * t / 4, "dv": k_t * b**3 / 12.0,
             "v": kt, "v_p": kt * t / 2, "p": kt * t * t / 4 + k_n * b**3 / 12.0, "w": kn}
    mass = {"u": rho * A, "v": rho * A, "w": rho * A, "p": rho * (Iy + Iz), "dw": rho * Iy, "dv": rho * Iz}
    sc = np.where(_SLOPE[None, :], h[:, None], 1.0)
    S = sc[:, :, None] * sc[:, None, :]
    out = []
    for coef in (stiff, mass):
        keys = list(coef)
        c = np.array([coef[k] for k in keys])[None, :] * h[:, None] ** np.array([_POWER[k] for k in keys])[None, :]
        out.append(S * np.einsum("ek,kij->eij", c, np.array([_TERMS[k] for k in keys])))
    return out[0], out[1]


def hetenyi_root_compliance(E: float, b: float, t: float, k_n: float) -> np.ndarray:
    """Root compliance ``[[w/P, w/M], [theta/P, theta/M]]`` of a semi-infinite Euler-Bernoulli beam on a
    Winkler foundation ``k_n b`` per length, loaded at its end by a transverse force P and a moment M
    (Hetenyi 1946; ``beta = (k_n b / 4 E I)^(1/4)``): ``w = (2 beta / k)(P - beta M)``,
    ``theta = (2 beta^2 / k)(-P + 2 beta M)`` with ``k = k_n b``, signs for the load applied at the
    end with the beam extending to positive x. The independent check of :func:`segment_matrices`."""
    k = k_n * b
    beta = (k / (4.0 * E * b * t**3 / 12.0)) ** 0.25
    return (2.0 * beta / k) * np.array([[1.0, -beta], [-beta, 2.0 * beta**2]])



def bond_stiffness(lam: float, E: float, t: float, L: float) -> float:
    """Bond stiffness per unit area [N/m^3] of the dimensionless bond length ``lam = 1 / (beta L)``: the
    Winkler length ``1/beta`` of the lever's flapwise section on the bond, ``beta^4 = k b / (4 E I_y) =
    3 k / (E t^3)``, over the free length L. Hetenyi's root rotation compliance is ``1 / (E I beta) =
    lam L / (E I)``: to first order a bond of ``lam`` lowers the modes as a clamp ``lam L`` further back."""
    return E * t**3 / (3.0 * (lam * L) ** 4)
