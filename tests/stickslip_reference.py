"""Independent reference for the compiled stick-slip kernels (schemes/stickslip.py): one basin
cell integrated with scipy's DOP853 at tight tolerances to a fixed end time (no certificate).
Used by tests/test_stickslip.py and benchmarks/basins.py; not part of the library."""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from probedyn.core.errors import SolverError
from probedyn.schemes.stickslip import DEFAULT_MODEL, TwoMassModel, equilibria, initial_states


def basin_reference(x3_0: float, x4_0: float, u0: float, psi: float, model: TwoMassModel = DEFAULT_MODEL,
                    t_end: float = 400.0, rtol: float = 1e-10, atol: float = 1e-12) -> dict[str, float]:
    """One cell with DOP853 (eq 4.8, :meth:`TwoMassModel.rhs`): the label is the stable node
    (eq 4.11) nearest to the final x3."""
    eq = equilibria(u0, psi)
    x0 = initial_states(np.array([x3_0]), np.array([x4_0]), model)[0]
    sol = solve_ivp(model.rhs, (0.0, t_end), x0, method="DOP853", rtol=rtol, atol=atol, args=(u0, 0.0, psi))
    if not sol.success:
        raise SolverError(f"DOP853 failed: {sol.message}")
    xe = sol.y[:, -1]
    nodes = eq.stable
    lab = int(np.argmin(np.abs(nodes - xe[2])))
    return {"label": lab, "x3_end": float(xe[2]), "x4_end": float(xe[3]), "dist": float(abs(nodes[lab] - xe[2]))}
