"""Independent truth physics for the blind thermal-spectrum set (blind_spectra2).

Written blind: nothing of probedyn (nor of its earlier blind generators) is read or imported.
Everything here is built from published physics:

* the lever: a 3D linear-elastic FEM (scikit-fem, triquadratic 27-node hexahedra, ElementHex2) of a
  rectangular silicon beam, x along the length (clamp at x = 0), y across the width, z through the
  thickness (laser on the top face z = t);
* elastic tensor: isotropic (E, nu) or cubic silicon (Hopcroft et al. 2010: C11 165.7, C12 63.9,
  C44 79.6 GPa) rotated so the lever runs along <110> of a (001) wafer, blended
  C = C_iso + a (C_cubic - C_iso);
* hidden effects in the mesh or the matrices: point mass on a top-surface node, compliant clamp (normal
  and tangential springs per unit area on the clamp face x = 0 instead of a fixed face), re-meshed true
  geometry, scaled modulus, uniform axial prestress (geometric stiffness sigma int du_i/dx dv_i/dx);
* fluid: Sader (1998) hydrodynamic function Gamma_rect = Omega(Re) Gamma_circ(Re) on the flapwise
  (cross-section mean) deflection, a torsional surrogate on the twist (see gamma_torsion), Stokes layers
  plus edge pressure on the lateral motion, all per mode (no intermodal coupling);
* thermal noise: fluctuation-dissipation per mode, S_q(f) = (2 kB T / (pi f)) Im chi(omega), seen by an
  optical lever (slope at the spot, calibrated by the static end-load slope-to-deflection ratio).
"""
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla
from scipy.special import kv
from skfem import (MeshHex, ElementHex2, ElementVector, Basis, FacetBasis, BilinearForm, LinearForm,
                   asm, condense)

KB = 1.380649e-23

# ------------------------------------------------------------------ elastic tensors
def c_iso(E, nu):
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    mu = E / (2 * (1 + nu))
    d = np.eye(3)
    return (lam * np.einsum('ij,kl->ijkl', d, d)
            + mu * (np.einsum('ik,jl->ijkl', d, d) + np.einsum('il,jk->ijkl', d, d)))


def c_cubic_110(C11=165.7e9, C12=63.9e9, C44=79.6e9):
    """Cubic silicon in lever axes: x = [110], y = [-110], z = [001]."""
    C = np.zeros((3, 3, 3, 3))
    d = np.eye(3)
    for i in range(3):
        for j in range(3):
            for k in range(3):
                for l in range(3):
                    v = C12 * d[i, j] * d[k, l] + C44 * (d[i, k] * d[j, l] + d[i, l] * d[j, k])
                    if i == j == k == l:
                        v = C11
                    C[i, j, k, l] = v
    s = 1 / np.sqrt(2)
    R = np.array([[s, s, 0], [-s, s, 0], [0, 0, 1.0]])   # rows: lever axes in crystal coordinates
    return np.einsum('ia,jb,kc,ld,abcd->ijkl', R, R, R, R, C)


def young_along_x(C):
    Cv = voigt(C)
    S = np.linalg.inv(Cv)
    return 1 / S[0, 0]


def voigt(C):
    idx = [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)]
    Cv = np.array([[C[idx[a][0], idx[a][1], idx[b][0], idx[b][1]] for b in range(6)] for a in range(6)])
    return Cv * np.array([1, 1, 1, 2, 2, 2.0])[None, :] ** 0  # plain Voigt stiffness (engineering shear)


# ------------------------------------------------------------------ mesh
def lever_mesh(L, w, t, nx=36, ny=6, nz=2, grade=1.2):
    """Box mesh, elements graded towards the clamp (end sizes ratio exp(grade))."""
    s = np.linspace(0, 1, nx + 1)
    x = L * np.expm1(grade * s) / np.expm1(grade)
    y = np.linspace(0, w, ny + 1)
    z = np.linspace(0, t, nz + 1)
    return MeshHex.init_tensor(x, y, z)


