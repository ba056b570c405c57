"""Scanner creep / nonlinearity: the real support position bows away from the nominal one."""

from __future__ import annotations

import numpy as np

from probedyn.diagnose.causes import CAUSES, Cause, CauseParam


@CAUSES.register
class ScannerNonlinearity(Cause):
    key = "scanner-nonlinearity"
    kind = "friction"
    title = "Scanner nonlinearity / creep"
    source = "quadratic piezo nonlinearity, exact at the calibrated ends: X = X_nom + c (X - X0)(X1 - X)/(X1 - X0)"
    description = "The stick-slip period drifts along the scan (the support moves faster in the middle than the nominal calibration says)."
    needs = "a scan with several lattice periods"
    changes = ("scanner",)
    params = (CauseParam("bow", "1", -0.4, 0.4, 0.0, "bow coefficient c (largest error c L / 4 mid-scan)", starts=(-0.1, 0.1)),)

    def data_starts(self, problem, ref: dict) -> list[dict]:
        """From the slip positions of every steady segment: a slip happens at a fixed true support
        position in the lattice (n a + c, c per segment: trace and retrace differ by the loop), so
        ``X_s + c_bow (X_s - X0)(X1 - X_s)/(X1 - X0) = a n + c`` -- linear least squares for the bow,
        the period and the offsets (n: the slip's well count from the spacing)."""
        L = problem.loop
        a_ref = float(ref.get("a", problem.a_slip))
        rows, rhs, n_off = [], [], 0
        blocks = []
        for i, sl in enumerate(L.slips):
            s_ = problem.data.scans[i]
            x0, x1 = float(s_.position.min()), float(s_.position.max())
            for d, pos in sl:
                n = np.round((pos - pos[0]) / a_ref)
                h = (pos - x0) * (x1 - pos) / max(x1 - x0, 1e-30)
                blocks.append((n, h, pos))
        if sum(len(b[0]) for b in blocks) < len(blocks) + 3:
            return []
        m = len(blocks)
        for j, (n, h, pos) in enumerate(blocks):
            for nn, hh, xx in zip(n, h, pos):
                row = np.zeros(2 + m)
                row[0], row[1], row[2 + j] = nn, -hh, 1.0
                rows.append(row)
                rhs.append(xx)
        sol = np.linalg.lstsq(np.array(rows), np.array(rhs), rcond=None)[0]
        return [{"a": float(sol[0]), "bow": float(sol[1])}]

    def effect(self, v, s):
        s.bow += v["bow"]
