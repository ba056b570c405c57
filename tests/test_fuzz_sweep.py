"""Sweeps against hostile or failing schedulers and sweep state (issue 16, classes 4 and 8).

Fast, in-process versions: Dask clusters here run their workers as threads; the versions that
kill real worker and scheduler processes are in tests/test_fuzz_faults.py (slow).
"""

from __future__ import annotations

import contextlib
import http.server
import json
import socket
import threading
import time

import numpy as np
import pytest

from fuzzkit import TALLY
from probedyn.core.errors import ParameterError, ResourceError
from probedyn.schemes import sweep as sw


def double(x):
    return {"y": np.asarray(x) * 2.0}


def slow_double(x):
    time.sleep(0.15 * np.size(x))
    return {"y": np.asarray(x) * 2.0}


def _record(case_id, cls, ok, detail, t0):
    TALLY.append({"id": case_id, "class": cls, "category": "clean-error" if ok else "wrong", "detail": detail,
                  "seconds": round(time.perf_counter() - t0, 2), "pending": None, "child": False})


@pytest.fixture
def silent_listener():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    s.listen(8)
    conns = []
    stop = threading.Event()

    def accept():
        s.settimeout(0.2)
        while not stop.is_set():
            try:
                conns.append(s.accept()[0])
            except OSError:
                pass

    th = threading.Thread(target=accept, daemon=True)
    th.start()
    yield f"tcp://127.0.0.1:{s.getsockname()[1]}"
    stop.set()
    th.join()
    for c in conns:
        c.close()
    s.close()


@pytest.fixture
def http_server():
    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *a):
            pass

    srv = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Quiet)
    th = threading.Thread(target=srv.serve_forever, daemon=True)
    th.start()
    yield f"tcp://127.0.0.1:{srv.server_address[1]}"
    srv.shutdown()
    srv.server_close()


def _run(scheduler, out=None, **kw):
    kw.setdefault("progress", False)
    kw.setdefault("connect_timeout", 0.5)
    return sw.run_sweep(double, {"x": np.linspace(0, 1, 6)}, out=out, scheduler=scheduler, **kw)


@pytest.mark.parametrize("kind", ["silent", "http"])
def test_listener_that_is_not_dask_fails_within_the_timeout(kind, silent_listener, http_server, tmp_path):
    addr = silent_listener if kind == "silent" else http_server
    import distributed  # noqa: F401  (imported before the clock starts: the bound is on the connection, not on an import under load)

    t0 = time.perf_counter()
    with pytest.raises(sw.SchedulerError, match="not .*Dask scheduler|did not answer as a Dask scheduler") as exc:
        _run(addr, tmp_path / "a.nc")
    dt = time.perf_counter() - t0
    _record(f"c4-{kind}-listener", 4, dt < 5, str(exc.value), t0)
    assert dt < 5.0
    assert not list(tmp_path.iterdir())  # nothing left behind: no parts folder, no lock


def test_tls_without_certificates_is_a_clear_error(http_server, tmp_path):
    t0 = time.perf_counter()
    with pytest.raises(sw.SchedulerError, match="tls:// scheduler needs TLS certificates") as exc:
        _run(http_server.replace("tcp://", "tls://"), tmp_path / "a.nc")
    _record("c4-tls", 4, True, str(exc.value), t0)


def test_a_worker_address_is_not_a_scheduler(tmp_path):
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp",
                      dashboard_address=None) as cl:
        worker = next(iter(cl.scheduler_info["workers"]))
        t0 = time.perf_counter()
        with pytest.raises(sw.SchedulerError, match="answers as a Dask Worker, not a scheduler") as exc:
            _run(worker)
        _record("c4-worker-address", 4, True, str(exc.value), t0)


def test_scheduler_without_workers_fails_after_the_worker_timeout(tmp_path):
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=0, processes=False, protocol="tcp", dashboard_address=None) as cl:
        t0 = time.perf_counter()
        with pytest.raises(sw.SchedulerError, match=r"has no workers \(waited 1 s\); start workers") as exc:
            _run(cl.scheduler_address, tmp_path / "a.nc", worker_timeout=1.0)
        dt = time.perf_counter() - t0
        _record("c4-no-workers", 4, dt < 6, str(exc.value), t0)
        assert dt < 6.0
    assert not list(tmp_path.iterdir())


