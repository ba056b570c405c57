"""The lever is a single crystal, not the isotropic material it was declared as.

Single-crystal silicon is cubic (C11 = 165.7, C12 = 63.9, C44 = 79.6 GPa; Hopcroft, Nix & Kenny,
JMEMS 19 (2010) 229). A lever along <110> on a (001) wafer has, in its own axes, E_x = 169 GPa -- the
value the isotropic "silicon" of the catalog takes, with nu = 0.28 -- but an in-plane shear modulus
``C66' = (C11 - C12) / 2`` = 50.9 GPa and out-of-plane ones ``C44' = C55'`` = 79.6 GPa, where the
isotropic model has ``G = E / (2 (1 + nu))`` = 66 GPa. The twist of a lever is carried by both
(``tau_xy`` through the thickness, ``tau_xz`` across the width), so its torsional frequencies are
5-12 % below the isotropic model's (0.906 for a 300 x 30 x 10 um lever, probedyn's FEM), its
bending frequencies within a few 1e-3 (the Poisson coupling of the plate).

The cause moves each region from its declared isotropic material towards the crystal it
approximates (:data:`probedyn.diagnose.modal_model.CRYSTALS`), ``C = C_iso + a (C_crystal - C_iso)``:
``a = 1`` is the crystal with Hopcroft's constants, ``a = 0`` the declared material; values between
or beyond measure how far the lever's elastic constants are from either (doping, a thin film of
another orientation). Regions of other materials (silicon nitride, PZT) are unchanged.
"""

from __future__ import annotations

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class CrystalAnisotropy(Cause):
    key = "crystal-anisotropy"
    kind = "modal"
    title = "The lever is an anisotropic crystal (silicon along <110>), not the isotropic material declared"
    source = ("C = C_iso + a (C_crystal - C_iso); Si: C11 = 165.7, C12 = 63.9, C44 = 79.6 GPa (Hopcroft et al. "
              "2010), lever axes x || [110]: G_xy = 50.9, G_xz = 79.6 GPa vs E/(2(1+nu)) = 66 GPa")
    description = ("The elastic constants of a single crystal instead of the isotropic approximation: for silicon "
                   "along <110>, torsional modes 5-12 % lower, bending modes nearly unchanged. a = 1: the crystal "
                   "with the handbook constants.")
    needs = ("torsional and lateral modes besides flapwise ones (a torsion shift alone is also a width error or "
             "a mass off the axis); a lever of silicon")
    changes = ("modulus",)
    params = (CauseParam("a_crystal", "1", -1.0, 2.0, 0.0, "fraction of the way from the isotropic model to the crystal",
                         starts=(1.0,)),)

    def effect(self, v, s):
        s.crystal += v["a_crystal"]
