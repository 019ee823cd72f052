"""Zero-phase Butterworth high-pass filtering in numpy alone (no ``scipy.signal``).

Importing ``scipy.signal`` costs 0.6–1.7 s, more than a whole compliance run; the synthetic
generator and the records' ``processing = highpass`` need one filter of it. This module is that
filter, written with the same arithmetic as scipy, step for step, so that its output is the
same to the last bit (``tests/test_iir.py`` checks it against scipy):

* :func:`butter_highpass_sos` — ``scipy.signal.butter(order, wn, "highpass", output="sos")``:
  analogue prototype poles, high-pass transform, bilinear transform, then second-order
  sections with the pole closest to the unit circle last and the gain in the first section
  (scipy's ``zpk2sos`` with ``pairing="nearest"``), for an even order;
* :func:`sosfiltfilt` — ``scipy.signal.sosfiltfilt(sos, x)`` for 1-D ``x`` (or each row of a
  2-D ``x``): odd extension of 3·(2·sections + 1) samples at both ends, steady-state initial
  conditions (``sosfilt_zi``), the direct-form-II-transposed recursion forwards and
  backwards (the forward pass skipping a start that is exactly zero, which it would leave
  at zero).

The design and the initial conditions are computed once per filter and kept.

The recursion runs as a Python loop over plain floats (0.3–0.7 µs per sample and section,
~20 ms for a 20 s synthetic component); where ``scipy.signal`` is loaded already its compiled
recursion is used — the same bits, 6× faster — and a process that has filtered
:data:`SCIPY_AFTER` signals outside a sweep (a loop of ``dp.run`` calls) imports it for the rest;
a sweep imports it at its start (:func:`load_compiled_filter`).
"""

from __future__ import annotations

import functools
import math
import sys

import numpy as np

__all__ = ["butter_highpass_sos", "load_compiled_filter", "sosfilt_zi", "sosfiltfilt"]

#: signals filtered in pure Python before this process imports scipy.signal for the rest (a
#: sweep's worker: its 0.5–1 s import is then paid once for hundreds of records)
SCIPY_AFTER = 16
_CALLS = [0]


def butter_highpass_sos(order: int, wn: float) -> np.ndarray:
    """Second-order sections of a digital Butterworth high-pass of even ``order`` at ``wn``
    (a fraction of the Nyquist frequency, 0 < wn < 1); shape (order // 2, 6). Designed once
    per (order, wn) (every record of a sweep asks for the same filter); each call returns its
    own copy."""
    return _butter_highpass_design(order, wn).copy()


@functools.lru_cache(maxsize=32, typed=True)
def _butter_highpass_design(order: int, wn: float) -> np.ndarray:
    """:func:`butter_highpass_sos`, remembered (read-only)."""
    if order < 2 or order % 2:
        raise ValueError(f"order must be even and >= 2, got {order}")
    if not 0.0 < wn < 1.0:
        raise ValueError(f"wn must lie in (0, 1), got {wn}")
    # analogue prototype (scipy.signal.buttap): unit cut-off, no zeros, gain 1
    p = -np.exp(1j * np.pi * np.arange(-order + 1, order, 2) / (2 * order))
    fs = 2.0
    warped = 2 * fs * math.tan(math.pi * wn / fs)
    # low-pass to high-pass (lp2hp_zpk): zeros at s = 0, poles wo / p
    z_hp = np.zeros(order)
    p_hp = warped / p
    k_hp = float(np.real(1.0 / np.prod(-p)))
    # bilinear transform (bilinear_zpk) at fs = 2
    fs2 = 2.0 * fs
    z_z = (fs2 + z_hp) / (fs2 - z_hp)
    p_z = (fs2 + p_hp) / (fs2 - p_hp)
    k_z = k_hp * np.real(np.prod(fs2 - z_hp) / np.prod(fs2 - p_hp))
    # sections (zpk2sos, nearest pairing): one conjugate pair and two zeros (all at z = 1) each
    upper = p_z[p_z.imag > 0]
    upper = upper[np.lexsort((np.abs(upper.imag), upper.real))]
    n_sections = order // 2
    sos = np.zeros((n_sections, 6))
    zeros = list(z_z.real)
    for si in range(n_sections - 1, -1, -1):
        worst = int(np.argmin(np.abs(1 - np.abs(upper))))
        p1 = upper[worst]
        upper = np.delete(upper, worst)
        z1, z2 = zeros.pop(), zeros.pop()
        sos[si, :3] = np.poly([z1, z2])
        sos[si, 3:] = np.poly([p1, p1.conj()]).real
    sos[0, :3] *= k_z
    sos.flags.writeable = False
    return sos


def sosfilt_zi(sos: np.ndarray) -> np.ndarray:
    """Initial conditions of each section for the steady state of a unit step
    (``scipy.signal.sosfilt_zi``); shape (sections, 2)."""
    sos = np.asarray(sos, dtype=float)
    return _step_state(sos.shape, sos.tobytes()).copy()


@functools.lru_cache(maxsize=32)
def _step_state(shape: tuple[int, ...], coefficients: bytes) -> np.ndarray:
    """:func:`sosfilt_zi` of the sections given by their ``shape`` and float64 bytes, computed
    once per filter (read-only)."""
    sos = np.frombuffer(coefficients).reshape(shape)
    zi = np.empty((sos.shape[0], 2))
    scale = 1.0
    for s in range(sos.shape[0]):
        b, a = sos[s, :3], sos[s, 3:]
        if a[0] != 1.0:
            b, a = b / a[0], a / a[0]
        # lfilter_zi: solve (I - A) zi = b[1:] - a[1:] b[0], A the transposed companion matrix
        i_minus_a = np.eye(2) - np.array([[-a[1], 1.0], [-a[2], 0.0]])
        zi[s] = scale * np.linalg.solve(i_minus_a, b[1:] - a[1:] * b[0])
        scale *= b.sum() / a.sum()
    zi.flags.writeable = False
    return zi


