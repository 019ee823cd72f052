"""Result CSV text (models/_rows_text.py): every value as ``repr(float)`` writes it, whether
``orjson`` writes it (the default) or ``repr`` itself (without ``orjson``)."""

import sys

import numpy as np
import pytest

from deckpound.models import _rows_text
from deckpound.models.result import Result, rounded_time


def _repr_text(table: np.ndarray) -> str:
    """The reference: Python's repr of every value, one line per row."""
    return "".join(",".join(map(repr, row)) + "\n" for row in table.astype(float).tolist())


def _every_kind_of_double() -> np.ndarray:
    """Random mantissas over the whole exponent range (subnormals to 1e308), both signs, the
    powers of ten and their neighbours, the edges of the decades where the two writers differ
    (1e-10, 1e-5, 1e-4, 1e16), integers, ±0, NaN and ±∞; one column."""
    rng = np.random.default_rng(7)
    n = 200_000
    random = rng.uniform(1.0, 10.0, n) * 10.0 ** rng.integers(-323, 308, n).astype(float)
    random *= rng.choice([-1.0, 1.0], n)
    powers = 10.0 ** np.arange(-323, 309).astype(float)
    near = np.concatenate([np.nextafter(powers, 0.0), np.nextafter(powers, np.inf)])
    decades = np.concatenate(
        [rng.uniform(1.0, 10.0, 2000) * 10.0**e for e in (-11, -10, -9, -6, -5, -4, -3, 15, 16)]
    )
    special = [0.0, -0.0, np.nan, np.inf, -np.inf, 5e-324, 2.2250738585072014e-308, 1.0, 3.0]
    special += [123.0, 1e15, 1e16, 1.5e16, 9.999999999999999e15, 1.7976931348623157e308]
    special += [1e-5, 3e-5, 1.0000000000000001e-10, 9.999999999999999e-11, 0.00009999999999999999]
    values = np.concatenate(
        [random, powers, -powers, near, decades, -decades, special, rng.integers(-9, 9, 500)]
    )
    return values.reshape(-1, 1)


def _result(n_rows: int) -> Result:
    rng = np.random.default_rng(3)
    cols = {"t": np.arange(n_rows) * 0.005}
    cols.update({f"gap_c{i}": rng.standard_normal(n_rows) * 10.0**-i for i in range(1, 5)})
    cols.update({f"x{i}": rng.standard_normal(n_rows) * 10.0 ** -(2 * i) for i in range(20)})
    cols["x0"][:6] = [np.nan, np.inf, -np.inf, -0.0, 1e-300, 3.0]
    return Result(engine="e", columns=cols, meta={})


def test_orjson_writes_repr_text_for_every_kind_of_double():
    pytest.importorskip("orjson")
    values = _every_kind_of_double()
    assert _rows_text.format_array(values) == _repr_text(values)
    wide = values[: values.shape[0] // 8 * 8].reshape(-1, 8)  # several columns per row
    assert _rows_text.format_array(wide) == _repr_text(wide)


def test_orjson_writes_repr_text_for_engine_results():
    pytest.importorskip("orjson")
    from deckpound.compare.engines import run_engine
    from deckpound.models.scene_io import load_scene

    scene = load_scene("saiidi-4span", ["run.duration=2.0"])
    for engine in ("compliance", "nonsmooth"):
        r = run_engine(engine, scene)
        table = np.column_stack(list(r.columns.values()))
        assert _rows_text.format_array(table) == _repr_text(table), engine


def test_without_orjson_the_repr_text_is_written(monkeypatch):
    r = _result(4001)
    expected = r.csv_bytes()
    monkeypatch.setitem(sys.modules, "orjson", None)  # import orjson now raises ImportError
    assert r.csv_bytes() == expected
    table = np.column_stack(list(r.columns.values()))
    assert _rows_text.format_array(table) == _repr_text(table)


def test_shapes_without_values():
    assert _rows_text.format_array(np.empty((0, 0))) == ""
    assert _rows_text.format_array(np.empty((0, 3))) == ""
    assert _rows_text.format_array(np.array([[1.5]])) == "1.5\n"


def test_written_results_read_back_bit_for_bit(tmp_path):
    """Every column reads back bit for bit; the time column as written, with the round-off of
    k·Δt taken out (:func:`deckpound.models.result.rounded_time`), which moves no time by more
    than a few units in the last place."""
    r = _result(4001)
    r.write(tmp_path)
    back = Result.read(tmp_path, "e")
    for k, v in r.columns.items():
        expected = rounded_time(v) if k == "t" else v
        np.testing.assert_array_equal(back.columns[k], expected)
    t = r.columns["t"]
    assert np.all(np.abs(back.columns["t"] - t) <= 8 * np.spacing(np.abs(t)))