@pytest.mark.slow
def test_one_of_two_workers_dying_mid_run_is_survived(tmp_path):
    """A worker lost mid-run while another remains is no failure: Dask recomputes what the lost one
    held (a running chunk, a finished one not yet fetched) on the other, the sweep only watches, and
    the result is the uninterrupted one."""
    from dask.distributed import LocalCluster

    out = tmp_path / "a.nc"
    grid = {"x": np.linspace(0, 1, 40)}
    cl = LocalCluster(n_workers=2, threads_per_worker=1, processes=False, protocol="tcp", dashboard_address=None)
    try:
        killed_at: list[int] = []

        def kill():
            parts = out.with_name("a.nc.parts")
            while not parts.exists() or len(list(parts.glob("chunk-*"))) < 3:
                time.sleep(0.05)
            cl.sync(list(cl.workers.values())[0].close)
            killed_at.append(len(list(parts.glob("chunk-*"))))

        th = threading.Thread(target=kill, daemon=True)
        th.start()
        r = sw.run_sweep(slow_double, grid, out=out, scheduler=cl.scheduler_address, chunk_size=1, progress=False,
                         worker_timeout=5.0, connect_timeout=1.0)
        th.join(timeout=10)
    finally:
        with contextlib.suppress(Exception):
            cl.close(timeout=5)
    assert killed_at and killed_at[0] < 40  # the fault did happen, during the run
    assert r.chunks_run == list(range(40)) and out.exists()
    np.testing.assert_array_equal(r.dataset["y"].values, 2 * grid["x"])


@pytest.mark.slow
@pytest.mark.parametrize("what", ["workers", "scheduler"])
def test_cluster_dying_mid_run_keeps_finished_chunks_for_resumption(what, tmp_path):
    from dask.distributed import LocalCluster

    out = tmp_path / "a.nc"
    grid = {"x": np.linspace(0, 1, 40)}
    cl = LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp", dashboard_address=None)
    try:
        def kill():
            while not out.with_name("a.nc.parts").exists() or len(list(out.with_name("a.nc.parts").glob("chunk-*"))) < 3:
                time.sleep(0.05)
            if what == "workers":
                cl.scale(0)
            else:
                cl.sync(cl.scheduler.close)

        th = threading.Thread(target=kill, daemon=True)
        th.start()
        t0 = time.perf_counter()
        with pytest.raises(sw.SchedulerError, match=r"chunks are kept in .*a\.nc\.parts; run the same command again") as exc:
            sw.run_sweep(slow_double, grid, out=out, scheduler=cl.scheduler_address, chunk_size=1, progress=False,
                         worker_timeout=1.0, connect_timeout=1.0)
        dt = time.perf_counter() - t0
        th.join(timeout=10)
        _record(f"c4-{what}-die-mid-run", 4, dt < 20, str(exc.value), t0)
        assert dt < 20.0
    finally:
        with contextlib.suppress(Exception):
            cl.close(timeout=5)
    kept = sorted(out.with_name("a.nc.parts").glob("chunk-*.npz"))
    assert len(kept) >= 3 and not out.exists()
    r = sw.run_sweep(slow_double, grid, out=out, chunk_size=1, progress=False, workers=2, processes=False)
    assert len(r.chunks_skipped) == len(kept)
    np.testing.assert_array_equal(r.dataset["y"].values, 2 * grid["x"])


