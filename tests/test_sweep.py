"""The Dask sweep engine: identity for 1 and N workers, resumption, errors, NetCDF output.

Dask clusters here are small (1-2 thread workers in this process, processes=False) so each
test takes a few seconds.
"""

from __future__ import annotations

import socket
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from probedyn.core.errors import ParameterError, ProbedynError, SolverError
from probedyn.schemes import stickslip as ss
from probedyn.schemes import sweep as sw

# ---------------------------------------------------------------------------------------
# test schemes (module level: picklable)
# ---------------------------------------------------------------------------------------

CALLS: list[tuple[int, ...]] = []  # (chunk's first x index, ...) of every evaluated call
_LOCK = threading.Lock()
FAIL_AT: dict[str, float | None] = {"x": None}


def noisy_scheme(x, y, scale=1.0, seed=None):
    """A vectorised randomised scheme: per-cell RNG from the engine's per-cell seed."""
    with _LOCK:
        CALLS.append(tuple(np.asarray(x).tolist()))
    if FAIL_AT["x"] is not None and np.any(np.isclose(x, FAIL_AT["x"])):
        raise RuntimeError("simulated crash")
    noise = np.array([np.random.default_rng(int(s)).standard_normal() for s in seed])
    traj = np.stack([x * scale, y * scale, x * y], axis=1)  # an array output per cell
    return {"f": np.sin(x) * np.cos(y) * scale, "noise": noise, "traj": traj, "flag": (x > y).astype(np.int8)}


def scalar_scheme(a, b):
    """Non-vectorised: called per cell with scalars."""
    return {"s": a + 10 * b, "v": np.array([a, b])}


def scheme_raising_parameter_error(x):
    raise ParameterError("x out of range for this scheme")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


GRID = {"x": np.linspace(0.0, 1.0, 7), "y": np.linspace(-1.0, 1.0, 5)}


def run(out=None, **kw):
    kw.setdefault("workers", 2)
    kw.setdefault("processes", False)
    kw.setdefault("progress", False)
    return sw.run_sweep(noisy_scheme, GRID, fixed={"scale": 2.0}, out=out, seed=42, **kw)


# ---------------------------------------------------------------------------------------


def test_dataset_layout_and_values(tmp_path):
    r = run(tmp_path / "a.nc", chunk_size=4)
    ds = r.dataset
    assert dict(ds.sizes) == {"x": 7, "y": 5, "traj_dim1": 3}
    X, Y = np.meshgrid(GRID["x"], GRID["y"], indexing="ij")
    # values land in the right cells (C order of the grid dict)
    np.testing.assert_array_equal(ds["f"].values, np.sin(X) * np.cos(Y) * 2.0)
    np.testing.assert_array_equal(ds["traj"].values[..., 2], X * Y)
    assert r.chunks_total == 9 and len(r.chunks_run) == 9
    # file written atomically, parts folder removed, no temporary left behind
    assert (tmp_path / "a.nc").exists()
    assert not (tmp_path / "a.nc.parts").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.nc"]
    back = sw.open_sweep(tmp_path / "a.nc")
    for k in ds.data_vars:
        np.testing.assert_array_equal(back[k].values, ds[k].values)


def test_one_and_n_workers_identical(tmp_path):
    r1 = run(tmp_path / "one.nc", workers=1, chunk_size=3)
    r2 = run(tmp_path / "two.nc", workers=2, chunk_size=3)
    a, b = sw.open_sweep(tmp_path / "one.nc"), sw.open_sweep(tmp_path / "two.nc")
    for k in a.data_vars:
        np.testing.assert_array_equal(a[k].values, b[k].values)
    # per-cell seeds depend only on (seed, cell): chunking does not change the noise either
    r3 = run(None, workers=2, chunk_size=11)
    np.testing.assert_array_equal(r3.dataset["noise"].values, r1.dataset["noise"].values)
    # different seed -> different noise (the seed is actually used)
    r4 = sw.run_sweep(noisy_scheme, GRID, fixed={"scale": 2.0}, seed=7, workers=1, processes=False, progress=False)
    assert not np.array_equal(r4.dataset["noise"].values, r1.dataset["noise"].values)


