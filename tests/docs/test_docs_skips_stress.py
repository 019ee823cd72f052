"""docs/performance.md's skips and stability paragraphs are the renderings of the committed
``docs/results`` CSVs (tools/skips_stress.py, published by ``python tools/bench_tables.py skips``
and ``... stress``): re-rendered here, each must be the page's block character for character.
The sentences are checked on small tables."""

import numpy as np
import pandas as pd
import pytest
import skips_stress as rr
from docs_blocks import RESULTS, block_of

from deckpound.cli import main
from deckpound.compare.bench.skips import skip_failures


def _block(begin: str, end: str) -> str:
    block = block_of(rr.PAGE.read_text(encoding="utf-8"), begin, end)
    assert block is not None, f"{rr.PAGE.name} has no {begin.split(':')[0]} block"
    return block


def test_skips_block_is_the_rendering_of_the_committed_csvs():
    expected = rr.render_skips(*rr.load_skips(RESULTS))
    assert _block(rr.SKIPS_BEGIN, rr.SKIPS_END) == expected, (
        "the skips paragraph of docs/performance.md is stale: run `python tools/bench_tables.py`"
    )


def test_stress_block_is_the_rendering_of_the_committed_csv():
    expected = rr.render_stress(rr.load_stress(RESULTS))
    assert _block(rr.STRESS_BEGIN, rr.STRESS_END) == expected, (
        "the stability paragraph of docs/performance.md is stale: run "
        "`python tools/bench_tables.py`"
    )


def _skips(identical=True):
    rows = []
    for scene, k in (("a", 1.0), ("b", 1.5)):
        rows += [
            dict(scene=scene, skip="contact", speedup=1.3 * k, max_abs_diff=0.0, identical=True),
            dict(
                scene=scene,
                skip="decimate",
                speedup=1.2,
                max_abs_diff=0.0 if identical else 1e-9,
                identical=identical,
            ),
            dict(scene=scene, skip="geometry", speedup=1.4, max_abs_diff=5e-5, identical=False),
        ]
    steps = pd.DataFrame(
        [
            dict(scene="a", commit_cap="lifted", commit_step=0.01, where="free", steps=10, median=1.2e-3),
            dict(scene="a", commit_cap="lifted", commit_step=0.01, where="contact", steps=10, median=3.5e-4),
            dict(scene="b", commit_cap="lifted", commit_step=0.01, where="free", steps=10, median=1.3e-3),
            dict(scene="b", commit_cap="lifted", commit_step=0.01, where="contact", steps=0, median=np.nan),
            dict(scene="a", commit_cap="default", commit_step=1e-4, where="free", steps=10, median=9.4e-5),
            dict(scene="a", commit_cap="default", commit_step=1e-4, where="contact", steps=10, median=9.4e-5),
        ]
    )  # fmt: skip
    return pd.DataFrame(rows), steps


def test_skips_sentence_gives_ranges_and_says_when_a_skip_changed_a_result():
    text = rr.render_skips(*_skips())
    assert "contact laws skipped while every predicted gap is open 1.3–2×" in text
    assert "output decimation 1.2×" in text
    assert "(a model choice, not a skip: largest result difference 5.0e-05)" in text
    assert "Every skip gives results identical to the last bit." in text
    assert "1.2 ms between impacts and 0.35 ms in contact (1.3 ms on b, no contact)" in text
    assert "(`compliance.commit_step` = 0.1 ms), 0.094 ms out of contact" in text
    bad = rr.render_skips(*_skips(identical=False))
    assert "output decimation 1.2× (**results differ** on a, b)" in bad
    assert "**Some skip changed a result**" in bad and "identical to the last bit" not in bad


def test_flushed_subnormals_are_a_choice_whose_difference_must_stay_below_1e_250():
    skips, steps = _skips()
    row = dict(scene="a", skip="subnormals", speedup=1.3, identical=False)
    small = pd.concat([skips, pd.DataFrame([dict(row, max_abs_diff=1.8e-304)])])
    text = rr.render_skips(small, steps)
    assert "subnormal numbers flushed to zero 1.3× (a floating-point choice, not a skip: " in text
    assert "largest result difference 1.8e-304)" in text
    assert "Every skip gives results identical to the last bit." in text
    assert not len(skip_failures(small))
    big = pd.concat([skips, pd.DataFrame([dict(row, max_abs_diff=1e-12)])])
    assert "largest result difference 1.0e-12, **above 1e-250**)" in rr.render_skips(big, steps)
    assert list(skip_failures(big)["skip"]) == ["subnormals"]
    assert list(skip_failures(_skips(identical=False)[0])["skip"]) == ["decimate", "decimate"]


def _stress(extra=()):
    rows = [
        dict(engine=e, stiffness=k, dt=dt, status="success", finite=True,
             max_penetration=p, energy_error=ee, complementarity=c)
        for e, ee, c in (("opensees", np.nan, np.nan), ("compliance", 1e-12, np.nan),
                         ("nonsmooth", 1e-14, 1e-15))
        for k, dt, p in ((1e4, 1e-3, 0.018), (1e10, 1e-5, 1e-6))
    ]  # fmt: skip
    return pd.DataFrame(rows + list(extra))


def test_stress_sentence_counts_cells_and_names_the_worst():
    text = rr.render_stress(_stress())
    assert "2 cells × 3 engines (opensees, compliance, nonsmooth)" in text
    assert "contact stiffness 10000 … 1e10 kN/m × time step 1e-5 … 0.001 s" in text
    assert "all finished with finite output" in text
    assert "compliance 1.0e-12, nonsmooth 1.0e-14" in text
    assert "nonsmooth engine: 1.0e-15 m/s" in text
    assert "opensees 18 mm (stiffness = 10000, dt = 0.001)" in text
    failed = dict(engine="nonsmooth", stiffness=1e4, dt=1e-2, status="timeout", finite=False,
                  max_penetration=np.nan, energy_error=np.nan, complementarity=np.nan)  # fmt: skip
    bad = rr.render_stress(_stress([failed]))
    assert "1 did not finish with finite output: nonsmooth timeout" in bad


def test_tables_that_are_not_the_commands_csv_are_refused():
    skips, steps = _skips()
    with pytest.raises(ValueError, match="skips.csv has no column 'speedup'"):
        rr.render_skips(skips.drop(columns=["speedup"]), steps)
    with pytest.raises(ValueError, match="stress.csv is empty"):
        rr.render_stress(_stress().iloc[:0])


def test_publish_copies_the_measurement_and_writes_only_its_block(tmp_path):
    src = tmp_path / "run"
    src.mkdir()
    skips, steps = _skips()
    skips.to_csv(src / "skips.csv", index=False)
    steps.to_csv(src / "adaptive_steps.csv", index=False)
    page = tmp_path / "performance.md"
    page.write_text(f"intro\n{rr.SKIPS_BEGIN}\nold\n{rr.SKIPS_END}\noutro\n")
    rr.publish_skips(src, page, tmp_path / "results")
    assert page.read_text() == f"intro\n{rr.render_skips(skips, steps)}\noutro\n"
    assert (tmp_path / "results" / "skips.csv").is_file()


def test_stress_cli_has_no_docs_writer(capsys, tmp_path):
    code = main(["stress", "--write-readme", "README.md", "-o", str(tmp_path / "o")])
    assert code == 2 and "--write-readme" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
