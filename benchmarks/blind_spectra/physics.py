"""Own physics for the blind thermal-spectrum generator (written blind, session 46, from the docs only).

Solid model: 3D linear elasticity of a rectangular lever, triquadratic 27-node Lagrange hexahedra on a
graded tensor-product mesh, assembled exactly as Kronecker products of 1D P2 matrices (own code, numpy/scipy;
no scikit-fem needed), general anisotropic 6x6 stiffness (Voigt), consistent mass.
Options, each a physical change of the *true* lever:
  * clamp: rigid (Dirichlet on the x=0 face) or an elastic foundation on that face (Robin springs per unit
    area: k_n on the normal (axial) displacement, k_t on both tangential displacements);
  * point mass at any point (consistent: m * N(x0)^T N(x0) for each displacement component);
  * uniform axial prestress sigma_xx: geometric stiffness sigma * sum_i du_i/dx dv_i/dx;
  * material: isotropic (E, nu) or cubic silicon rotated so that the lever axis is <110> ((001) wafer).
Fluid: Sader (1998) hydrodynamic function of a rectangular beam applied mode by mode to the width-averaged
flapwise displacement; residual gas in the free-molecular regime (Christian 1966 / Bao 2002 type momentum
transfer: normal rho_g*vbar per face, tangential rho_g*vbar/4 per face) on every mode.
Thermal PSD: fluctuation-dissipation for each mode (mass-normalised modal coordinate), summed incoherently.
"""
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.special import kve

KB = 1.380649e-23
R_GAS = 8.314462618

# ---------------------------------------------------------------- materials
def c_isotropic(E, nu):
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    mu = E / (2 * (1 + nu))
    C = np.zeros((6, 6))
    C[:3, :3] = lam
    C[0, 0] = C[1, 1] = C[2, 2] = lam + 2 * mu
    C[3, 3] = C[4, 4] = C[5, 5] = mu
    return C


_VOIGT = [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)]


def _to_tensor(C):
    T = np.zeros((3, 3, 3, 3))
    for I, (i, j) in enumerate(_VOIGT):
        for J, (k, l) in enumerate(_VOIGT):
            for a, b in ((i, j), (j, i)):
                for c, d in ((k, l), (l, k)):
                    T[a, b, c, d] = C[I, J]
    return T


def _to_voigt(T):
    C = np.zeros((6, 6))
    for I, (i, j) in enumerate(_VOIGT):
        for J, (k, l) in enumerate(_VOIGT):
            C[I, J] = T[i, j, k, l]
    return C


def c_silicon_110(C11=165.7e9, C12=63.9e9, C44=79.6e9):
    """Cubic Si (Hopcroft et al. 2010 constants) in the lever frame: x along [110], y along [-110], z [001]."""
    C = np.zeros((6, 6))
    C[:3, :3] = C12
    for i in range(3):
        C[i, i] = C11
        C[i + 3, i + 3] = C44
    T = _to_tensor(C)
    c, s = np.cos(np.pi / 4), np.sin(np.pi / 4)
    Q = np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])  # rows: lever axes in crystal coordinates
    Tr = np.einsum('ai,bj,ck,dl,ijkl->abcd', Q, Q, Q, Q, T)
    return _to_voigt(Tr)


def engineering_constants(C):
    S = np.linalg.inv(C)
    return dict(Ex=1 / S[0, 0], Ey=1 / S[1, 1], Ez=1 / S[2, 2], Gyz=1 / S[3, 3], Gxz=1 / S[4, 4],
                Gxy=1 / S[5, 5], nu_xy=-S[0, 1] / S[0, 0], nu_xz=-S[0, 2] / S[0, 0])


# ---------------------------------------------------------------- media
def air(T, p=101325.0):
    M = 0.0289647
    rho = p * M / (R_GAS * T)
    eta = 1.716e-5 * (T / 273.15) ** 1.5 * (273.15 + 110.4) / (T + 110.4)  # Sutherland
    return rho, eta


def argon(T, p=101325.0):
    M = 0.039948
    rho = p * M / (R_GAS * T)
    eta = 2.125e-5 * (T / 273.15) ** 1.5 * (273.15 + 144.4) / (T + 144.4)  # Sutherland, Ar
    return rho, eta


def water(T):
    t = T - 273.15
    rho = 999.974950 * (1 - (t - 3.983035) ** 2 * (t + 301.797) / (522528.9 * (t + 69.34881)))  # Tanaka 2001
    eta = 2.414e-5 * 10 ** (247.8 / (T - 140.0))  # Vogel
    return rho, eta


