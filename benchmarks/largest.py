"""The largest model actually solved in the machine's memory (not extrapolated): first 10 modes
of the default cantilever with P2 tetrahedra (and, with ``--element hex-s2``, the structured
serendipity mesh) on ever finer meshes, each in a fresh process, until the next step would not
fit.  Needs the machine to itself (run it last, nothing else heavy running; ``free -g`` should
show >= 20 GiB available).

The next size is chosen from the measured peak memory of the previous ones (power law in the
DOFs, fitted on the last two steps) so that its prediction stays below ``--limit`` GiB; a step
that fails (out of memory, killed) ends the ladder and the last successful one is reported.

Usage::

    .venv/bin/python benchmarks/largest.py --out benchmarks/results/largest.txt
    .venv/bin/python benchmarks/largest.py --element hex-s2 --limit 22
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np

T = 10e-6


def one(divisor: float, element: str) -> dict:
    from probedyn.probes import get_probe

    p = get_probe("cantilever")[0]
    if element == "tet-p2":
        v = p.resolve({"element": "tet-p2", "elements_through_thickness": 1, "element_size": T / divisor})
    else:
        v = p.resolve({"element": element, "elements_through_thickness": max(1, int(round(3 * divisor / 2))),
                       "element_size": T * 2 / divisor})
    t0 = time.perf_counter()
    model = p.build(v)
    t1 = time.perf_counter()
    res = model.modes(10)
    t2 = time.perf_counter()
    return {"divisor": divisor, "element": element, "dofs": res.dofs, "mesh_s": t1 - t0, "solve_total_s": t2 - t1,
            "total_s": t2 - t0, "assemble_s": res.timings.get("assemble_s"), "factor_s": res.timings.get("factor_s"),
            "eigen_s": res.timings.get("arpack_s"), "f1_hz": float(res.frequencies_hz[0]),
            "peak_rss_gib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20}


def rss_gib(pid: int) -> float:
    """Resident memory [GiB] of a running process (0 when it is gone)."""
    try:
        with open(f"/proc/{pid}/status") as fh:
            for line in fh:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 2**20
    except OSError:
        pass
    return 0.0


def run_capped(cmd: list[str], cap_gib: float | None) -> tuple[int, str, str, float]:
    """Run ``cmd``; kill it if its resident memory exceeds ``cap_gib`` (other jobs share the
    machine: an out-of-memory kill would hit them too). Returns (exit code, stdout, stderr,
    highest RSS seen [GiB])."""
    import tempfile

    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        p = subprocess.Popen(cmd, stdout=out, stderr=err, text=True)
        high = 0.0
        while p.poll() is None:
            high = max(high, rss_gib(p.pid))
            if cap_gib is not None and high > cap_gib:
                p.kill()
                p.wait()
                err.write(f"killed by the benchmark: resident memory {high:.2f} GiB above the cap {cap_gib:g} GiB\n")
                break
            time.sleep(0.2)
        out.seek(0)
        err.seek(0)
        return p.returncode, out.read(), err.read(), high


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--one", type=float, default=None, help=argparse.SUPPRESS)
    ap.add_argument("--element", default="tet-p2", choices=("tet-p2", "hex-s2"))
    ap.add_argument("--limit", type=float, default=22.0, help="GiB a step may be predicted to use")
    ap.add_argument("--start", type=float, default=5.0, help="first divisor (h = t / divisor)")
    ap.add_argument("--out", default=None)
    ap.add_argument("--cap", type=float, default=None, help="kill a step whose resident memory exceeds this [GiB]")
    ap.add_argument("--only", action="store_true", help="solve the --start size only (no ladder)")
    a = ap.parse_args()
    if a.one is not None:
        print(json.dumps(one(a.one, a.element)))
        return
    import tempfile

    os.environ.setdefault("PROBEDYN_CACHE", tempfile.mkdtemp(prefix="probedyn-largest-"))
    lines = [f"probedyn benchmarks/largest.py ({a.element}): 10 modes of the default cantilever, ever finer meshes, "
             f"each in a fresh process; load average at start {os.getloadavg()[0]:.1f}"]
    print(lines[0], flush=True)
    done: list[dict] = []
    d = a.start
    while True:
        cmd = [sys.executable, __file__, "--one", str(d), "--element", a.element]
        code, stdout, stderr, high = run_capped(cmd, a.cap)
        if code != 0:
            msg = f"t/{d:.3g}: failed (exit {code}): {stderr.strip().splitlines()[-1] if stderr.strip() else 'killed'}"
            print(msg, flush=True)
            lines.append(msg)
            break
        r = json.loads(stdout.strip().splitlines()[-1])
        r["watched_rss_gib"] = high
        done.append(r)
        msg = (f"t/{d:.3g}: {r['dofs']} DOFs, total {r['total_s']:.0f} s (assembly {r['assemble_s']:.0f}, factor "
               f"{r['factor_s']:.0f}, eigen {r['eigen_s']:.0f}), peak {r['peak_rss_gib']:.2f} GiB, f1 {r['f1_hz']:.1f} Hz")
        print(msg, flush=True)
        lines.append(msg)
        if a.only:
            break
        # next: a power law in DOFs through the last two steps; DOFs ~ d^3
        if len(done) >= 2:
            n = np.log([done[-2]["dofs"], done[-1]["dofs"]])
            m = np.log([done[-2]["peak_rss_gib"], done[-1]["peak_rss_gib"]])
            e = (m[1] - m[0]) / (n[1] - n[0])
        else:
            e = 1.2
        grow = (a.limit / r["peak_rss_gib"]) ** (1.0 / max(e, 1.0))  # DOF factor that reaches the limit
        if grow < 1.15:
            break
        d *= min(grow, 2.0) ** (1.0 / 3.0) * 0.98
    if done:
        best = done[-1]
        lines.append(f"largest model solved: {best['dofs']} DOFs ({a.element}) in {best['total_s']:.0f} s end to end, "
                     f"peak {best['peak_rss_gib']:.2f} GiB")
        print(lines[-1])
    if a.out:
        from probedyn.core.io import write_text

        write_text(a.out, "\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
