"""Comparison layer: alignment keeps peaks and impulse; metrics on hand-computed cases (issue 6)."""

from __future__ import annotations

import numpy as np
import pytest

from deckpound.compare.align import align, bin_average, bin_sum, common_time_base, long_table
from deckpound.compare.metrics import compare_pair, correlation, nrmse, peak, residual, time_of_peak
from deckpound.models.result import Result, closure_times


def _res(engine, t, **cols):
    return Result(engine=engine, columns={"t": t, **cols})


def test_common_base_finest_step_earliest_end():
    a = _res("a", np.arange(0, 2.0001, 0.01), x=np.zeros(201))
    b = _res("b", np.arange(0, 1.5001, 0.005), x=np.zeros(301))
    t = common_time_base({"a": a, "b": b})
    assert t[1] == pytest.approx(0.005) and t[-1] == pytest.approx(1.5)


def test_downsampling_keeps_peaks_exactly():
    t = np.arange(0, 1.0001, 0.001)
    x = np.sin(2 * np.pi * 3 * t) + np.where(np.abs(t - 0.5123) < 1e-9, 5.0, 0.0)
    r = _res("fine", t, deck_theta=x)
    coarse = _res("coarse", np.arange(0, 1.0001, 0.01), deck_theta=np.zeros(101))
    out = align({"fine": r, "coarse": coarse}, dt=0.01)
    assert out["fine"]["deck_theta"].abs().max() == pytest.approx(np.abs(x).max(), abs=0)


def test_upsampling_is_linear_interpolation():
    t = np.arange(0, 1.0001, 0.1)
    r = _res("a", t, deck_x=3 * t + 1)
    out = align({"a": r}, dt=0.01)
    np.testing.assert_allclose(out["a"]["deck_x"], 3 * out["a"]["t"] + 1, atol=1e-12)


def test_force_bins_conserve_impulse():
    """A short contact pulse on a fine base keeps its impulse on a coarse base."""
    t = np.arange(0, 1.0 + 1e-12, 1e-4)
    f = np.where((t > 0.3012) & (t < 0.3047), 1e6 * np.sin(np.pi * (t - 0.3012) / 0.0035), 0.0)
    impulse = np.trapezoid(f, t)
    tc = np.arange(0, 1.0 + 1e-12, 0.005)
    avg = bin_average(t, f, tc)
    assert np.sum(avg) * 0.005 == pytest.approx(impulse, rel=1e-9)


def test_impulse_columns_are_summed():
    t = np.arange(0, 1.0 + 1e-12, 0.001)
    p = np.zeros_like(t)
    p[[100, 101, 555]] = [1.0, 2.0, 4.0]
    s = bin_sum(t, p, np.arange(0, 1.0 + 1e-12, 0.01))
    assert s.sum() == pytest.approx(7.0) and s[10] == pytest.approx(3.0)


def test_metrics_hand_computed():
    r = np.array([0.0, 1.0, -2.0, 1.0, 0.0])
    x = np.array([0.0, 1.0, -1.0, 1.0, 0.0])
    assert peak(r) == 2.0 and time_of_peak(np.arange(5.0), r) == 2.0
    assert nrmse(x, r) == pytest.approx(np.sqrt(1 / 5) / 2)
    assert correlation(r, r) == pytest.approx(1.0)
    assert correlation(-r, r) == pytest.approx(-1.0)
    assert residual(np.concatenate([np.zeros(98), [2.0, 2.0]])) == pytest.approx(2.0)
    g = np.array([0.01, 0.0, -0.001, 0.002, -0.0001, 0.003])
    np.testing.assert_array_equal(closure_times(np.arange(6.0), g), [1.0, 4.0])


def test_compare_pair_and_long_table():
    t = np.linspace(0, 1, 101)
    a = _res("a", t, deck_theta=np.sin(6 * t), deck_y=t)
    b = _res("b", t, deck_theta=0.5 * np.sin(6 * t), deck_y=t)
    al = align({"a": a, "b": b})
    m = compare_pair(b, a, al["b"], al["a"], ["deck_theta", "deck_y"])
    row = m.set_index("quantity").loc["deck_theta"]
    assert row["peak_ratio"] == pytest.approx(0.5) and row["correlation"] == pytest.approx(1.0)
    assert m.set_index("quantity").loc["deck_y", "nrmse"] == 0.0
    lt = long_table(al)
    assert set(lt.columns) == {"engine", "t", "quantity", "value"} and len(lt) == 2 * 2 * 101
