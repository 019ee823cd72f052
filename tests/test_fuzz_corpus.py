"""The CLI fuzz corpus of issue 16: 0 tracebacks, 0 partial outputs, 0 silent nonsense.

The corpus (:mod:`tests._fuzz_corpus`, > 3,000 generated cases over scenes, overrides, output
paths, injected faults, engine steps, result folders, names and options) runs in-process
through ``deckpound.cli.main``; :mod:`tests._fuzz_run` classifies each outcome. The counts per
outcome are printed (``pytest -s`` shows them). A deterministic quick subset (~200 cases) runs
by default; the whole corpus with ``-m slow``. A small sample also runs as real processes,
where stdout can be ``/dev/full`` and stderr must hold exactly the one line (OpenSees's exit
chatter included).
"""

from __future__ import annotations

import collections
import os
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from _fuzz_corpus import generate, quick_subset
from _fuzz_run import BAD_OUTCOMES, OK_OUTCOMES, run_case

from deckpound.cli import main

CASES = generate()


@pytest.fixture(scope="module")
def result_dir(tmp_path_factory) -> Path:
    """A tiny finished run (the input of the export-vtk cases)."""
    out = tmp_path_factory.mktemp("fuzz-result") / "res"
    code = main(
        [
            "run",
            "saiidi-4span",
            "--set",
            "excitation.duration=0.3",
            "--set",
            "run.output_dt=0.01",
            "--engine",
            "opensees",
            "-o",
            str(out),
        ]
    )
    assert code == 0 and (out / "opensees.csv").is_file()
    return out


