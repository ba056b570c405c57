"""Checks of the blind_spectra2 physics: `python checks.py OUT_DIR` -> OUT_DIR/checks.txt."""
import os, sys, time
import numpy as np
from scipy.integrate import quad
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import physics as ph
from gen import MESH, E0, NU0, RHO0

out = []
def say(s):
    print(s, flush=True); out.append(s)

L, w, t = 300e-6, 30e-6, 3e-6
lv = ph.Lever(L, w, t, E=E0, nu=NU0, rho=RHO0, **MESH)
f = lv.solve_modes(10); lv.classify()
I = w * t ** 3 / 12; A = w * t
fam = {}
for i, (fm, o) in enumerate(zip(lv.family, lv.order)):
    fam[(fm, o)] = f[i]
say('plain lever %g x %g x %g um, mesh %s, %d DOF' % (L * 1e6, w * 1e6, t * 1e6, MESH, lv.ndof))
for n, lam in enumerate([1.8751040687, 4.6940911330, 7.8547574382], 1):
    feb = lam ** 2 / (2 * np.pi) * np.sqrt(E0 * I / (RHO0 * A * L ** 4))
    say('flapwise %d: FEM %.1f Hz, Euler-Bernoulli %.1f Hz, FEM/EB - 1 = %+.4f' % (n, fam[('flapwise', n)], feb, fam[('flapwise', n)] / feb - 1))
G = E0 / (2 * (1 + NU0))
r = t / w
J = w * t ** 3 / 3 * (1 - 192 / np.pi ** 5 * r * sum(np.tanh((2 * k + 1) * np.pi / (2 * r)) / (2 * k + 1) ** 5 for k in range(20)))
Ip = RHO0 * (w * t ** 3 + w ** 3 * t) / 12
ft = 1 / (4 * L) * np.sqrt(G * J / Ip)
say('torsion 1: FEM %.1f Hz, Saint-Venant %.1f Hz, FEM/SV - 1 = %+.4f' % (fam[('torsion', 1)], ft, fam[('torsion', 1)] / ft - 1))
lam_w = np.sqrt(E0 * (w ** 3 * t ** 3 / 144) / (G * J))
say('  expected: flapwise a few per mille ABOVE EB (w/t = 10: partial plate stiffening towards E/(1-nu^2) = +%.1f %%'
    ' at most, less a (t/L)^2 shear/rotary-inertia term); torsion ABOVE Saint-Venant by the clamp\'s warping'
    ' restraint: Vlasov decay length sqrt(E Gamma_w/(G J)) = %.2f um (Gamma_w = w^3 t^3/144), a root'
    ' boundary layer that shortens the lever by ~ that: + %.1f %%' % (100 * ((1 - NU0 ** 2) ** -0.5 - 1), lam_w * 1e6, 100 * lam_w / L))
# mesh convergence: 1.5x finer in every direction
m2 = dict(nx=int(MESH['nx'] * 1.5), ny=int(MESH['ny'] * 1.5), nz=3, grade=MESH['grade'])
lv2 = ph.Lever(L, w, t, E=E0, nu=NU0, rho=RHO0, **m2)
f2 = lv2.solve_modes(10); lv2.classify()
say('mesh convergence vs 1.5x finer mesh %s (%d DOF):' % (m2, lv2.ndof))
for i in range(10):
    say('  %-9s %d  %12.1f  %12.1f  rel %+.2e' % (lv.family[i], lv.order[i], f[i], f2[i], f[i] / f2[i] - 1))
# Sader Gamma
for Re in [1.0, 10.0, 1e4]:
    g = ph.gamma_rect(Re); gc = ph.gamma_circ(Re)
    # independent Gamma_circ from K_nu(z) = int_0^inf exp(-z cosh u) cosh(nu u) du (Re z > 0)
    z = -1j * np.sqrt(1j * Re)
    def K(nu):
        fr = lambda u: (np.exp(-z * np.cosh(u)) * np.cosh(nu * u)).real
        fi = lambda u: (np.exp(-z * np.cosh(u)) * np.cosh(nu * u)).imag
        return quad(fr, 0, 30, limit=400)[0] + 1j * quad(fi, 0, 30, limit=400)[0]
    gq = 1 + 4j * K(1) / (np.sqrt(1j * Re) * K(0))
    say('Re=%g: Gamma_circ %.5f%+.5fi (integral repr. %.5f%+.5fi), Omega %.5f%+.5fi, Gamma_rect %.4f%+.4fi; '
        'large-Re asymptote of Gamma_circ 1+2sqrt2(1+i)/sqrt(Re) = %.4f%+.4fi' % (
            Re, gc.real, gc.imag, gq.real, gq.imag, ph.sader_omega(Re).real, ph.sader_omega(Re).imag,
            g.real, g.imag, 1 + 2 * np.sqrt(2) / np.sqrt(Re), 2 * np.sqrt(2) / np.sqrt(Re)))
# equipartition: area under a mode's PSD = c^2 kT / omega^2 (vacuum SHO and Sader-loaded)
T = 295.0; fn, Q, c = 50e3, 300.0, 1.7
fa = np.linspace(1, 20 * fn, 4_000_001)
S = ph.mode_psd(fa, fn, Q, c, T)
say('equipartition (vacuum SHO, Q=300): area / (c^2 kT/omega^2) = %.5f' % (np.trapezoid(S, fa) / (c ** 2 * ph.KB * T / (2 * np.pi * fn) ** 2)))
lv.Iw, lv.It_ang, lv.Iv = lv.Iw, lv.It_ang, lv.Iv
mu = ph.modal_fluid_mu(lv, fa, 1.2, 1.82e-5)[0]
S = ph.mode_psd(fa, f[0], 1e4, 1.0, T, mu)
say('equipartition (flap 1 in air, Sader-loaded, Re(mu) = %.4f at the line): area / (kT/omega_vac^2) = %.4f '
    '(expected 1: the FDT area is kT times the static compliance chi(0) = 1/omega_vac^2, the fluid\'s added mass'
    ' only moves the line)' % (mu[np.argmin(abs(fa - f[0]))].real, np.trapezoid(S, fa) / (ph.KB * T / (2 * np.pi * f[0]) ** 2)))
od = sys.argv[1] if len(sys.argv) > 1 else '.'
open(os.path.join(od, 'checks.txt'), 'w').write('\n'.join(out) + '\n')
