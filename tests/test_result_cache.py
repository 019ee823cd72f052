"""The result cache under damage and concurrency, and workers that die with their parent
(issue 16: 16 of 400 concurrent writes and 33 reads raised; a truncated entry changed a study
table silently; killed parents left workers writing for 20 s)."""

from __future__ import annotations

import json
import multiprocessing as mp
import os
import signal
import subprocess
import sys
import textwrap
import time
import warnings

import numpy as np
import pytest
from _process_helpers import alive

from deckpound.compare.result_cache import MANIFEST, ResultCache
from deckpound.compare.result_cache import ResultCache as ReExported
from deckpound.models.result import Result

KEYS = [f"{i:064x}" for i in range(1, 5)]


def _result(seed: int, n: int = 200) -> Result:
    rng = np.random.default_rng(seed)
    return Result(
        engine="compliance",
        columns={"t": np.arange(n) * 0.01, "deck_theta": rng.normal(size=n)},
        meta={"seed": seed},
    )


def test_reexported_from_cases():
    assert ReExported is ResultCache


def test_put_get_round_trip_with_checksums(tmp_path):
    cache = ResultCache(tmp_path)
    assert cache.get(KEYS[0], "compliance") is None and cache.misses == 1
    cache.put(KEYS[0], _result(1))
    got = cache.get(KEYS[0], "compliance")
    assert cache.hits == 1
    np.testing.assert_array_equal(got["deck_theta"], _result(1)["deck_theta"])
    manifest = json.loads((tmp_path / KEYS[0] / MANIFEST).read_text())
    assert set(manifest["files"]) == {"compliance.csv", "compliance.json"}
    assert all(len(f["sha256"]) == 64 for f in manifest["files"].values())
    assert sorted(p.name for p in tmp_path.iterdir()) == [KEYS[0]]  # no temporary left