def fast_assembly(basis, D, rho):
    """Vectorised element assembly (same forms as skfem BilinearForms, without its per-pair loop):
    stiffness eps^T D eps (Voigt, engineering shears), consistent mass rho u.v, and the unit axial
    geometric stiffness sum_i du_i/dx dv_i/dx."""
    nloc = len(basis.basis)
    grads = np.array([basis.basis[a][0].grad for a in range(nloc)])      # (a, i, j, e, q)
    vals = np.array([basis.basis[a][0].value for a in range(nloc)])      # (a, i, e, q)
    dx = basis.dx                                                          # (e, q)
    B = np.stack([grads[:, 0, 0], grads[:, 1, 1], grads[:, 2, 2],
                  grads[:, 1, 2] + grads[:, 2, 1], grads[:, 0, 2] + grads[:, 2, 0],
                  grads[:, 0, 1] + grads[:, 1, 0]], axis=1)                # (a, 6, e, q)
    DB = np.einsum('kl,bleq->bkeq', D, B) * dx
    Ke = np.einsum('akeq,bkeq->abe', B, DB, optimize=True)
    Me = rho * np.einsum('aieq,bieq->abe', vals, vals * dx, optimize=True)
    gx = grads[:, :, 0]                                                   # (a, i, e, q)  du_i/dx
    Ge = np.einsum('aieq,bieq->abe', gx, gx * dx, optimize=True)
    ed = basis.element_dofs                                                # (a, e)
    rows = np.broadcast_to(ed[:, None, :], Ke.shape).ravel()
    cols = np.broadcast_to(ed[None, :, :], Ke.shape).ravel()
    N = basis.N
    mk = lambda Ae: sp.coo_matrix((Ae.ravel(), (rows, cols)), shape=(N, N)).tocsr()
    return mk(Ke), mk(Me), mk(Ge)


def skfem_reference_assembly(basis, C, rho):
    """Plain skfem BilinearForm assembly (slow), used once in checks.py to verify fast_assembly."""
    @BilinearForm
    def stiff(u, v, _):
        eu = 0.5 * (u.grad + np.swapaxes(u.grad, 0, 1))
        ev = 0.5 * (v.grad + np.swapaxes(v.grad, 0, 1))
        return np.einsum('ij...,ij...->...', np.einsum('ijkl,kl...->ij...', C, eu), ev)

    @BilinearForm
    def mass(u, v, _):
        return rho * (u[0] * v[0] + u[1] * v[1] + u[2] * v[2])
    return asm(stiff, basis), asm(mass, basis)


# ------------------------------------------------------------------ hydrodynamics
_OMR_N = [0.91324, -0.48274, 0.46842, -0.12886, 0.044055, -0.0035117, 0.00069085]
_OMR_D = [1.0, -0.56964, 0.48690, -0.13444, 0.045155, -0.0035862, 0.00069085]
_OMI_N = [-0.024134, -0.029256, 0.016294, -0.00010961, 0.000064577, -0.000044510]
_OMI_D = [1.0, -0.59702, 0.55182, -0.18357, 0.079156, -0.014369, 0.0028361]


def _poly(c, x):
    return sum(ci * x ** i for i, ci in enumerate(c))


def sader_omega(Re):
    tau = np.log10(Re)
    return _poly(_OMR_N, tau) / _poly(_OMR_D, tau) + 1j * _poly(_OMI_N, tau) / _poly(_OMI_D, tau)


def gamma_circ(Re):
    """Stokes's oscillating circular cylinder (Sader 1998 eq. 19), e^{-i w t} convention."""
    Re = np.asarray(Re, float)
    s = np.sqrt(1j * Re)
    z = -1j * s
    return 1 + 4j * kv(1, z) / (s * kv(0, z))


def gamma_rect(Re):
    return sader_omega(Re) * gamma_circ(Re)


def gamma_torsion(Re):
    """Torsional hydrodynamic function SURROGATE (Green & Sader's own fit not reproduced here).

    Inviscid limit 1 (added moment of inertia pi rho b^4 / 128 per length, the flat plate's); the viscous
    excess taken as the flexural one's, Gamma_tor = 1 + (Gamma_rect - 1).  Documented approximation."""
    return 1 + (gamma_rect(Re) - 1)