def test_basin_sweep_one_vs_two_workers_identical(tmp_path):
    g = {"x4_0": sw.axis("x4_0", -8, 8, 12), "x3_0": sw.axis("x3_0", -12, 12, 12)}
    fixed = {"u0": 8.0, "psi": 5.0}
    a = sw.run_sweep(ss.basin_cell, g, fixed=fixed, out=tmp_path / "b1.nc", workers=1, processes=False, progress=False, chunk_size=20)
    b = sw.run_sweep(ss.basin_cell, g, fixed=fixed, out=tmp_path / "b2.nc", workers=2, processes=False, progress=False, chunk_size=20)
    for k in ("label", "x3_final", "t_settle"):
        np.testing.assert_array_equal(a.dataset[k].values, b.dataset[k].values)
    # and identical to the in-process computation over all cells at once
    X3, X4 = np.meshgrid(g["x3_0"], g["x4_0"])
    ref = ss.basin_labels(X3, X4, 8.0, 5.0)
    np.testing.assert_array_equal(a.dataset["label"].values, ref["label"])


def test_interrupted_sweep_resumes_only_remaining_chunks(tmp_path):
    out = tmp_path / "r.nc"
    full = run(None, workers=1, chunk_size=5).dataset  # uninterrupted reference
    CALLS.clear()
    FAIL_AT["x"] = GRID["x"][4]  # chunks containing x = x[4] crash
    try:
        with pytest.raises(SolverError, match="simulated crash"):
            run(out, workers=1, chunk_size=5)
    finally:
        FAIL_AT["x"] = None
    parts = out.with_name(out.name + ".parts")
    saved = sorted(int(p.stem.split("-")[1]) for p in parts.glob("chunk-*.npz"))
    n_chunks = 7  # 35 cells / 5
    failing = {i for i in range(n_chunks) if np.any(np.isclose(np.unravel_index(np.arange(5 * i, 5 * i + 5), (7, 5))[0], 4))}
    assert saved and failing.isdisjoint(saved)  # finished chunks persisted, failed ones not
    assert not out.exists()  # no final file from an interrupted run
    CALLS.clear()
    r = run(out, workers=2, chunk_size=5)
    assert r.chunks_skipped == saved
    assert sorted(r.chunks_run) == sorted(set(range(n_chunks)) - set(saved))
    assert len(CALLS) == len(r.chunks_run)  # only the remaining chunks were evaluated
    for k in full.data_vars:
        np.testing.assert_array_equal(r.dataset[k].values, full[k].values)
    assert not parts.exists()


def test_resume_refuses_a_different_sweep(tmp_path):
    out = tmp_path / "m.nc"
    FAIL_AT["x"] = GRID["x"][6]
    try:
        with pytest.raises(SolverError):
            run(out, workers=1, chunk_size=5)
    finally:
        FAIL_AT["x"] = None
    with pytest.raises(ParameterError, match="different sweep"):
        sw.run_sweep(noisy_scheme, GRID, fixed={"scale": 3.0}, out=out, seed=42, workers=1, processes=False,
                     progress=False, chunk_size=5)
    r = sw.run_sweep(noisy_scheme, GRID, fixed={"scale": 3.0}, out=out, seed=42, workers=1, processes=False,
                     progress=False, chunk_size=5, restart=True)
    assert r.chunks_skipped == [] and len(r.chunks_run) == 7


def test_non_vectorised_scheme():
    r = sw.run_sweep(scalar_scheme, {"a": [1.0, 2.0], "b": [0.0, 1.0, 2.0]}, vectorized=False, workers=1,
                     processes=False, progress=False)
    np.testing.assert_array_equal(r.dataset["s"].values, [[1, 11, 21], [2, 12, 22]])
    assert r.dataset["v"].shape == (2, 3, 2)


def test_scheme_errors_propagate_cleanly():
    with pytest.raises(ParameterError, match="out of range"):
        sw.run_sweep(scheme_raising_parameter_error, {"x": [1.0]}, workers=1, processes=False, progress=False)


