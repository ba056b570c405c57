"""The pull-off load of Maugis–Dugdale against the published fit of Carpick, Ogletree &
Salmeron (COS), J. Colloid Interface Sci. 211 (1999) 395: an independent check of the
Maugis–Dugdale solution (departure 7) over the whole DMT–JKR transition.

COS fit: ``lambda = -0.924 ln(1 - 1.02 alpha)``, pull-off load in units of pi W R
``-(0.267 alpha^2 - 0.767 alpha + 2.000)``: -2 at lambda = 0 (DMT), -1.5 at alpha = 1 (JKR; as
lambda -> inf alpha tends to 1/1.02, where the fit gives -1.505), within about 1 % of Maugis'
result in between.
"""

from __future__ import annotations

import math
from typing import Any, Sequence

from probedyn.schemes.contact.maugis_dugdale import MaugisDugdale

REFERENCE = "Carpick, Ogletree & Salmeron, J. Colloid Interface Sci. 211 (1999) 395"

#: lambdas of the pull-off table (DMT side to JKR side)
PULL_OFF_LAMBDAS = (1e-3, 0.01, 0.1, 0.3, 0.5, 0.938, 1.0, 2.0, 5.0, 10.0, 100.0, 1000.0)


def cos_fit_pull_off(lam: float) -> float:
    """Pull-off load / (pi W R) of the COS fit at transition parameter ``lam`` (inf = JKR)."""
    alpha = (1.0 - math.exp(-lam / 0.924)) / 1.02 if math.isfinite(lam) else 1.0 / 1.02
    return -(0.267 * alpha**2 - 0.767 * alpha + 2.000)


def pull_off_table(lams: Sequence[float] = PULL_OFF_LAMBDAS) -> list[dict[str, Any]]:
    """Pull-off of Maugis–Dugdale (load control: minimum of P; displacement control: jump-out)
    vs the COS fit, one row per lambda (normalised units)."""
    rows = []
    for lam in lams:
        po = MaugisDugdale(lam=lam).nd_pull_off()
        fit = cos_fit_pull_off(lam)
        rows.append(dict(lam=lam, pull_off=po["P_pull_off"], A_pull_off=po["A_pull_off"], cos_fit=fit,
                         rel_diff_pct=100 * (po["P_pull_off"] / fit - 1), jump_out=po["P_jump_out"],
                         D_jump_out=po["D_jump_out"]))
    return rows
