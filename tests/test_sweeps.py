"""Sweeps in long-lived workers (compare/pool.py), the batch API, the variability study on a
local process pool and on a Dask cluster over TCP, and a clean Ctrl-C."""

import gc
import json
import os
import signal
import subprocess
import sys
import time
import weakref

import numpy as np
import pytest
from _process_helpers import cached_rows, running, start_in_own_group, wait_for_rows

import deckpound as dp
from deckpound import cli
from deckpound.compare import cases, pool
from deckpound.compare.cases import MAX_BATCH, batch_size, map_parallel, task_batches
from deckpound.models.file_io import is_temporary
from deckpound.models.result import read_table

SHORT = ["excitation.duration=2.0"]


def _pid(_x):
    time.sleep(0.05)  # long enough that both workers take cases
    return os.getpid()


def _boom(x):
    if x == 3:
        raise ValueError("case 3 failed")
    return x


def _blas_threads(_x):
    from threadpoolctl import threadpool_info

    np.ones((300, 300)) @ np.ones((300, 300))  # BLAS loaded and used in this worker
    return max((lib["num_threads"] for lib in threadpool_info()), default=1)


def test_workers_keep_blas_to_one_thread():
    """A worker's BLAS threads would busy-wait on the cores the other workers' step loops
    need (compare/pool.py, one_blas_thread): each worker runs BLAS on one thread."""
    threads = []
    map_parallel([0, 1], lambda i: (i,), _blas_threads, lambda it, v: threads.append(v), 2, None)
    assert threads == [1, 1]


def _frozen_objects(_x):
    return gc.get_freeze_count()


@pytest.mark.parametrize("where", ["this process", "pool", "dask"])
def test_cases_run_with_the_older_objects_out_of_the_collectors_way(where, monkeypatch):
    """A sweep's cases run inside pool.gc_frozen, in this process and in the workers' batches,
    and a Dask client (with, here, its scheduler) stays frozen while the map runs: the full
    collections a sweep's allocations trigger do not visit the objects that existed before
    it; after it, nothing is left frozen. (The local pool's parent is not frozen: see
    map_parallel.)"""
    assert gc.get_freeze_count() == 0
    inside, parent = [], []

    def done(it, v):
        inside.append(v)
        parent.append(gc.get_freeze_count())

    args = (list(range(4)), lambda i: (i,), _frozen_objects, done)
    if where == "dask":
        distributed = pytest.importorskip("dask.distributed")
        # the worker runs in this process: its heap and kernels are the test process's own
        monkeypatch.setattr(cases, "keep_freed_memory", lambda: False)
        with distributed.LocalCluster(
            n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
        ) as cluster:
            map_parallel(*args, None, cluster.scheduler_address)
    else:
        map_parallel(*args, 1 if where == "this process" else 2, None)
    assert len(inside) == 4 and min(inside) > 0
    assert min(parent) > 0 if where != "pool" else max(parent) == 0
    assert gc.get_freeze_count() == 0


def test_gc_frozen_restores_and_leaves_an_owners_freeze_alone():
    """gc_frozen unfreezes at its end, also after an error, so a cycle dropped inside is
    collected afterwards; a process that froze objects itself keeps its freeze."""

    class Node:
        pass

    def cycle():
        a, b = Node(), Node()
        a.other, b.other = b, a
        return a

    held = cycle()
    probe = weakref.ref(held)
    with pytest.raises(RuntimeError), pool.gc_frozen():
        assert gc.get_freeze_count() > 0
        del held  # garbage now, but frozen: the collector does not visit it inside
        gc.collect()
        assert probe() is not None
        raise RuntimeError("a case failed")
    assert gc.get_freeze_count() == 0
    gc.collect()
    assert probe() is None
    gc.freeze()
    try:
        owners = gc.get_freeze_count()
        with pool.gc_frozen():
            assert gc.get_freeze_count() == owners
        assert gc.get_freeze_count() == owners
    finally:
        gc.unfreeze()


def _square_pid(x):
    return x * x, os.getpid()