@pytest.mark.parametrize(
    "grid, msg",
    [
        ({}, "empty"),
        ({"x": []}, "zero points"),
        ({"x": [0.0, np.nan]}, "NaN"),
        ({"x": [[0.0, 1.0]]}, "one-dimensional"),
        ({"x": [1.0, 1.0]}, "repeated"),
        ({"1x": [1.0]}, "identifier"),
        ({"seed": [1.0]}, "reserved"),
        ({"scale": [1.0]}, "both a grid axis and a fixed"),
    ],
)
def test_bad_grids(grid, msg):
    t0 = time.perf_counter()
    with pytest.raises(sw.GridError, match=msg):
        sw.run_sweep(noisy_scheme, grid, fixed={"scale": 1.0}, workers=1, processes=False, progress=False)
    assert time.perf_counter() - t0 < 1.0  # rejected before any cluster starts


@pytest.mark.parametrize(
    "args, msg",
    [
        (("x", 0.0, 1.0, 0), "zero points"),
        (("x", 1.0, 0.0, 5), "inverted range"),
        (("x", 0.0, float("nan"), 5), "not a finite"),
        (("x", 1.0, 1.0, 3), "empty range"),
        (("x", 0.0, 1.0, 2.5), "integer"),
    ],
)
def test_bad_axes(args, msg):
    with pytest.raises(sw.GridError, match=msg):
        sw.axis(*args)


def test_parse_axis():
    name, a = sw.parse_axis("v=0.1:10:3:log")
    assert name == "v"
    np.testing.assert_allclose(a, [0.1, 1.0, 10.0])
    assert sw.parse_axis("u0=1,2,3")[1].tolist() == [1.0, 2.0, 3.0]
    for bad in ("v", "v=1:2", "v=a:b:c", "v=2:1:4", "v=0:1:0"):
        with pytest.raises(sw.GridError):
            sw.parse_axis(bad)


def test_unreachable_scheduler_fails_fast():
    port = free_port()  # nothing listens there
    t0 = time.perf_counter()
    with pytest.raises(sw.SchedulerError, match="cannot reach Dask scheduler"):
        sw.run_sweep(noisy_scheme, GRID, fixed={"scale": 1.0}, seed=1, scheduler=f"tcp://127.0.0.1:{port}",
                     connect_timeout=1.0, progress=False)
    assert time.perf_counter() - t0 < 5.0
    for bad in ("nonsense", "tcp://host", "http://x:1:2"):
        with pytest.raises(sw.SchedulerError, match="malformed"):
            sw.run_sweep(noisy_scheme, GRID, fixed={"scale": 1.0}, seed=1, scheduler=bad, progress=False)
    assert issubclass(sw.SchedulerError, ProbedynError)


def test_existing_scheduler_address(tmp_path):
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, protocol="tcp", dashboard_address=None) as cl:
        r = sw.run_sweep(noisy_scheme, GRID, fixed={"scale": 2.0}, seed=42, scheduler=cl.scheduler_address,
                         progress=False, chunk_size=5)
    ref = run(None, workers=1, chunk_size=5)
    for k in ref.dataset.data_vars:
        np.testing.assert_array_equal(r.dataset[k].values, ref.dataset[k].values)