@pytest.fixture
def memory_cap():
    """Cap this process's address space while the corpus runs: a regression that makes some
    input explode in memory fails here (MemoryError: exit 3, a counted case) instead of
    summoning the machine's OOM killer."""
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    cap = 8 << 30
    if hard != resource.RLIM_INFINITY:
        cap = min(cap, hard)
    resource.setrlimit(resource.RLIMIT_AS, (cap, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def _run_corpus(cases, tmp_path: Path, result_dir: Path, title: str):
    counts: collections.Counter = collections.Counter()
    per_family: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)
    bad = []
    t0 = time.perf_counter()
    for i, case in enumerate(cases):
        outcome = run_case(case, tmp_path / f"c{i}", result_dir)
        counts[outcome.outcome] += 1
        per_family[case.family][outcome.outcome] += 1
        if outcome.outcome in BAD_OUTCOMES:
            bad.append(outcome)
    wall = time.perf_counter() - t0
    print(f"\n{title}: {len(cases)} cases in {wall:.0f} s")
    for name in OK_OUTCOMES + BAD_OUTCOMES:
        print(f"  {name:16s} {counts.get(name, 0)}")
    for fam, c in sorted(per_family.items()):
        print(f"  [{fam}] " + ", ".join(f"{k} {v}" for k, v in sorted(c.items())))
    return counts, bad


def _report(bad) -> str:
    return "\n".join(f"{b.outcome}: {b.case_id} (exit {b.code}): {b.detail}" for b in bad[:40])


def test_corpus_is_large_unique_and_has_a_quick_subset():
    assert len(CASES) >= 3000
    assert len({c.id for c in CASES}) == len(CASES)
    families = collections.Counter(c.family for c in CASES)
    assert set(families) == {
        "set",
        "file",
        "override",
        "path",
        "fault",
        "engine",
        "vtk",
        "name",
        "option",
        "script",
        "input",
        "stream",
    }
    quick = quick_subset(CASES)
    assert 150 <= len(quick) <= 230 and {c.family for c in quick} == set(families)


def test_classifier_catches_what_it_must(tmp_path, result_dir, monkeypatch):
    """The classifier is not blind: a traceback, a partial folder and nonsense are found."""
    from _fuzz_corpus import Case

    import deckpound.models.file_io as dio

    bug = Case(
        "probe:bug",
        "probe",
        (
            "run",
            "saiidi-4span",
            "--set",
            "excitation.duration=0.3",
            "--engine",
            "nonsmooth",
            "-o",
            "{tmp}/out",
        ),
        target="{tmp}/out",
        target_kind="dir",
        nonsense=True,
    )
    assert run_case(bug, tmp_path / "a", result_dir).outcome == "SILENT NONSENSE"
    monkeypatch.setattr(dio, "output_folder", _leaky_folder)
    leaky = Case(
        "probe:leak",
        "probe",
        bug.argv,
        fault="enospc-write:2",
        target="{tmp}/out",
        target_kind="dir",
    )
    assert run_case(leaky, tmp_path / "b", result_dir).outcome == "PARTIAL OUTPUT"
    monkeypatch.setattr("deckpound.cli._guarded_main", _raising_main)
    assert run_case(bug, tmp_path / "c", result_dir).outcome == "TRACEBACK"


def _raising_main(argv):
    raise ZeroDivisionError("escaped")


def _leaky_folder(path, command, field="--output"):
    import contextlib

    @contextlib.contextmanager
    def cm():
        Path(path).mkdir(parents=True, exist_ok=True)
        (Path(path) / "part.csv").write_text("t\n0\n")  # no marker, and a stray file
        yield Path(path)

    return cm()


def test_quick_corpus(tmp_path, result_dir, memory_cap):
    counts, bad = _run_corpus(quick_subset(CASES), tmp_path, result_dir, "quick corpus")
    assert not bad, _report(bad)
    assert counts["refused"] > 50 and counts["success"] > 20 and counts["I/O error"] > 10


@pytest.mark.slow
def test_full_corpus(tmp_path, result_dir, memory_cap):
    counts, bad = _run_corpus(CASES, tmp_path, result_dir, "full corpus")
    assert not bad, _report(bad)
    assert sum(counts.values()) == len(CASES)


# -- a sample as real processes -------------------------------------------------------------


def _deckpound(args, cwd, **kw):
    return subprocess.run(
        [sys.executable, "-m", "deckpound", *args],
        cwd=cwd,
        capture_output="stdout" not in kw,
        text=True,
        timeout=300,
        check=False,
        **kw,
    )


PROCESS_SAMPLE = [  # (argv, exit status, stderr lines)
    (
        [
            "run",
            "saiidi-4span",
            "--set",
            "excitation.duration=0.3",
            "--engine",
            "opensees",
            "-o",
            "out",
        ],
        0,
        0,
    ),
    (
        [
            "run",
            "saiidi-4span",
            "--set",
            "opensees.max_iterations=9223372036854775808",
            "--engine",
            "opensees",
            "-o",
            "out",
        ],
        2,
        1,
    ),
    (["run", "saiidi-4span", "--set", "opensees.dt=30", "--engine", "opensees", "-o", "out"], 2, 1),
    (
        [
            "run",
            "saiidi-4span",
            "--set",
            "excitation.duration=0.3",
            "--engine",
            "opensees",
            "-o",
            "/proc/deckpound-fuzz/out",
        ],
        3,
        1,
    ),
    (
        [
            "run",
            "saiidi-4span",
            "--set",
            "excitation.duration=0.3",
            "--engine",
            "opensees",
            "-o",
            "link",
        ],
        2,
        1,
    ),
    (["scene", "validate", "deep.toml"], 2, 1),
    (["compare", "saiidi-4span", "--scheduler", "foo", "-o", "out"], 2, 1),
    (["stress", "--quick", "--timeout", "nan"], 2, 1),
    (["export-vtk", "bad", "-o", "vtk"], 2, 1),
    (
        [
            "export",
            "saiidi-4span",
            "--set",
            "excitation.duration=0.3",
            "--format",
            "tcl",
            "-o",
            "/dev/full",
        ],
        2,  # a device as the script: its data folder would land in /dev (refused, one line)
        1,
    ),
]


@pytest.mark.parametrize(
    "argv,code,nlines", PROCESS_SAMPLE, ids=[" ".join(a[:2] + a[-1:]) for a, _, _ in PROCESS_SAMPLE]
)
def test_process_sample(tmp_path, argv, code, nlines):
    (tmp_path / "real").mkdir()
    os.symlink(tmp_path / "real", tmp_path / "link")
    (tmp_path / "deep.toml").write_text("v = " + "[" * 50_000 + "]" * 50_000 + "\n")
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "opensees.json").write_text('{"x":')
    (tmp_path / "bad" / "opensees.csv").write_text("t,a\n")
    p = _deckpound(argv, tmp_path)
    assert p.returncode == code, p.stderr
    assert len(p.stderr.splitlines()) == nlines, p.stderr  # OpenSees's exit line suppressed
    assert "Traceback" not in p.stderr + p.stdout
    assert not list((tmp_path / "real").iterdir())
    assert not (tmp_path / "out").exists() or code == 0


def test_process_stdout_to_dev_full(tmp_path):
    with open("/dev/full", "w") as full:
        p = _deckpound(
            ["scene", "show", "saiidi-4span"], tmp_path, stdout=full, stderr=subprocess.PIPE
        )
    assert p.returncode == 3
    assert p.stderr.splitlines() == [
        ("deckpound: error: cannot write the output to stdout: no space left on the device")
    ]


def test_process_sigint_exits_130_with_one_line(tmp_path):
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "deckpound",
            "run",
            "saiidi-4span",
            "--engine",
            "opensees",
            "--set",
            "opensees.dt=1e-4",
            "-o",
            "out",
        ],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    time.sleep(4.0)  # imports done, OpenSees stepping
    proc.send_signal(signal.SIGINT)
    _out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert err.splitlines() == ["deckpound: interrupted"]
    assert not (tmp_path / "out").exists()