def test_second_identical_sweep_is_refused_while_the_first_runs(tmp_path):
    out = tmp_path / "a.nc"
    grid = {"x": np.linspace(0, 1, 10)}
    res = {}

    def first():
        res["r"] = sw.run_sweep(slow_double, grid, out=out, chunk_size=1, progress=False, workers=1,
                                processes=False)

    th = threading.Thread(target=first)
    th.start()
    while not out.with_name("a.nc.parts").exists():
        time.sleep(0.02)
    t0 = time.perf_counter()
    with pytest.raises(sw.SweepBusyError, match=r"another probedyn sweep \(pid \d+\) is writing") as exc:
        sw.run_sweep(slow_double, grid, out=out, chunk_size=1, progress=False, workers=1, processes=False)
    _record("c8-concurrent-sweep", 8, True, str(exc.value), t0)
    th.join()
    assert out.exists() and len(res["r"].chunks_run) == 10
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.nc"]  # lock file and parts removed
    # and afterwards the same sweep runs again normally
    sw.run_sweep(double, grid, out=out, progress=False, workers=1, processes=False)


@pytest.mark.parametrize("state", ["empty", "manifest-only", "other-manifest-no-chunks"])
def test_parts_folder_without_chunks_is_not_another_sweep(state, tmp_path):
    out = tmp_path / "a.nc"
    parts = tmp_path / "a.nc.parts"
    parts.mkdir()
    if state != "empty":
        sig = "0" * 64 if state == "other-manifest-no-chunks" else None
        (parts / "manifest.json").write_text(json.dumps({"signature": sig}) if sig else "{not json")
    r = _run(None, out, workers=1, processes=False)
    assert out.exists() and len(r.chunks_run) == r.chunks_total and not parts.exists()


def test_chunks_without_a_manifest_are_a_clear_error(tmp_path):
    parts = tmp_path / "a.nc.parts"
    parts.mkdir()
    np.savez(parts / "chunk-00000.npz", v_y=np.zeros(1))
    t0 = time.perf_counter()
    with pytest.raises(ParameterError, match="holds chunks but no readable manifest") as exc:
        _run(None, tmp_path / "a.nc", workers=1, processes=False)
    _record("c8-chunks-no-manifest", 8, True, str(exc.value), t0)


def test_memory_estimate_refuses_a_huge_grid_before_allocating(tmp_path):
    t0 = time.perf_counter()
    with pytest.raises(ResourceError, match=r"a sweep of 1e\+10 cells needs about .* of memory") as exc:
        sw.run_sweep(double, {"a": np.arange(100000.0), "b": np.arange(100000.0)}, out=tmp_path / "a.nc",
                     progress=False)
    dt = time.perf_counter() - t0
    _record("c8-memory-estimate", 8, dt < 2, str(exc.value), t0)
    assert dt < 2.0 and not list(tmp_path.iterdir())


def test_failed_connection_leaves_no_parts_folder(tmp_path):
    port = socket.socket()
    port.bind(("127.0.0.1", 0))
    addr = f"tcp://127.0.0.1:{port.getsockname()[1]}"
    port.close()  # nothing listens there
    with pytest.raises(sw.SchedulerError, match="cannot reach"):
        _run(addr, tmp_path / "a.nc")
    assert not list(tmp_path.iterdir())


def test_asyncio_reports_about_orphaned_dask_tasks_are_dropped(caplog):
    """A worker lost while a chunk was gathered leaves Dask tasks that fail after the sweep has
    reported; asyncio would log "Task exception was never retrieved" with a traceback when they
    are collected. The sweep's filter drops those records, and only those (a task of anyone else
    failing unretrieved is still reported)."""
    import asyncio
    import gc
    import logging

    from distributed.client import AllExit

    with sw._quiet_dask():
        pass

    def orphan(exc: BaseException) -> None:
        async def fail():
            raise exc

        async def main():
            asyncio.ensure_future(fail())  # never awaited, never retrieved
            await asyncio.sleep(0.01)

        asyncio.run(main())
        gc.collect()

    def ours(records, text):  # only this test's tasks: an earlier test's orphaned future may be collected here too
        return [r for r in records if r.name == "asyncio" and text in r.getMessage()]

    gc.collect()  # orphans of earlier tests in this process are reported now, before the capture
    with caplog.at_level(logging.ERROR, logger="asyncio"):
        orphan(AllExit())
        dask_records = ours(caplog.records, "AllExit")
        orphan(ValueError("someone else's task"))
        other_records = ours(caplog.records, "someone else's task")
    assert dask_records == []
    assert len(other_records) == 1 and "never retrieved" in other_records[0].getMessage()