def test_cli_sweep_basins_and_errors(tmp_path, capsys):
    import json

    from probedyn.cli import main

    out = tmp_path / "b.nc"
    assert main(["sweep", "basins", "--u0", "8", "--psi", "5", "--grid", "10", "--out", str(out),
                 "--no-progress", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert Path(res["plot"]).exists() and out.exists()
    assert res["unsettled_cells"] == 0
    assert abs(sum(res["basin_fraction"]) - 1.0) < 1e-12
    assert main(["sweep", "basins", "--u0", "8", "--grid", "0", "--out", str(out)]) == 2
    assert "zero points" in capsys.readouterr().err
    assert main(["sweep", "basins", "--u0", "8", "--grid", "4", "--x3-range", "5:-5", "--out", str(out)]) == 2
    assert "inverted range" in capsys.readouterr().err
    port = free_port()
    t0 = time.perf_counter()
    assert main(["sweep", "basins", "--u0", "8", "--grid", "4", "--out", str(out),
                 "--scheduler", f"tcp://127.0.0.1:{port}"]) == 2
    assert "cannot reach Dask scheduler" in capsys.readouterr().err
    assert time.perf_counter() - t0 < 8.0


@pytest.mark.slow  # ~13 s: a subprocess with its own Dask cluster
def test_killed_cli_sweep_resumes(tmp_path):
    """A real interruption: SIGKILL the `probedyn sweep basins` process after a few chunks
    are on disk, rerun the same command, and compare with the in-process computation."""
    import os
    import signal
    import subprocess
    import sys

    from probedyn.cli import main

    out = tmp_path / "k.nc"
    parts = tmp_path / "k.nc.parts"
    args = ["sweep", "basins", "--u0", "20", "--psi", "5", "--grid", "128", "--chunk-size", "256",
            "--workers", "1", "--out", str(out), "--no-progress"]
    proc = subprocess.Popen([sys.executable, "-c", "import sys; from probedyn.cli import main; sys.exit(main(sys.argv[1:]))", *args],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        t0 = time.time()
        while time.time() - t0 < 60:
            if len(list(parts.glob("chunk-*.npz"))) >= 2 or proc.poll() is not None:
                break
            time.sleep(0.02)
        assert proc.poll() is None, "the sweep finished before it could be interrupted"
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(10)
    finally:
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
    assert not out.exists()
    saved = sorted(int(p.stem.split("-")[1]) for p in parts.glob("chunk-*.npz"))
    assert 2 <= len(saved) < 64  # 128*128/256 = 64 chunks
    # a temporary file of a chunk being written at the kill may remain; it is never read
    from probedyn.schemes.regimes import run_basins

    rr = run_basins(20.0, 5.0, 128, out, workers=2, processes=False, progress=False, chunk_size=256)
    assert rr["chunks_skipped"] == len(saved) and rr["chunks_run"] == 64 - len(saved)
    ds = sw.open_sweep(out)
    X3, X4 = np.meshgrid(ds["x3_0"].values, ds["x4_0"].values)
    ref = ss.basin_labels(X3, X4, 20.0, 5.0)
    np.testing.assert_array_equal(ds["label"].values, ref["label"])



def test_parts_folder_without_manifest_and_chunks_is_reused(tmp_path):
    # a run killed right after creating the parts folder leaves it empty: not an error
    out = tmp_path / "e.nc"
    (tmp_path / "e.nc.parts").mkdir()
    r = run(out, workers=1, chunk_size=7)
    assert len(r.chunks_run) == 5 and out.exists()


def test_process_workers_match_in_process(tmp_path):
    # the default LocalCluster runs workers as processes: the scheme is pickled by reference
    # and imported there; results must equal the in-process computation bit for bit
    g = {"x4_0": sw.axis("x4_0", -8, 8, 6), "x3_0": sw.axis("x3_0", -12, 12, 6)}
    r = sw.run_sweep(ss.basin_cell, g, fixed={"u0": 8.0, "psi": 5.0}, out=tmp_path / "p.nc", workers=2,
                     processes=True, progress=False, chunk_size=9)
    X3, X4 = np.meshgrid(g["x3_0"], g["x4_0"])
    ref = ss.basin_labels(X3, X4, 8.0, 5.0)
    np.testing.assert_array_equal(r.dataset["label"].values, ref["label"])
    np.testing.assert_array_equal(r.dataset["t_settle"].values, ref["t_settle"])


def test_cli_generic_sweep_run(tmp_path, capsys):
    import json

    from probedyn.cli import main

    out = tmp_path / "g.nc"
    assert main(["sweep", "run", "tests.test_sweep:scalar_scheme", "--grid", "a=1,2", "--grid", "b=0:2:3",
                 "--scalar", "--workers", "1", "--threads", "--out", str(out), "--no-progress", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["dims"] == {"a": 2, "b": 3, "v_dim1": 2}
    np.testing.assert_array_equal(sw.open_sweep(out)["s"].values, [[1, 11, 21], [2, 12, 22]])
    assert main(["sweep", "run", "tests.test_sweep:nope", "--grid", "a=1", "--out", str(out)]) == 2
    assert "has no function" in capsys.readouterr().err
    assert main(["sweep", "run", "tests.test_sweep:scalar_scheme", "--grid", "a=2:1:3", "--out", str(out)]) == 2
    assert "inverted range" in capsys.readouterr().err