def test_a_sweep_travels_in_batches_and_every_item_is_done_once():
    """Workers take several cases per task (compare/cases.py, batch_size); on_done still sees
    every item once, with its own value."""
    assert batch_size(1, 2) == 1 and batch_size(10, 2) == 1
    assert batch_size(10_000, 2) == MAX_BATCH
    assert 1 < batch_size(60, 2) <= MAX_BATCH
    seen = {}
    map_parallel(
        list(range(60)), lambda i: (i,), _square_pid, lambda it, v: seen.setdefault(it, v), 2, None
    )
    assert sorted(seen) == list(range(60))
    assert all(seen[i][0] == i * i for i in seen)
    # items of one batch run in one worker, one after the other; the batches shrink to single
    # items at the end (no worker waits at the end for another's whole batch)
    size = batch_size(60, 2)
    batches = task_batches(list(range(60)), size, 2)
    assert [i for b in batches for i in b] == list(range(60))
    lengths = [len(b) for b in batches]
    assert lengths[0] == size and lengths[-1] == 1 and lengths == sorted(lengths, reverse=True)
    assert all(len({seen[i][1] for i in b}) == 1 for b in batches)
    # a long map: a task per MAX_BATCH items, then the shrinking tail
    long = [len(b) for b in task_batches(list(range(10_000)), MAX_BATCH, 2)]
    assert long.count(MAX_BATCH) >= 10_000 // MAX_BATCH - 4 and len(long) < 10_000 // MAX_BATCH + 40


def test_pool_scope_reuses_workers_across_maps():
    def pids(n_items):
        out = []
        map_parallel(
            list(range(n_items)), lambda i: (i,), _pid, lambda it, v: out.append(v), 2, None
        )
        return set(out)

    with pool.pool_scope():
        first, second = pids(6), pids(6)
        assert second == first and os.getpid() not in first  # the same two workers
    assert pool._SCOPE.pool is None  # closed with the scope
    assert pids(6).isdisjoint(first)  # outside: a pool per map


def test_worker_error_propagates_and_kills_the_workers():
    with pool.pool_scope():
        with pytest.raises(ValueError, match="case 3 failed"):
            map_parallel(list(range(8)), lambda i: (i,), _boom, lambda *a: None, 2, None)
        assert pool._SCOPE.pool is None


def test_run_batch_equals_single_runs(tmp_path):
    scenes = [
        dp.load_scene("saiidi-4span", set=[*SHORT, f"excitation.seed={s}"]) for s in (1, 2, 3)
    ]
    batch = dp.run_batch(scenes, engine="compliance", workers=2, cache=tmp_path)
    assert dp.run_many is dp.run_batch
    for sc, r in zip(scenes, batch):
        one = dp.run(sc, engine="compliance")
        np.testing.assert_array_equal(r["deck_theta"], one["deck_theta"])
    again = dp.run_batch(scenes, engine="compliance", workers=2, cache=tmp_path)  # cached
    assert [r.meta["scene_hash"] for r in again] == [r.meta["scene_hash"] for r in batch]
    # summary-only results: no rows, the full runs' every-step peaks, cached apart from them
    for _ in range(2):  # computed, then read back from the same cache
        summaries = dp.run_batch(
            scenes, engine="compliance", workers=2, cache=tmp_path, summary_only=True
        )
        for full, summary in zip(batch, summaries):
            assert not summary.has_histories and len(summary.t) == 0
            assert summary.peak("deck_theta") == full.peak("deck_theta")
            assert summary.meta["gap_closures"] == full.meta["gap_closures"]
    assert dp.run_batch(scenes, engine="compliance", workers=1, cache=tmp_path)[0].has_histories


def _variability(tmp_path, name, *extra):
    out = tmp_path / name
    code = cli.main(
        [
            "study",
            "variability",
            "saiidi-4span",
            "--cases",
            "3",
            "--no-progress",
            "-o",
            str(out),
            *[a for s in SHORT for a in ("--set", s)],
            *extra,
        ]
    )
    assert code == 0
    return out, read_table(out / "variability.csv"), read_table(out / "variability_summary.csv")