# ---------------------------------------------------------------- Sader 1998
def gamma_circ(Re):
    s = np.sqrt(1j * Re)
    return 1 + 4j * kve(1, -1j * s) / (s * kve(0, -1j * s))


def omega_rect(Re):
    t = np.log10(Re)
    Or = (0.91324 - 0.48274 * t + 0.46842 * t**2 - 0.12886 * t**3 + 0.044055 * t**4
          - 0.0035117 * t**5 + 0.00069085 * t**6) / (
        1 - 0.56964 * t + 0.48690 * t**2 - 0.13444 * t**3 + 0.045155 * t**4
        - 0.0035862 * t**5 + 0.00069085 * t**6)
    Oi = (-0.024134 - 0.029256 * t + 0.016294 * t**2 - 0.00010961 * t**3 + 0.000064577 * t**4
          - 0.000044510 * t**5) / (
        1 - 0.59702 * t + 0.55182 * t**2 - 0.18357 * t**3 + 0.079156 * t**4
        - 0.014369 * t**5 + 0.0028361 * t**6)
    return Or + 1j * Oi


def gamma_rect(omega, b, rho, eta):
    Re = rho * omega * b**2 / (4 * eta)
    return omega_rect(Re) * gamma_circ(Re)


# ---------------------------------------------------------------- FEM lever
# Tensor-product mesh of 27-node triquadratic Lagrange hexahedra. Because the mesh is a tensor product
# of 1D P2 meshes (graded towards the clamp and the side edges), every global matrix is an exact sum of
# Kronecker products of 1D matrices: int d_p N_a d_q N_b dV = (x) over the three directions of
# D2 (d=p=q), D10 (d=p!=q), D01 (d=q!=p) or D0 (mass) -- no element loop is needed.
_G, _GW = np.polynomial.legendre.leggauss(4)


def _p2_shape(s):
    """1D P2 Lagrange shapes and derivatives on the reference element [0,1] (nodes 0, 1/2, 1)."""
    N = np.array([2 * (s - 0.5) * (s - 1), -4 * s * (s - 1), 2 * s * (s - 0.5)])
    dN = np.array([4 * s - 3, -8 * s + 4, 4 * s - 1])
    return N, dN


def _mats1d(nodes_el):
    """Global 1D matrices D0, D10, D01, D2 for element edges nodes_el (P2: 2n+1 nodes)."""
    ne = len(nodes_el) - 1
    n = 2 * ne + 1
    D = {k: np.zeros((n, n)) for k in ('0', '10', '01', '2')}
    s = (_G + 1) / 2
    N, dN = _p2_shape(s)
    for e in range(ne):
        h = nodes_el[e + 1] - nodes_el[e]
        wq = _GW / 2 * h
        d = dN / h
        idx = slice(2 * e, 2 * e + 3)
        D['0'][idx, idx] += (N * wq) @ N.T
        D['10'][idx, idx] += (d * wq) @ N.T      # [a,b] = int N'_a N_b
        D['01'][idx, idx] += (N * wq) @ d.T      # [a,b] = int N_a N'_b
        D['2'][idx, idx] += (d * wq) @ d.T
    coords = np.empty(n)
    coords[0::2] = nodes_el
    coords[1::2] = 0.5 * (nodes_el[:-1] + nodes_el[1:])
    return {k: sp.csr_matrix(v) for k, v in D.items()}, coords


def _eval1d(nodes_el, x, deriv=False):
    """Row vector(s) of the global 1D P2 shape functions at points x."""
    ne = len(nodes_el) - 1
    x = np.atleast_1d(x)
    out = np.zeros((len(x), 2 * ne + 1))
    for i, xx in enumerate(x):
        e = min(max(np.searchsorted(nodes_el, xx, side='right') - 1, 0), ne - 1)
        h = nodes_el[e + 1] - nodes_el[e]
        N, dN = _p2_shape(np.array([(xx - nodes_el[e]) / h]))
        out[i, 2 * e:2 * e + 3] = (dN[:, 0] / h) if deriv else N[:, 0]
    return out


def graded(a, b, hmin, hmax, ratio=1.3, both=False):
    """Element edges from a to b, size hmin at a (and at b if both) growing by ratio up to hmax."""
    if both:
        half = graded(a, 0.5 * (a + b), hmin, hmax, ratio)
        return np.concatenate([half, (a + b - half[::-1])[1:]])
    sizes, h, tot = [], hmin, 0.0
    while tot < (b - a) - 1e-15:
        sizes.append(h)
        tot += h
        h = min(h * ratio, hmax)
    sizes = np.array(sizes) * (b - a) / tot
    return a + np.concatenate([[0], np.cumsum(sizes)])


