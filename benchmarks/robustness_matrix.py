"""Interrupt, kill and full-disk matrix of issue 16 (the closing note's table), measured on real processes.

For each of ``modes --out``, ``diagnose --out``, ``report`` (``--quick --only`` one cheap
section) and a sweep (``sweep run``, 24 cells of 0.25 s, chunk size 1):

1. a first run writes the *previous set* into the output folder;
2. a run with different arguments (so a *new set* would differ) gets SIGINT at half its duration;
3. the same run gets SIGKILL at half its duration; then a third run (the same arguments, to the
   end) shows whether the temporaries of the killed one are removed;
4. full disk: the folder lives on a file system that holds the previous set and nothing more
   (a 16 MiB tmpfs mounted in a private mount namespace, ``unshare -m``, then filled with a
   filler file: real ENOSPC from the kernel), and the run with different arguments goes there.
   Without the right to mount (not root) the fallback is ``RLIMIT_FSIZE`` = 1 KiB on the run
   (SIGXFSZ ignored, so ``write`` fails with EFBIG "File too large" as on a full disk); the table
   says which one was used.

After each case: exit code, the state of the output folder (``previous set`` = byte-identical
to the previous set, ``new set`` = every file of the set replaced, ``MIXED`` otherwise, which
must never happen), and temporaries left (``*.probedyn-tmp-*``, journals).

    .venv/bin/python benchmarks/robustness_matrix.py [--only modes,sweep] [--json out.json]

Takes about 5-10 minutes on 2 shared cores (each run is a fresh ``python -m probedyn.cli``).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EX = ROOT / "examples" / "measurements"
CELLS = ("import time\nimport numpy as np\n\ndef slow(x, seed=None):\n    time.sleep(0.25 * np.size(x))\n"
         "    return {'y': np.asarray(x) * 2.0}\n")
SWEEP = ["sweep", "run", "cells:slow", "--grid", "x=0:1:24", "--chunk-size", "1", "--threads", "--no-progress"]

#: name -> (first run, run with different arguments, files of a complete set, folder of intended partial state)
TARGETS = {
    "modes --out": (["modes", "cantilever", "--n-modes", "4", "--out", "{out}"],
                    ["modes", "cantilever", "--n-modes", "4", "--set", "length=320e-6", "--out", "{out}"],
                    ("modes.json", "modes.vtu"), None),
    "diagnose --out": (["diagnose", str(EX / "al_cantilever_length_sweep.toml"), "--out", "{out}"],
                       ["diagnose", str(EX / "afm_cantilever_modes.toml"), "--out", "{out}"],
                       ("diagnose.json", "diagnose.md", "residuals.png", "evidence.png"), None),
    "report --quick --only": (["report", "--quick", "--only", "diagnosis", "--out", "{out}"],
                              ["report", "--quick", "--only", "contact", "--out", "{out}"], ("report.md",), None),
    "sweep run": (SWEEP + ["--out", "{out}/a.nc"], SWEEP + ["--seed", "3", "--out", "{out}/a.nc"], ("a.nc",),
                  "a.nc.parts"),
}


def _default_signals() -> None:  # in the child: a runner started in the background ignores SIGINT
    for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(s, signal.SIG_DFL)


def _cmd(argv: list[str]) -> list[str]:
    return [sys.executable, "-m", "probedyn.cli", *argv]


def _fill(argv: list[str], out: Path) -> list[str]:
    return [a.replace("{out}", str(out)) for a in argv]


def _is_tmp(name: str) -> bool:
    return "probedyn-tmp" in name or "probedyn-journal" in name


def snapshot(folder: Path, keep: str | None) -> dict[str, str]:
    if not folder.exists():
        return {}
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file() and not _is_tmp(p.name)
            and not p.name.endswith(".probedyn-lock") and not (keep and p.relative_to(folder).parts[0] == keep)}


def temporaries(where: Path) -> list[str]:
    return sorted(p.name for p in where.rglob("*") if _is_tmp(p.name)) if where.exists() else []


def state(before: dict[str, str], now: dict[str, str], files: tuple[str, ...]) -> str:
    if now == before:
        return "previous set"
    if not now:
        return "absent"
    replaced = [f for f in files if f in before and now.get(f) != before[f]]
    if len(replaced) == len([f for f in files if f in before]) and set(files) <= set(now):
        return "new set"
    return "MIXED"


def run(argv, cwd, env, timeout=900) -> subprocess.CompletedProcess:
    return subprocess.run(_cmd(argv), cwd=cwd, capture_output=True, text=True, timeout=timeout, env=env)


def signalled(argv, cwd, env, sig, delay) -> tuple[int, str, float | None]:
    p = subprocess.Popen(_cmd(argv), cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                         preexec_fn=_default_signals)
    time.sleep(delay)
    if p.poll() is not None:
        _, err = p.communicate()
        return p.returncode, err, None
    p.send_signal(sig)
    t0 = time.perf_counter()
    _, err = p.communicate(timeout=180)
    return p.returncode, err, time.perf_counter() - t0


def last_line(err: str) -> str:
    lines = [ln for ln in err.strip().splitlines() if ln.strip()]
    if any("Traceback" in ln for ln in lines):
        return "TRACEBACK: " + lines[-1]
    return lines[-1] if lines else ""


def can_mount() -> bool:
    if os.geteuid() != 0 or not shutil.which("unshare"):
        return False
    return subprocess.run(["unshare", "-m", "true"], capture_output=True).returncode == 0


def full_disk(name, first, alt, files, keep, work, env) -> dict:
    """The run with different arguments onto a file system full after the previous set."""
    mnt = work / "full"
    mnt.mkdir()
    out = mnt / "out"
    report = work / "full.json"
    if can_mount():
        method = "tmpfs 16 MiB in a private mount namespace, filled after the previous set (ENOSPC)"
        # the whole sequence runs inside the namespace (the mount disappears with it); a small
        # Python driver measures the folder before and after
        driver = f"""