def test_variability_study_table_summary_figure_and_resume(tmp_path, capsys):
    out, table, summary = _variability(tmp_path, "v", "--workers", "2")
    assert list(table["seed"]) == [1994, 1995, 1996] and (table["status"] == "success").all()
    assert {"peak_theta", "peak_y", "gap_closures", "closures_c1"} <= set(table.columns)
    s = summary.set_index("quantity")
    for q in ("peak_theta", "peak_y", "gap_closures"):
        x = table[q].to_numpy(float)
        assert s.loc[q, "median"] == pytest.approx(np.median(x))
        assert s.loc[q, "p16"] == pytest.approx(np.percentile(x, 16))
        assert s.loc[q, "p84"] == pytest.approx(np.percentile(x, 84))
    assert (out / "variability.png").stat().st_size > 5000
    printed = capsys.readouterr().out
    assert "median" in printed and "3 cases (0 not finished, 0 doubtful" in printed
    # a second run takes every row from the cache
    _variability(tmp_path, "v", "--workers", "2")
    assert json.loads((out / "variability.json").read_text())["from_cache"] == 3


def test_variability_on_a_dask_cluster_over_tcp_equals_local(tmp_path):
    distributed = pytest.importorskip("dask.distributed")
    _, local, _ = _variability(tmp_path, "local", "--workers", "1")
    with distributed.LocalCluster(
        n_workers=1,
        threads_per_worker=1,
        processes=True,
        protocol="tcp",
        host="127.0.0.1",
        dashboard_address=None,
    ) as cluster:
        assert cluster.scheduler_address.startswith("tcp://127.0.0.1:")
        _, remote, _ = _variability(tmp_path, "dask", "--scheduler", cluster.scheduler_address)
    for q in ("peak_theta", "peak_y", "gap_closures"):
        np.testing.assert_array_equal(remote[q], local[q])


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc needed")
@pytest.mark.parametrize(
    ("sig", "status", "word"),
    [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated (SIGTERM)")],
)
def test_ctrl_c_stops_every_worker_with_one_line_and_resumes(tmp_path, sig, status, word):
    """Ctrl-C (SIGINT to the whole process group, as a terminal sends it) and SIGTERM (to the
    command alone, as ``kill`` or ``timeout`` send it) stop the same clean way."""
    argv = [
        sys.executable,
        "-m",
        "deckpound",
        "study",
        "variability",
        "saiidi-4span",
        "--cases",
        "400",
        "--workers",
        "2",
        "--no-progress",
        "-o",
        "out",
        "--set",
        "excitation.duration=4.0",
    ]
    proc = start_in_own_group(argv, tmp_path)  # as a terminal runs it
    rows = tmp_path / "out" / "cache" / "variability"
    workers = wait_for_rows(proc, rows)
    assert proc.poll() is None and len(workers) >= 2, "the study ended before the interrupt"
    if sig == signal.SIGINT:
        os.killpg(proc.pid, sig)
    else:
        os.kill(proc.pid, sig)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == status, err
    lines = err.splitlines()
    assert len(lines) == 1 and "Traceback" not in err + out, err
    assert lines[0].startswith(f"deckpound: {word}: study variability: ")
    assert "cached in" in lines[0] and "run the same command again to resume" in lines[0]
    assert not running(workers)  # every worker is gone
    # rows written whole: each a line of the row log, appended in one write
    cached = cached_rows(rows)
    assert cached >= 3
    assert (tmp_path / "out" / "INCOMPLETE").is_file()
    # resume: the same command computes only the missing cases
    done = subprocess.run(
        argv, cwd=tmp_path, capture_output=True, text=True, timeout=600, check=False
    )
    assert done.returncode == 0, done.stderr
    report = json.loads((tmp_path / "out" / "variability.json").read_text())
    assert report["from_cache"] == cached and report["computed"] == 400 - cached
    assert not (tmp_path / "out" / "INCOMPLETE").exists()
    assert not [p.name for p in rows.glob("*") if is_temporary(p.name)]  # none left behind