def _sosfilt(sos: np.ndarray, x: np.ndarray, zi: np.ndarray) -> np.ndarray:
    """Direct form II transposed, section after section for each sample (scipy's order)."""
    coeffs = [tuple(float(c) for c in row) for row in sos]
    state = [[float(zi[s, 0]), float(zi[s, 1])] for s in range(len(coeffs))]
    out = x.tolist()
    for s, (b0, b1, b2, _a0, a1, a2) in enumerate(coeffs):
        z0, z1 = state[s]
        for i, xc in enumerate(out):
            xn = b0 * xc + z0
            z0 = b1 * xc - a1 * xn + z1
            z1 = b2 * xc - a2 * xn
            out[i] = xn
    return np.array(out)


def load_compiled_filter() -> None:
    """Import ``scipy.signal`` now, so that every later :func:`sosfiltfilt` of this process
    (and of processes forked from it) uses its compiled recursion. A sweep calls this at its
    start (:func:`deckpound.compare.cases.map_parallel`, the worker pool and the Dask workers'
    set-up): the import then costs its second once, before the first case, not as a stall in
    the middle of the sweep at the :data:`SCIPY_AFTER`-th record."""
    import scipy.signal  # noqa: F401


def sosfiltfilt(sos: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Forward-backward filtering of a 1-D signal, or of each row of a 2-D array of signals
    (``scipy.signal.sosfiltfilt`` with its defaults, along the last axis: odd padding of
    3 · (2 · sections + 1) samples); each row gives the bits it gives alone.

    The forward pass starts after the samples that are +0.0 in every row at the start (the
    zero pads of :func:`deckpound.models.record_motion.highpass_padded`): see
    :func:`_silent_start`."""
    sos = np.asarray(sos, dtype=float)
    x = np.asarray(x, dtype=float)
    ntaps = 2 * sos.shape[0] + 1
    ntaps -= min(int((sos[:, 2] == 0).sum()), int((sos[:, 5] == 0).sum()))
    edge = 3 * ntaps
    if x.ndim not in (1, 2) or x.shape[-1] <= edge:
        raise ValueError(f"the signal needs more than {edge} samples, got {x.shape}")
    _CALLS[0] += 1 if x.ndim == 1 else x.shape[0]
    if _CALLS[0] >= SCIPY_AFTER and "scipy.signal" not in sys.modules:
        import scipy.signal  # noqa: F401  (a long sweep: worth its import from now on)
    rows = x if x.ndim == 2 else x[None]
    ext = np.concatenate(
        (
            2 * rows[:, :1] - rows[:, edge:0:-1],
            rows,
            2 * rows[:, -1:] - rows[:, -2 : -(edge + 2) : -1],
        ),
        axis=1,
    )
    zi = _step_state(sos.shape, sos.tobytes())
    silent = _silent_start(sos, ext)
    forward = np.zeros(ext.shape)
    signal = sys.modules.get("scipy.signal")
    if signal is not None:  # already paid for: its compiled loop gives the same bits
        # initial states (sections, rows, 2): each row's steady state at its first value, or
        # rest after a silent start
        zi_rows = zi[:, None, :]
        start = zi_rows * ext[:, :1] if not silent else np.zeros(zi_rows.shape[:1] + (len(ext), 2))
        if silent < ext.shape[1]:
            forward[:, silent:] = signal.sosfilt(sos, ext[:, silent:], zi=start)[0]
        y = signal.sosfilt(sos, forward[:, ::-1], zi=zi_rows * forward[:, -1:])[0][:, ::-1]
    else:
        # sections are applied one after the other on the whole signal: the same numbers as
        # scipy's sample-by-sample interleaving (each section only sees its predecessor's
        # output)
        y = np.empty(ext.shape)
        for i, row in enumerate(ext):
            start = zi * row[0] if not silent else np.zeros(zi.shape)
            forward[i, silent:] = _sosfilt(sos, row[silent:], start)
            y[i] = _sosfilt(sos, forward[i, ::-1], zi * forward[i, -1])[::-1]
    return (y if x.ndim == 2 else y[0])[..., edge:-edge]


def _silent_start(sos: np.ndarray, signals: np.ndarray) -> int:
    """How many first samples of the ``signals`` (rows) a forward pass may skip: those that
    are +0.0 bit for bit in every row, when there are at least two and every section has
    b0 > 0 and b2 > 0 (as a Butterworth high-pass); else 0.

    On +0.0 input, a section of the direct form II transposed, whatever its (signed zero)
    initial state, gives y = b0·0 + z0 = +0.0 and, from the second sample on, the state
    z0 = b1·0 − a1·y + z1 = +0.0 and z1 = b2·0 − a2·y = +0.0; so the pass gives +0.0 over
    those samples and reaches the next one at rest, where it starts from zero state."""
    if not (np.all(sos[:, 0] > 0.0) and np.all(sos[:, 2] > 0.0)):
        return 0
    sounding = np.any(signals.view(np.uint64) != 0, axis=0)
    silent = int(np.argmax(sounding)) if sounding.any() else signals.shape[1]
    return silent if silent >= 2 else 0