@pytest.mark.parametrize(
    "damage",
    ["truncate-csv", "edit-csv", "truncate-json", "manifest-sha", "manifest-junk", "drop-csv"],
)
def test_a_damaged_entry_is_recomputed_with_a_warning(tmp_path, damage):
    cache = ResultCache(tmp_path)
    cache.put(KEYS[0], _result(1))
    entry = tmp_path / KEYS[0]
    csv, js, man = entry / "compliance.csv", entry / "compliance.json", entry / MANIFEST
    if damage == "truncate-csv":
        csv.write_bytes(csv.read_bytes()[:-100])  # a crash in the middle of a write
    elif damage == "edit-csv":
        csv.write_text(csv.read_text().replace("0.01", "0.02", 1))  # same size, other numbers
    elif damage == "truncate-json":
        js.write_bytes(js.read_bytes()[:10])
    elif damage == "manifest-sha":
        m = json.loads(man.read_text())
        m["files"]["compliance.csv"]["sha256"] = "0" * 64
        man.write_text(json.dumps(m))
    elif damage == "manifest-junk":
        man.write_text("{not json")
    else:
        csv.unlink()
    with pytest.warns(UserWarning, match="damaged.*recomputing"):
        assert cache.get(KEYS[0], "compliance") is None
    assert cache.corrupt == 1 and cache.misses == 1
    cache.put(KEYS[0], _result(2))  # the recomputed result replaces the damaged entry
    np.testing.assert_array_equal(
        cache.get(KEYS[0], "compliance")["deck_theta"], _result(2)["deck_theta"]
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == [KEYS[0]]


def test_an_entry_without_manifest_is_a_silent_miss_and_replaced(tmp_path):
    """Entries of the earlier cache format (no checksums) are recomputed, not trusted."""
    _result(1).write(tmp_path / KEYS[0])
    cache = ResultCache(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert cache.get(KEYS[0], "compliance") is None
    cache.put(KEYS[0], _result(1))
    assert cache.get(KEYS[0], "compliance") is not None


def test_a_put_that_cannot_write_warns_and_leaves_nothing(tmp_path, monkeypatch):
    import deckpound.models.file_io as dio

    def full(fd, data, **_):
        raise OSError(28, "No space left on device")

    cache = ResultCache(tmp_path)
    monkeypatch.setattr(dio, "_write_fd", full)
    with pytest.warns(UserWarning, match="could not store a result"):
        cache.put(KEYS[0], _result(1))
    assert list(tmp_path.iterdir()) == []


def _hammer(args):
    """Worker: mixed puts and gets on a few keys; returns (errors, bad reads, reads)."""
    folder, worker, ops = args
    cache = ResultCache(folder)
    expected = {s: _result(s)["deck_theta"] for s in range(4)}
    errors, bad, reads = [], 0, 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a damaged-entry warning would be a failure here
        for i in range(ops):
            key = KEYS[(worker + i) % len(KEYS)]
            seed = (worker * 7 + i) % 4
            try:
                if i % 2:
                    cache.put(key, _result(seed))
                else:
                    got = cache.get(key, "compliance")
                    reads += 1
                    if got is not None and not any(
                        np.array_equal(got["deck_theta"], v) for v in expected.values()
                    ):
                        bad += 1
            except BaseException as err:
                errors.append(f"{type(err).__name__}: {err}")
    return errors, bad, reads


def test_concurrent_puts_and_gets_never_raise(tmp_path):
    """8 processes x 100 operations on 4 keys: 400 writes and 400 reads at once."""
    n_workers, ops = 8, 100
    with mp.get_context("fork").Pool(n_workers) as pool:
        out = pool.map(_hammer, [(str(tmp_path), w, ops) for w in range(n_workers)])
    errors = [e for errs, _, _ in out for e in errs]
    assert not errors, errors[:5]
    assert sum(b for _, b, _ in out) == 0  # every read is whole: one of the stored results
    assert sum(r for _, _, r in out) == n_workers * ops // 2
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(KEYS)  # no temporaries left
    cache = ResultCache(tmp_path)
    assert all(cache.get(k, "compliance") is not None for k in KEYS)


PARENT = textwrap.dedent("""
    import os, sys, time
    from deckpound.compare import _workers
    from deckpound.compare.cases import map_parallel

    if sys.argv[2] == "watchdog-only":
        _workers._set_pdeathsig = lambda: False

    def work(folder):
        open(os.path.join(folder, str(os.getpid())), "w").close()
        time.sleep(120)

    map_parallel([1, 2], lambda i: (sys.argv[1],), work, lambda *a: None, 2, None)
""")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc needed")
@pytest.mark.parametrize("mode", ["prctl", "watchdog-only"])
def test_workers_die_with_their_parent(tmp_path, mode):
    script = tmp_path / "parent.py"
    script.write_text(PARENT)
    pids_dir = tmp_path / "pids"
    pids_dir.mkdir()
    parent = subprocess.Popen([sys.executable, str(script), str(pids_dir), mode])
    try:
        deadline = time.time() + 60
        while len(list(pids_dir.iterdir())) < 2 and time.time() < deadline:
            time.sleep(0.1)
        workers = [int(p.name) for p in pids_dir.iterdir()]
        assert len(workers) == 2 and all(alive(w) for w in workers)
        os.kill(parent.pid, signal.SIGKILL)
        parent.wait(10)
        t0 = time.time()
        while any(alive(w) for w in workers) and time.time() - t0 < 5:
            time.sleep(0.05)
        assert not any(alive(w) for w in workers), f"workers alive {time.time() - t0:.1f} s later"
    finally:
        parent.kill()
        for p in pids_dir.iterdir():
            try:
                os.kill(int(p.name), signal.SIGKILL)
            except ProcessLookupError:
                pass


def test_changing_one_engines_settings_reruns_only_that_engine(tmp_path):
    """Issue 11: the cache key is the physics plus that engine's settings, so changing
    nonsmooth.h re-runs the nonsmooth case and serves the other engines from the cache."""
    from deckpound.compare.cases import Case, run_cases
    from deckpound.compare.result_cache import ResultCache
    from deckpound.models.scene_io import load_scene

    sc = load_scene("saiidi-4span", ["run.duration=0.2"])
    engines = ("opensees", "compliance", "nonsmooth")
    run_cases(
        [Case(e, e, sc) for e in engines], cache=ResultCache(tmp_path), workers=1, progress=False
    )
    changed = load_scene("saiidi-4span", ["run.duration=0.2", "nonsmooth.h=5e-4"])
    cache = ResultCache(tmp_path)
    run_cases([Case(e, e, changed) for e in engines], cache=cache, workers=1, progress=False)
    assert cache.by_engine == {"opensees": [1, 0], "compliance": [1, 0], "nonsmooth": [0, 1]}