# ------------------------------------------------------------------ the lever model
class Lever:
    """One true lever.  Parameters (SI):
    L, w, t; C (3x3x3x3 tensor) or E, nu; rho;
    clamp: None (fixed face) or (k_n, k_t) springs per unit area [N/m^3] on the face x = 0;
    sigma0: uniform axial prestress [Pa]; point_mass: (mass, xi) on the top-surface centre line."""

    def __init__(self, L, w, t, E=169e9, nu=0.28, rho=2330.0, C=None, clamp=None, sigma0=0.0,
                 point_mass=None, nx=36, ny=6, nz=2, grade=1.2):
        self.L, self.w, self.t, self.rho = L, w, t, rho
        self.C = c_iso(E, nu) if C is None else C
        self.mesh = lever_mesh(L, w, t, nx, ny, nz, grade)
        self.basis = Basis(self.mesh, ElementVector(ElementHex2()), intorder=4)
        Cten = self.C

        K, M, G = fast_assembly(self.basis, voigt(Cten), rho)
        if sigma0:
            K = K + sigma0 * G
        self.point_node = None
        if point_mass is not None:
            mp, xi = point_mass
            p = self.mesh.p
            top = np.nonzero(np.isclose(p[2], t) & np.isclose(p[1], w / 2))[0]
            n = top[np.argmin(np.abs(p[0, top] - xi * L))]
            self.point_node = n
            self.point_xi = p[0, n] / L
            M = M.tolil()
            for d in self.basis.nodal_dofs[:, n]:
                M[d, d] += mp
            M = M.tocsr()
        clamp_facets = self.mesh.facets_satisfying(lambda x: np.isclose(x[0], 0.0))
        if clamp is None:
            self.fixed = self.basis.get_dofs(clamp_facets).all()
        else:
            kn, kt = clamp
            fb = FacetBasis(self.mesh, ElementVector(ElementHex2()), facets=clamp_facets, intorder=4)

            @BilinearForm
            def spring(u, v, _):
                return kn * u[0] * v[0] + kt * (u[1] * v[1] + u[2] * v[2])
            K = K + asm(spring, fb)
            self.fixed = np.array([], dtype=int)
        self.K, self.M = K.tocsr(), M.tocsr()
        self.free = np.setdiff1d(np.arange(self.basis.N), self.fixed)

    @property
    def ndof(self):
        return len(self.free)

    def solve_modes(self, k=12):
        Kf = self.K[self.free][:, self.free].tocsc()
        Mf = self.M[self.free][:, self.free].tocsc()
        shift = -1.0 * (2 * np.pi * 1e3) ** 2
        lu = sla.splu((Kf - shift * Mf).tocsc())
        op = sla.LinearOperator(Kf.shape, matvec=lu.solve, dtype=float)
        lam, V = sla.eigsh(Kf, k=k, M=Mf, sigma=shift, OPinv=op, which='LM')
        o = np.argsort(lam)
        lam, V = lam[o], V[:, o]
        full = np.zeros((self.basis.N, k))
        full[self.free] = V
        self.lam = lam
        self.freq = np.sqrt(np.abs(lam)) / (2 * np.pi)
        self.modes = full
        self._lu = lu
        return self.freq

    def static_end_load(self):
        """Unit end load along z, spread uniformly over the free end face x = L."""
        fac = self.mesh.facets_satisfying(lambda x: np.isclose(x[0], self.L))
        fb = FacetBasis(self.mesh, ElementVector(ElementHex2()), facets=fac, intorder=4)
        area = self.w * self.t

        @LinearForm
        def load(v, _):
            return v[2] / area
        f = asm(load, fb)
        u = np.zeros(self.basis.N)
        Kf = self.K[self.free][:, self.free].tocsc()
        u[self.free] = sla.spsolve(Kf, f[self.free])
        return u

    # ---------------------------------------------------------- sampling of fields
    def probe_matrix(self, pts):
        return self.basis.probes(np.asarray(pts, float))

    def slope_at(self, U, x0, y0, h=None):
        """d u_z / dx and d u_z / dy on the top face at (x0, y0) (central differences of the FEM field)."""
        h = h or 0.2 * self.t
        pts = np.array([[x0 - h, x0 + h, x0, x0], [y0, y0, y0 - h, y0 + h], [self.t] * 4])
        P = self.probe_matrix(pts)
        uz = (P @ U)[8:12] if U.ndim == 1 else (P @ U)[8:12]
        return (uz[1] - uz[0]) / (2 * h), (uz[3] - uz[2]) / (2 * h)

    def section_fields(self, nxs=161, nys=9):
        """Cross-section means along x at mid-thickness for every mode: wbar (flap), theta (twist),
        vbar (lateral), ubar (axial); returns xs and dict of arrays (nxs, nmodes)."""
        xs = np.linspace(0, self.L, nxs)
        ys = np.linspace(0, self.w, nys)
        X, Y = np.meshgrid(xs, ys, indexing='ij')
        pts = np.array([X.ravel(), Y.ravel(), np.full(X.size, self.t / 2)])
        P = self.probe_matrix(pts)
        npt = X.size
        F = P @ self.modes
        ux = F[:npt].reshape(nxs, nys, -1)
        uy = F[npt:2 * npt].reshape(nxs, nys, -1)
        uz = F[2 * npt:].reshape(nxs, nys, -1)
        yc = ys - self.w / 2
        theta = np.einsum('j,ijm->im', yc, uz) / np.sum(yc ** 2)
        return xs, dict(w=uz.mean(1), theta=theta, v=uy.mean(1), u=ux.mean(1))

    def classify(self):
        xs, f = self.section_fields()
        self.xs, self.sec = xs, f
        Iw = np.trapezoid(f['w'] ** 2, xs, axis=0)
        It = np.trapezoid(f['theta'] ** 2, xs, axis=0) * self.w ** 2 / 12
        Iv = np.trapezoid(f['v'] ** 2, xs, axis=0)
        Iu = np.trapezoid(f['u'] ** 2, xs, axis=0)
        E = np.vstack([Iw, Iv, It, Iu])
        names = np.array(['flapwise', 'lateral', 'torsion', 'axial'])
        fam = names[np.argmax(E, 0)]
        purity = E.max(0) / E.sum(0)
        order, cnt = [], {}
        for fm in fam:
            cnt[fm] = cnt.get(fm, 0) + 1
            order.append(cnt[fm])
        self.family, self.order, self.purity = list(fam), order, purity
        self.Iw, self.It_ang, self.Iv = Iw, np.trapezoid(f['theta'] ** 2, xs, axis=0), Iv
        return self.family, self.order


