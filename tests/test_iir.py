"""The numpy Butterworth high-pass (models/iir.py) gives scipy.signal's numbers bit for bit,
so the synthetic record and filtered records do not need scipy.signal (1 s of imports)."""

import subprocess
import sys

import numpy as np
import pytest
import scipy.signal

from deckpound.models import iir


@pytest.mark.parametrize("wn", [1e-6, 5e-3, 0.05, 0.5, 0.95])
@pytest.mark.parametrize("order", [2, 4, 8])
def test_design_and_filter_equal_scipy_bitwise(wn, order, monkeypatch):
    sos = iir.butter_highpass_sos(order, wn)
    assert np.array_equal(sos, scipy.signal.butter(order, wn, btype="highpass", output="sos"))
    x = np.random.default_rng(order).standard_normal(2000)
    monkeypatch.delitem(sys.modules, "scipy.signal")  # the pure numpy path
    monkeypatch.setattr(iir, "_CALLS", [-(10**9)])  # and no switch to scipy on the way
    mine = iir.sosfiltfilt(sos, x)
    monkeypatch.undo()
    assert np.array_equal(mine, scipy.signal.sosfiltfilt(sos, x))
    assert np.array_equal(iir.sosfilt_zi(sos), scipy.signal.sosfilt_zi(sos))


def test_refuses_what_it_cannot_design():
    for order, wn in ((3, 0.1), (4, 0.0), (4, 1.0)):
        with pytest.raises(ValueError):
            iir.butter_highpass_sos(order, wn)
    with pytest.raises(ValueError):
        iir.sosfiltfilt(iir.butter_highpass_sos(4, 0.1), np.zeros(10))


def test_synthetic_record_needs_no_scipy_signal():
    code = (
        "import sys; from deckpound.models.scene_io import load_scene; "
        "from deckpound.models.excitation import support_motion; "
        "support_motion(load_scene('saiidi-4span')); "
        "print(sorted(m for m in ('scipy.signal', 'scipy.linalg', 'pandas') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_a_long_sweep_switches_to_scipy_with_the_same_bits():
    code = (
        "import sys, numpy as np; from deckpound.models import iir\n"
        "sos = iir.butter_highpass_sos(4, 0.01)\n"
        "x = np.random.default_rng(1).standard_normal(500)\n"
        "outs, seen = [], []\n"
        "for _ in range(iir.SCIPY_AFTER + 2):\n"
        "    seen.append('scipy.signal' in sys.modules); outs.append(iir.sosfiltfilt(sos, x))\n"
        "print(seen.index(True), all(np.array_equal(o, outs[0]) for o in outs))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    from deckpound.models.iir import SCIPY_AFTER

    assert out.stdout.split() == [str(SCIPY_AFTER), "True"]


def test_a_sweep_imports_scipy_signal_at_its_start_not_mid_sweep():
    """Issue 33, item 4: a sweep pays scipy.signal's import before its first case (in process,
    and in the pool's workers, forked after it; a scope's pool forked by a small map before is
    replaced), instead of stalling at its 16th record."""
    import subprocess
    import sys

    code = (
        "import sys\n"
        "from deckpound.compare.cases import map_parallel\n"
        "def loaded(i): return 'scipy.signal' in sys.modules\n"
        "seen = {}\n"
        "for workers in (1, 2):\n"
        "    out = []\n"
        "    map_parallel(list(range(20)), lambda i: (i,), loaded, lambda i, v: out.append(v),"
        " workers, None)\n"
        "    seen[workers] = all(out)\n"
        "from deckpound.compare.pool import pool_scope\n"
        "with pool_scope():\n"
        "    map_parallel([0, 1, 2], lambda i: (i,), loaded, lambda i, v: None, 2, None)\n"
        "    out = []\n"
        "    map_parallel(list(range(20)), lambda i: (i,), loaded, lambda i, v: out.append(v),"
        " 2, None)\n"
        "    seen['scope'] = all(out)\n"
        "print(seen)\n"
    )
    cp = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True
    )
    assert cp.stdout.strip() == "{1: True, 2: True, 'scope': True}", cp.stdout + cp.stderr


@pytest.mark.parametrize("compiled", [True, False])
def test_rows_filter_as_they_do_alone(compiled, monkeypatch):
    """Rows of a 2-D array are filtered as each one alone, with scipy.signal's compiled
    recursion and with the numpy one, and as scipy.signal.sosfiltfilt filters them."""
    sos = iir.butter_highpass_sos(4, 0.002)
    x = np.random.default_rng(2).standard_normal((3, 1500))
    expected = [scipy.signal.sosfiltfilt(sos, row) for row in x]
    if not compiled:
        monkeypatch.delitem(sys.modules, "scipy.signal")
        monkeypatch.setattr(iir, "_CALLS", [-(10**9)])
    rows = iir.sosfiltfilt(sos, x)
    alone = [iir.sosfiltfilt(sos, row) for row in x]
    monkeypatch.undo()
    for i in range(3):
        assert np.array_equal(rows[i], expected[i])
        assert np.array_equal(alone[i], expected[i])


def test_designs_are_remembered_but_not_shared():
    """The remembered design is handed out as a copy: changing it changes no later design."""
    sos = iir.butter_highpass_sos(4, 0.01)
    sos[0, 0] = 123.0
    again = iir.butter_highpass_sos(4, 0.01)
    assert again[0, 0] != 123.0
    assert np.array_equal(again, scipy.signal.butter(4, 0.01, btype="highpass", output="sos"))


@pytest.mark.parametrize("compiled", [True, False])
def test_a_silent_start_gives_scipys_bits(compiled, monkeypatch):
    """Signals that start with exact zeros (the pads of a filtered record), a -0.0 inside
    them, all zero, and a filter whose sections have b0, b2 < 0 (where zeros need not stay
    +0.0): every bit, the signs of zeros included, as scipy.signal.sosfiltfilt."""
    rng = np.random.default_rng(4)
    butter = iir.butter_highpass_sos(4, 0.003)
    flipped = butter.copy()
    flipped[0, :3] *= -1.0
    x = rng.standard_normal((4, 900))
    x[:, :300] = 0.0
    x[1, 150] = -0.0
    x[2] = 0.0
    x[3, :2] = 0.0
    for sos in (butter, flipped):
        expected = np.array([scipy.signal.sosfiltfilt(sos, row) for row in x])
        if not compiled:
            monkeypatch.delitem(sys.modules, "scipy.signal")
            monkeypatch.setattr(iir, "_CALLS", [-(10**9)])
        together = iir.sosfiltfilt(sos, x[:3])  # a common silent start of 300 + 15 samples
        alone = [iir.sosfiltfilt(sos, row) for row in x]
        monkeypatch.undo()
        assert np.array_equal(together.view(np.uint64), expected[:3].view(np.uint64))
        for i, row in enumerate(alone):
            assert np.array_equal(row.view(np.uint64), expected[i].view(np.uint64))
