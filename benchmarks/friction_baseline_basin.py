"""Is a friction baseline's misfit a wrong basin or the model? (docs/diagnose.md, session 8, null 6037)

Usage: ``python benchmarks/friction_baseline_basin.py SEED [EFFECT]`` (a case of
``benchmarks/diagnose_rates_friction.py``, truth from its cache). Prints the baseline fit from its own
starts, the chi^2 at the truth's (u0, a) and the baseline re-fitted from there (the same chi^2: the
same basin), and the chi^2 per group (scan x direction) at the optimum: where the misfit sits.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from diagnose_rates_friction import cached_case  # noqa: E402

from probedyn.diagnose.engine import Fitter  # noqa: E402
from probedyn.diagnose.problems import make_problem  # noqa: E402


def main(seed: int, effect: str | None) -> None:
    path, truth = cached_case(seed, effect)
    P = make_problem(path)
    F = Fitter(P)
    t = time.process_time()
    b = F.baseline()
    print(f"baseline from its starts: chi2 {b.chi2:.6g} for {b.dof} dof at u0 {b.values['u0']:.5g}, a {b.values['a']:.5g} "
          f"({time.process_time() - t:.1f} s CPU)")
    tv = {"u0": truth["u0"], "a": truth["a"]}
    print(f"at the truth's u0 {tv['u0']:.5g}, a {tv['a']:.5g}: chi2 {float(np.sum(F.residuals(tv, ()) ** 2)):.6g}")
    bt = F.fit((), [tv])
    print(f"re-fitted from the truth: chi2 {bt.chi2:.6g} at u0 {bt.values['u0']:.5g}, a {bt.values['a']:.5g}")
    best = bt if bt.chi2 < b.chi2 else b
    g = np.asarray(P.groups)
    for gg in np.unique(g):
        m = g == gg
        print(f"group {gg}: {int(m.sum())} samples, chi2 {float(np.sum(best.r[m] ** 2)):.6g}")


if __name__ == "__main__":
    main(int(sys.argv[1]), sys.argv[2] if len(sys.argv) > 2 and sys.argv[2] != "None" else None)