import hashlib, json, subprocess, sys, pathlib
sys.path.insert(0, {str(ROOT / 'benchmarks')!r})
from robustness_matrix import snapshot, temporaries, state, last_line, _cmd, _fill
out = pathlib.Path({str(out)!r})
r1 = subprocess.run(_cmd(_fill({first!r}, out)), capture_output=True, text=True, cwd={str(work)!r})
before = snapshot(out, {keep!r})
filler = pathlib.Path({str(mnt)!r}) / "filler"
with open(filler, "wb") as fh:
    try:
        while True:
            fh.write(b"\\0" * 65536); fh.flush()
    except OSError:
        pass
try:
    fh.close()
except OSError:
    pass
r2 = subprocess.run(_cmd(_fill({alt!r}, out)), capture_output=True, text=True, cwd={str(work)!r})
now = snapshot(out, {keep!r})
json.dump({{"first": r1.returncode, "first_err": r1.stderr[-300:], "exit": r2.returncode,
           "message": last_line(r2.stderr), "folder": state(before, now, {tuple(files)!r}),
           "temporaries": temporaries(out)}}, open({str(report)!r}, "w"))
"""
        (work / "driver.py").write_text(driver)
        script = f"mount -t tmpfs -o size=16m none {shlex.quote(str(mnt))} && {shlex.quote(sys.executable)} driver.py"
        subprocess.run(["unshare", "-m", "bash", "-c", script], cwd=work, env=env, capture_output=True, timeout=1800)
        r = json.loads(report.read_text())
        if r["first"] != 0:
            r["message"] = f"the first run failed on the tmpfs: {r['first_err']}"
    else:
        method = "RLIMIT_FSIZE 1 KiB on the run (EFBIG, SIGXFSZ ignored)"
        r1 = run(_fill(first, out), work, env)
        assert r1.returncode == 0, r1.stderr[-1000:]
        before = snapshot(out, keep)

        def limit():
            import resource

            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
            resource.setrlimit(resource.RLIMIT_FSIZE, (1024, 1024))

        p = subprocess.run(_cmd(_fill(alt, out)), cwd=work, capture_output=True, text=True, env=env, preexec_fn=limit)
        r = {"exit": p.returncode, "message": last_line(p.stderr), "folder": state(before, snapshot(out, keep), files),
             "temporaries": temporaries(out)}
    return {"command": name, "fault": "full disk", "method": method, **{k: r[k] for k in
            ("exit", "message", "folder", "temporaries")}, "seconds_to_exit": None}


def matrix(only: list[str] | None = None) -> list[dict]:
    rows = []
    for name, (first, alt, files, keep) in TARGETS.items():
        if only and not any(o in name for o in only):
            continue
        work = Path(tempfile.mkdtemp(prefix="probedyn-matrix-"))
        try:
            (work / "cells.py").write_text(CELLS)
            env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(work), os.environ.get("PYTHONPATH", "")])}
            out = work / "out"
            t0 = time.perf_counter()
            r = run(_fill(first, out), work, env)
            full = time.perf_counter() - t0
            if r.returncode != 0:
                raise SystemExit(f"{name}: the first run failed: {r.stderr[-1000:]}")
            before = snapshot(out, keep)
            for _ in range(2):  # the second time warm (mesh cache, numba), as the faulted runs are
                t0 = time.perf_counter()
                r = run(_fill(alt, out), work, env)
                full_alt = time.perf_counter() - t0
                if r.returncode != 0:
                    raise SystemExit(f"{name}: the run with other arguments failed: {r.stderr[-1000:]}")
            # back to the previous set (the first arguments again)
            run(_fill(first, out), work, env)
            before = snapshot(out, keep)
            for sig in (signal.SIGINT, signal.SIGKILL):
                code, err, dt = signalled(_fill(alt, out), work, env, sig, 0.5 * full_alt)
                now = snapshot(out, keep)
                row = {"command": name, "fault": f"{sig.name} at {0.5 * full_alt:.1f} s of {full_alt:.1f} s",
                       "exit": code, "message": last_line(err) if sig != signal.SIGKILL else "-",
                       "folder": state(before, now, files), "temporaries": temporaries(work),
                       "seconds_to_exit": None if dt is None else round(dt, 2)}
                if sig == signal.SIGKILL:
                    r3 = run(_fill(alt, out), work, env)
                    row["next run"] = (f"exit {r3.returncode}, folder {state(before, snapshot(out, keep), files)}, "
                                       f"temporaries {temporaries(work) or 'none'}")
                    run(_fill(first, out), work, env)  # restore the previous set
                    before = snapshot(out, keep)
                if keep and (out / keep).exists():
                    row["partial state kept"] = f"{len(list((out / keep).glob('chunk-*')))} chunks in {keep}/"
                rows.append(row)
            rows.append(full_disk(name, first, alt, files, keep, work, env))
            rows[-1]["first run s"] = round(full, 1)
        finally:
            shutil.rmtree(work, ignore_errors=True)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", default="", help="comma-separated substrings of the command names")
    ap.add_argument("--json", default=None, help="write the rows as JSON")
    a = ap.parse_args()
    rows = matrix([s for s in a.only.split(",") if s] or None)
    print("| command | fault | exit | s to exit | output folder after | temporaries left | message / next run |")
    print("|---|---|---:|---:|---|---|---|")
    for r in rows:
        extra = r.get("next run") or r.get("message", "")
        if r.get("partial state kept"):
            extra += f"; {r['partial state kept']}"
        print(f"| {r['command']} | {r['fault']} | {r['exit']} | {r['seconds_to_exit'] if r['seconds_to_exit'] is not None else '-'} "
              f"| {r['folder']} | {', '.join(r['temporaries']) or 'none'} | {extra} |")
    methods = sorted({r["method"] for r in rows if r.get("method")})
    for m in methods:
        print(f"full disk: {m}")
    bad = [r for r in rows if r["folder"] == "MIXED" or "TRACEBACK" in str(r.get("message"))
           or (r["fault"] != "full disk" and r["exit"] not in (130, -9) and r["folder"] != "new set")
           or (r["fault"] == "full disk" and r["exit"] != 2)]
    print(f"{len(rows)} cases, {len(bad)} not as required")
    if a.json:
        Path(a.json).write_text(json.dumps(rows, indent=2) + "\n")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