# ------------------------------------------------------------------ spectra
def modal_fluid_mu(lever, f, rho_f, eta_f):
    """mu_n(f) (nmodes, nf): the fluid's modal mass ratio (complex) for mass-normalised modes."""
    if rho_f == 0:
        return np.zeros((len(lever.freq), len(f)), complex)
    om = 2 * np.pi * f
    b, t = lever.w, lever.t
    Re_b = rho_f * om * b ** 2 / (4 * eta_f)
    Re_t = rho_f * om * t ** 2 / (4 * eta_f)
    g_flap = np.pi / 4 * rho_f * b ** 2 * gamma_rect(Re_b)
    g_tor = np.pi / 128 * rho_f * b ** 4 * gamma_torsion(Re_b)
    g_lat = (2 * b * np.sqrt(rho_f * eta_f / (2 * om)) * (1 + 1j)
             + np.pi / 4 * rho_f * t ** 2 * gamma_rect(Re_t))
    return (lever.Iw[:, None] * g_flap[None] + lever.It_ang[:, None] * g_tor[None]
            + lever.Iv[:, None] * g_lat[None])


def mode_psd(f, fn, Q, c, T, mu=None):
    """One-sided signal PSD [m^2/Hz] of a mass-normalised mode seen with gain c (m per unit q)."""
    om, on = 2 * np.pi * f, 2 * np.pi * fn
    load = 1 + (0 if mu is None else mu)
    chi = 1.0 / (on ** 2 - om ** 2 * load - 1j * om * on / Q)
    return c ** 2 * 2 * KB * T / (np.pi * f) * np.abs(chi.imag)