class Lever:
    """Rectangular lever x in [0,L] (clamp at x=0), y in [-w/2,w/2], z in [-t/2,t/2]."""

    def __init__(self, L, w, t, C, rho, refine=1.0, clamp=None, point_mass=None, sigma=0.0, rxyz=(1.0, 1.0, 1.0)):
        self.L, self.w, self.t, self.C, self.rho = L, w, t, C, rho
        rx, ry, rz = (refine * q for q in rxyz)
        hmax_x = min(max(2.0 * t, L / 50), L / 16) / rx
        self.ex = graded(0.0, L, min(t / 3, hmax_x) / rx, hmax_x, 1.25)
        self.ey = graded(-w / 2, w / 2, min(t / 2, w / 8) / ry, w / 6 / ry, 1.5, both=True)
        nz = max(1, int(round(2 * rz)))
        self.ez = np.linspace(-t / 2, t / 2, nz + 1)
        Dx, self.xc = _mats1d(self.ex)
        Dy, self.yc = _mats1d(self.ey)
        Dz, self.zc = _mats1d(self.ez)
        self.n1 = (len(self.xc), len(self.yc), len(self.zc))
        Nn = int(np.prod(self.n1))
        self.Nn = Nn
        Dd = (Dx, Dy, Dz)

        def A(p, q):
            mats = []
            for d in range(3):
                if d == p and d == q:
                    mats.append(Dd[d]['2'])
                elif d == p:
                    mats.append(Dd[d]['10'])
                elif d == q:
                    mats.append(Dd[d]['01'])
                else:
                    mats.append(Dd[d]['0'])
            return sp.kron(mats[0], sp.kron(mats[1], mats[2], 'csr'), 'csr')

        Ct = _to_tensor(C)
        cache = {}
        blocks = [[None] * 3 for _ in range(3)]
        for i in range(3):          # test component (v_i)
            for j in range(3):      # trial component (u_j)
                B = None
                for p in range(3):
                    for q in range(3):
                        c = Ct[i, p, j, q]   # sigma_ip = C_ipjq du_j/dx_q ; v_i,p
                        if c == 0.0:
                            continue
                        if (p, q) not in cache:
                            cache[(p, q)] = A(p, q)
                        term = c * cache[(p, q)]      # [a,b]: int d_p N_a d_q N_b
                        B = term if B is None else B + term
                blocks[i][j] = B if B is not None else sp.csr_matrix((Nn, Nn))
        K = sp.bmat(blocks, format='csr')
        M0 = sp.kron(Dx['0'], sp.kron(Dy['0'], Dz['0'], 'csr'), 'csr')
        M = sp.block_diag([rho * M0] * 3, format='csr')
        if sigma != 0.0:
            Kg = sp.kron(Dx['2'], sp.kron(Dy['0'], Dz['0'], 'csr'), 'csr')
            K = K + sp.block_diag([sigma * Kg] * 3, format='csr')
        if point_mass is not None:
            mp, xp = point_mass
            row = self.shape_row(xp)
            Pm = sp.csr_matrix(row.T @ row)
            M = M + sp.block_diag([mp * Pm] * 3, format='csr')
        self.dx = Dx
        self.Dy, self.Dz = Dy, Dz
        e0 = np.zeros(self.n1[0]); e0[0] = 1
        if clamp is None:
            ix = np.arange(Nn).reshape(self.n1)[0].ravel()
            self.D = np.concatenate([ix, ix + Nn, ix + 2 * Nn])
        else:
            kn, kt = clamp
            F = sp.kron(sp.csr_matrix(np.outer(e0, e0)), sp.kron(Dy['0'], Dz['0'], 'csr'), 'csr')
            K = K + sp.block_diag([kn * F, kt * F, kt * F], format='csr')
            self.D = np.array([], dtype=int)
        self.K, self.M = K.tocsr(), M.tocsr()

    def shape_row(self, xp):
        rx = _eval1d(self.ex, xp[0])
        ry = _eval1d(self.ey, xp[1])
        rz = _eval1d(self.ez, xp[2])
        return np.kron(rx, np.kron(ry, rz))

    def solve(self, fmax, kmin=8):
        N = self.K.shape[0]
        keep = np.setdiff1d(np.arange(N), self.D)
        Kc = self.K[keep][:, keep].tocsc()
        Mc = self.M[keep][:, keep].tocsc()
        k = kmin
        lu = None
        while True:
            if lu is None:
                lu = spla.splu(Kc, permc_spec='MMD_AT_PLUS_A')
                OPinv = spla.LinearOperator(Kc.shape, matvec=lu.solve, dtype=float)
            lam, V = spla.eigsh(Kc, k=k, M=Mc, sigma=0.0, which='LM', OPinv=OPinv)
            o = np.argsort(lam)
            lam, V = lam[o], V[:, o]
            f = np.sqrt(np.abs(lam)) / (2 * np.pi)
            if f[-1] > fmax or k >= 60:
                break
            k += 8
        Vf = np.zeros((N, len(lam)))
        Vf[keep] = V
        sel = f <= fmax
        return f[sel], Vf[:, sel]

    def disp(self, V, pts):
        """Displacements (3, npts, nmodes) at points pts (3, npts)."""
        pts = np.asarray(pts, float)
        R = np.vstack([self.shape_row(pts[:, k]) for k in range(pts.shape[1])])
        Nn = self.Nn
        return np.stack([R @ V[c * Nn:(c + 1) * Nn] for c in range(3)])

    def classify(self, V):
        L, w = self.L, self.w
        U = self.disp(V, np.array([[L, L, L], [0, w / 2, -w / 2], [0, 0, 0]]))
        fam = []
        for n in range(V.shape[1]):
            ux0, uy0, uz0 = U[0, 0, n], U[1, 0, n], U[2, 0, n]
            uz1, uz2 = U[2, 1, n], U[2, 2, n]
            a = {'flap': abs(uz1 + uz2) / 2,
                 'torsion': abs(uz1 - uz2) / 2,
                 'lateral': abs(uy0), 'axial': abs(ux0)}
            fam.append(max(a, key=a.get))
        return fam

    def width_avg_w(self, V):
        """Mid-plane width-averaged u_z(x) of each mode at Gauss points in every x element."""
        Nn = self.Nn
        ny = len(self.yc)
        rz = _eval1d(self.ez, 0.0)                    # (1, nzn)
        ry = np.ones((1, ny)) @ self.Dy['0'].toarray() / self.w    # width average of the y shapes
        s = (_G + 1) / 2
        xq, wq = [], []
        for e in range(len(self.ex) - 1):
            h = self.ex[e + 1] - self.ex[e]
            xq.append(self.ex[e] + s * h)
            wq.append(_GW / 2 * h)
        xq, wq = np.concatenate(xq), np.concatenate(wq)
        rx = _eval1d(self.ex, xq)
        R = sp.csr_matrix(np.kron(rx, np.kron(ry, rz)))
        W = R @ V[2 * Nn:3 * Nn]
        return xq, wq, W

    def gas_damping_matrix(self, alpha_n, alpha_t):
        """Free-molecular surface damping (per face: alpha_n on the normal, alpha_t on the tangential
        velocity) on the top, bottom, two side and end faces (not the clamp face)."""
        Dx, Dy, Dz = self.dx, self.Dy, self.Dz
        nx, ny, nz = self.n1

        def ee(n, i):
            e = np.zeros(n); e[i] = 1
            return sp.csr_matrix(np.outer(e, e))
        Fz = sp.kron(Dx['0'], sp.kron(Dy['0'], ee(nz, 0) + ee(nz, nz - 1), 'csr'), 'csr')
        Fy = sp.kron(Dx['0'], sp.kron(ee(ny, 0) + ee(ny, ny - 1), Dz['0'], 'csr'), 'csr')
        Fx = sp.kron(ee(nx, nx - 1), sp.kron(Dy['0'], Dz['0'], 'csr'), 'csr')
        cx = alpha_n * Fx + alpha_t * (Fy + Fz)
        cy = alpha_n * Fy + alpha_t * (Fx + Fz)
        cz = alpha_n * Fz + alpha_t * (Fx + Fy)
        return sp.block_diag([cx, cy, cz], format='csr')


def euler_bernoulli_flap(L, w, t, E, rho, n=4):
    bl = np.array([1.8751040687, 4.6940911330, 7.8547574382, 10.9955407349, 14.1371683910])[:n]
    I = w * t**3 / 12
    return bl**2 / (2 * np.pi * L**2) * np.sqrt(E * I / (rho * w * t))
