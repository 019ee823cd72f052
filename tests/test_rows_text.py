"""Result CSV text on two cores (models/_rows_text.py): the same bytes as on one."""

import os

import numpy as np

from deckpound.models import _rows_text
from deckpound.models.result import Result


def _result(n_rows: int) -> Result:
    rng = np.random.default_rng(3)
    cols = {"t": np.arange(n_rows) * 0.005}
    cols.update({f"gap_c{i}": rng.standard_normal(n_rows) * 10.0**-i for i in range(1, 5)})
    cols.update({f"x{i}": rng.standard_normal(n_rows) for i in range(20)})
    cols["x0"][:6] = [np.nan, np.inf, -np.inf, -0.0, 1e-300, 3.0]
    return Result(engine="e", columns=cols, meta={})


def test_parallel_text_is_byte_identical_and_reads_back(tmp_path):
    r = _result(4001)
    assert r.csv_bytes(parallel=True) == r.csv_bytes()
    r.write(tmp_path, parallel=True)
    back = Result.read(tmp_path, "e")
    for k, v in r.columns.items():
        np.testing.assert_array_equal(back.columns[k], v)


def test_small_tables_and_failed_children_fall_back(monkeypatch):
    r = _result(10)
    assert r.csv_bytes(parallel=True) == r.csv_bytes()  # below the threshold: no fork
    big = _result(4001)
    expected = big.csv_bytes()
    real_fork = os.fork

    def fork_and_fail():
        pid = real_fork()
        if pid == 0:
            os._exit(3)  # a child that dies before writing anything
        return pid

    monkeypatch.setattr(_rows_text.os, "fork", fork_and_fail)
    assert big.csv_bytes(parallel=True) == expected
