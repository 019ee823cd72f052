"""A re-run of ``deckpound paper`` into the same folder reuses the figures whose inputs are
unchanged (issue 32, item 7): every figure the second time; after one changed setting only the
figures that draw results it changes; a damaged or missing figure file is drawn again."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from deckpound.compare.report.figure_cache import (
    MANIFEST_NAME,
    FigureManifest,
    fingerprint,
    reusable,
    reuse_figures,
)
from deckpound.compare.report.paper import run_paper
from deckpound.models.result import Result
from deckpound.models.scene_io import load_scene, modified

TINY = [
    "excitation.duration=1.0",
    "run.output_dt=0.01",
    "opensees.dt=0.001",
    "compliance.dt=0.001",
    "nonsmooth.h=0.001",
    "sequence.pgas=[0.5, 1.0]",
]

CALLS: list[str] = []


@reusable
def line_figure(values, path, label="", formats=()):
    """A stand-in figure: writes its inputs' text (and counts its calls)."""
    CALLS.append(path.name)
    path.write_text(f"{label} {np.asarray(values).tolist()}")
    return [path]


def test_a_figure_is_drawn_again_exactly_when_an_input_or_its_file_changes(tmp_path):
    manifest = tmp_path / MANIFEST_NAME
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    CALLS.clear()

    def run(values_b, label_b="b"):
        with reuse_figures(manifest) as m:
            line_figure(np.arange(3.0), a, label="a")
            line_figure(values_b, b, label=label_b)
        return [p.name for p in m.drawn], [p.name for p in m.reused]

    assert run(np.arange(4.0)) == (["a.png", "b.png"], [])
    assert run(np.arange(4.0)) == ([], ["a.png", "b.png"])
    assert run(np.arange(4.0) + 1e-12) == (["b.png"], ["a.png"])  # one changed array element
    assert run(np.arange(4.0) + 1e-12, label_b="c") == (["b.png"], ["a.png"])  # a keyword
    assert run(np.arange(4.0, dtype=np.float32) + 1e-12) == (["b.png"], ["a.png"])  # dtype
    a.write_text("damaged")
    assert run(np.arange(4.0, dtype=np.float32)) == (["a.png", "b.png"], [])
    b.unlink()
    assert run(np.arange(4.0, dtype=np.float32)) == (["b.png"], ["a.png"])
    with reuse_figures(manifest, reuse=False) as m:  # --redraw
        line_figure(np.arange(3.0), a, label="a")
    assert m.drawn == [a] and not m.reused
    manifest.write_text("{not json")  # an unreadable manifest: everything is drawn again
    assert run(np.arange(4.0, dtype=np.float32)) == (["a.png", "b.png"], [])
    n = len(CALLS)
    line_figure(np.arange(3.0), a, label="a")  # outside reuse_figures: always drawn
    assert len(CALLS) == n + 1


def test_the_fingerprint_reads_results_tables_and_scenes_but_not_timings():
    scene = load_scene("saiidi-4span", TINY)
    t = np.linspace(0.0, 1.0, 11)
    r1 = Result("compliance", {"t": t, "deck_theta": np.sin(t)}, {"wall_time": 1.0})
    r2 = Result("compliance", {"t": t, "deck_theta": np.sin(t)}, {"wall_time": 2.0})
    r3 = Result("compliance", {"t": t, "deck_theta": np.sin(t) * (1 + 1e-15)}, {})
    table = pd.DataFrame({"case": ["a", "b"], "peak": [1.0, 2.0]})

    def key(result=r1, frame=table, sc=scene):
        return fingerprint(line_figure, {"results": {"x": result}, "table": frame, "scene": sc})

    assert key() == key(result=r2)  # the run's timing is not drawn
    assert key() != key(result=r3)
    assert key() != key(frame=table.assign(peak=[1.0, 2.5]))
    assert key() != key(frame=table.assign(case=["a", "c"]))
    assert key() == key(frame=table.assign(wall_time=[0.1, 0.2], cached=[True, False]))
    assert key() != key(sc=modified(scene, "deck.mass=300.0"))
    # an engine setting reaches a figure only through the results it draws
    assert key() == key(sc=modified(scene, "compliance.rtol=1e-7"))
    assert fingerprint(line_figure, {"x": object()}) is None  # unreadable: always drawn


def test_the_paper_loads_matplotlib_only_to_draw():
    """A paper whose figures are all reused never draws, so importing it must not load
    matplotlib (the figure functions import it when they draw)."""
    code = "import sys, deckpound.compare.report.paper; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def _figure_files(out):
    return {p.name: (p.stat().st_ino, p.stat().st_mtime_ns) for p in (out / "figures").iterdir()}


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """A tiny paper (OpenSees sequence, so no IDA section; two studies) run twice into the same
    folder."""
    out = tmp_path_factory.mktemp("paper")
    scene = load_scene("saiidi-4span", TINY)
    kwargs = dict(
        quick=True,
        workers=1,
        studies=("stiffness", "law"),
        progress=False,
        engines=("opensees",),
        reference="opensees",
    )
    run_paper(scene, out, **kwargs)
    first = _figure_files(out)
    first_bytes = {n: (out / "figures" / n).read_bytes() for n in first}
    md = run_paper(scene, out, **kwargs)
    return out, scene, kwargs, first, first_bytes, md


def test_a_second_run_reuses_every_figure(folder):
    out, _, _, first, _, md = folder
    assert len(first) >= 10
    assert _figure_files(out) == first  # no file rewritten: same inodes and mtimes
    manifest = FigureManifest(out / MANIFEST_NAME)
    assert {p.split("/")[-1] for p in manifest.entries} == set(first)
    assert f"This run drew 0 figures and reused {len(first)} whose" in md.read_text()


def test_a_changed_setting_or_file_redraws_exactly_the_figures_it_touches(folder):
    """compliance.rtol is read by the adaptive integrator only: of the figures, only the law
    study's (its cases run adaptive) draw results it changes; the stiffness study's compliance
    cases run again (their cache key changed) but give the same columns. A damaged figure file
    and a deleted one are drawn again, byte-identical to their first draw."""
    out, scene, kwargs, first, first_bytes, _ = folder
    figs = out / "figures"
    (figs / "peak_rotation_vs_pga.png").write_bytes(b"\x89PNG damaged")
    (figs / "run1_histories.png").unlink()
    md = run_paper(modified(scene, "compliance.rtol=1e-4"), out, **kwargs)
    now = _figure_files(out)
    redrawn = {n for n in first if now[n] != first[n]}
    assert redrawn == {
        "study_law_run2.png",
        "study_law_virgin.png",
        "peak_rotation_vs_pga.png",
        "run1_histories.png",
    }
    for name in ("peak_rotation_vs_pga.png", "run1_histories.png"):
        assert (figs / name).read_bytes() == first_bytes[name]
    assert f"This run drew 4 figures and reused {len(first) - 4} whose" in md.read_text()
