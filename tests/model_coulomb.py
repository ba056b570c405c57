"""A friction model written the way a user adds one: this file and nothing else.

Coulomb friction regularised by ``tanh`` (no internal state, no static excess)::

    F = F_0 tanh(v / v_0)

so in steady sliding at v >> v_0 the friction force is the level ``F_0``. Registered in the
friction registry on import; tests/test_new_models.py runs it through ``probedyn simulate ffm``.
"""

import math

from numba import njit

from probedyn.core.params import Param, ParamSet
from probedyn.core.presets import preset
from probedyn.schemes.friction.base import FRICTION_MODELS, FrictionModel


@njit(cache=True)
def coulomb_kernel(p, x, v, z):
    """(F, z', dF/dx, dF/dv, dF/dz, dz'/dx, dz'/dv, dz'/dz); p = (F_0, v_0)."""
    F0, v0 = p[0], p[1]
    t = math.tanh(v / v0)
    return (F0 * t, 0.0, 0.0, F0 * (1.0 - t * t) / v0, 0.0, 0.0, 0.0, 0.0)


@FRICTION_MODELS.register
class Coulomb(FrictionModel):
    key = "coulomb"
    title = "Coulomb friction regularised by tanh (an example model, tests only)"
    source = "textbook Coulomb law; F = F_0 tanh(v / v_0)"
    n_state = 0
    params = ParamSet([
        Param("F_0", preset("table-2.1")["F_c_x"], "N", "friction level", positive=True, hi=1e-3),
        Param("v_0", 1e-9, "m/s", "regularisation speed", positive=True, hi=1.0),
    ])
    packed = ("F_0", "v_0")
    load_params = ("F_0",)
    kernel = staticmethod(coulomb_kernel)

    def scales(self):
        return self.values["F_0"], 1.0
