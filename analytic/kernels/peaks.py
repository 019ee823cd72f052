"""Peaks of the result columns and gap closures, taken at every step of the compiled loops.

The output rows see one step in ``stride`` (``run.output_dt`` / the engine's step): a peak or
a closure between two rows is lost, and how much depends on the output rate (issue 28: the
benchmark's peak deck rotation read 0.81 mrad instead of 3.62 at ``run.output_dt = 0.5``).
Every step loop therefore calls :func:`track_state` once per accepted step (every sub-step of
a rescued step, every adaptive step) and once at t = 0, with the state it commits:

* the step's values of the columns of the **peak layout** are read from that state: the engine
  columns in the layout ``Peaks.layout`` of
  :func:`deckpound.analytic.kernels.system.store_standard` (time, absolute displacements and
  velocities, gaps, normal and tangential contact forces, bent spring forces;
  :data:`deckpound.analytic.kernels.system.RowLayout`), then the
  displacements relative to the supports (:data:`deckpound.models.plan.RELATIVE_COLUMNS`:
  deck x, y relative to the mean shake-table motion, each seat relative to its actuator) and
  the bent deformations d = B u − S u_g of the ``nbs`` bent springs — the columns
  :func:`deckpound.models.engine_contract.finish` derives from the output rows, here from the
  support displacement at the step (:func:`deckpound.models.result.peak_columns` names the
  layout); no row is built;
* ``Peaks.value`` / ``Peaks.time`` keep, per column, the largest |x| and the first time it
  was reached [s] — for the gaps the smallest (most negative: the deepest penetration)
  signed value instead;
* ``Peaks.closures`` counts, per corner, the steps at which the corner goes from out of
  contact to in contact (:func:`in_contact_now`, the one definition; a run that starts in
  contact counts one: ``Peaks.inside`` starts False);
* ``Peaks.gap_open`` / ``Peaks.gap_open_time`` keep, per corner, the **largest** gap g_c [m]
  and its first time [s], ``Peaks.gap_start`` the gap at t = 0: the largest opening
  g_c − g_c(0) is the seat-width demand, and with the support length N of the facing seat
  (``seats[i].support_length``, ``Peaks.support``; +inf: not checked) the seat margin is
  m_c = N − (g_c − g_c(0)). Its minimum over the run is at the largest gap. The first step at
  which a margin is negative (g_c − g_c(0) > N: the deck end has moved away from the
  backwall by more than the seat under it) is the **unseating**: :func:`track_state` returns
  True and ``Peaks.unseat`` holds 1 + the corner's index and ``Peaks.unseat_time`` its time;
  the loops finish that step and stop (status ``RUN_UNSEATED``).

The engine passes its own force values (the compliance engines' λ_N, λ_T; the nonsmooth
engine's impulse of the step divided by the step, ``Peaks.force`` is its scratch).
:func:`track_step` does the same from a row in the peak layout whose engine columns the caller
wrote into ``Peaks.row`` (it completes the row, then takes its peaks): the same statistics, bit
for bit. The arrays are allocated by
:func:`new_peaks` (the loops run without numba's runtime) and read back by
:func:`step_peaks` and :func:`step_closures` into :class:`~deckpound.models.engine_contract.
RunOutput`. The tracking reads and writes only its own arrays: the result columns are those
of a run without it, bit for bit.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from deckpound.analytic._jit import kernel
from deckpound.analytic.kernels.system import (
    C_U,
    RowLayout,
    bent_column,
    end_column,
    gap_column,
    normal_force_column,
    row_layout,
    tangential_force_column,
    velocity_column,
)
from deckpound.models.engine_contract import engine_columns
from deckpound.models.plan import RELATIVE_COLUMNS, SEAT_X
from deckpound.models.result import peak_columns

__all__ = [
    "N_RELATIVE",
    "Peaks",
    "corner_support_lengths",
    "in_contact_now",
    "n_relative",
    "new_peaks",
    "peak_row_size",
    "run_output_fields",
    "run_peaks",
    "step_closures",
    "step_openings",
    "step_peaks",
    "step_unseated",
    "track_state",
    "track_step",
]

#: The per-step peaks bundle (a field of :data:`deckpound.analytic.bundles.Output`):
#: ``row`` (n,) a step's row in the peak layout (:func:`track_step`), ``value`` (n,) the peak
#: of each column so far (max |x|; min x for the gaps), ``time`` (n,) when it was reached [s];
#: ``tx``, ``ty`` int64 the support channels of the shake tables in x and y whose mean is the
#: reference of each segment's relative displacement, segment s's at ``tstart[s]:tstart[s +
#: 1]`` (one segment: every table), ``seat`` (2,) int64 the actuator channel of each seat;
#: ``inside`` (nc,) bool corner in contact at the last step, ``closures`` (nc,) int64 closures
#: per corner; ``force`` (2, nc) scratch for the step's normal and tangential forces; per
#: corner ``gap_open`` (nc,) the largest gap [m] and ``gap_open_time`` (nc,) its time [s],
#: ``gap_start`` (nc,) the gap at t = 0 [m], ``support`` (nc,) the support length of the
#: facing seat [m] (+inf: not checked); ``unseat`` int64 (1,) 1 + the first unseated corner
#: (0: none) and ``unseat_time`` (1,) when [s] (module docstring); ``layout`` the
#: :data:`deckpound.analytic.kernels.system.RowLayout` of the engine columns (of these rows and
#: of the loop's output rows): its DOF columns, the corners' size tag (nc = its length, a
#: compile-time constant of :func:`track_step`) and the number of bent springs.
Peaks = namedtuple(
    "Peaks",
    [
        "row",
        "value",
        "time",
        "tx",
        "ty",
        "tstart",
        "seat",
        "inside",
        "closures",
        "force",
        "gap_open",
        "gap_open_time",
        "gap_start",
        "support",
        "unseat",
        "unseat_time",
        "layout",
    ],
)

#: Number of relative-displacement columns of the peak layout of a one-segment deck (the bent
#: deformations follow); :func:`n_relative` gives it for any layout.
N_RELATIVE = len(RELATIVE_COLUMNS)


@kernel(inline="always")
def n_relative(layout):
    """Relative-displacement columns of ``layout``: x and y of each deck segment (three DOF
    columns each after the seats' four), then each seat's x."""
    return 2 * ((len(layout.dof_columns) - 4) // 3) + 2


def peak_row_size(layout: RowLayout) -> int:
    """Length of the peak layout's row: the engine columns of ``layout``, the relative
    displacements, then the deformations of the ``layout.nbs`` bent springs."""
    # the offsets' Python twins: no kernel load here
    return end_column.py_func(layout) + n_relative.py_func(layout) + layout.nbs


def corner_support_lengths(plan) -> np.ndarray:
    """The support length N [m] under each corner of the ``plan`` (the scene's
    ``seats[i].support_length`` or ``joints[i].support_length``, ``Corner.support_length``),
    +inf where it is not set (not checked)."""
    return np.array(
        [np.inf if c.support_length is None else float(c.support_length) for c in plan.corners]
    )


def _segment_tables(channels, bent_names, segment_bents) -> tuple[np.ndarray, ...]:
    """(tx, ty, tstart): the x and y table channels of every segment's relative displacement
    one after the other, segment s's at ``tstart[s]:tstart[s + 1]`` (its bents' tables, or
    every table for a segment on no bent: :meth:`~deckpound.models.plan.Plan.
    segment_table_channels`)."""
    tx, ty, tstart = [], [], [0]
    for bents in segment_bents:
        names = [bent_names[i] for i in bents] if bents else list(bent_names)
        tx += [channels.index(f"{b}_x") for b in names]
        ty += [channels.index(f"{b}_y") for b in names]
        tstart.append(len(tx))
    return (
        np.array(tx, dtype=np.int64),
        np.array(ty, dtype=np.int64),
        np.array(tstart, dtype=np.int64),
    )


def new_peaks(layout: RowLayout, channels, bent_names, support, segment_bents=None) -> Peaks:
    """Zeroed :data:`Peaks` for a model whose engine columns are in ``layout``
    (:func:`deckpound.analytic.kernels.system.row_layout`), with these support ``channels`` (the
    order of u_g) and bents; the gap entries start at +inf (their statistic is the minimum),
    the largest gaps at −inf. ``support`` (n_corners,) the corners' support lengths [m]
    (:func:`corner_support_lengths`; +inf: not checked), one per corner of the layout;
    ``segment_bents`` the bents each deck segment carries (default: one segment on every
    bent)."""
    support = np.asarray(support, dtype=float)
    nc = len(layout.corners)
    if support.shape != (nc,):
        raise ValueError(
            f"support lengths: one per corner of the layout ({nc}), got shape {support.shape}"
        )
    n = peak_row_size(layout)
    channels = list(channels)
    if segment_bents is None:
        segment_bents = (tuple(range(len(bent_names))),)
    tx, ty, tstart = _segment_tables(channels, list(bent_names), segment_bents)
    value = np.zeros(n)
    c_gap = gap_column.py_func(layout)
    value[c_gap : c_gap + nc] = np.inf
    return Peaks(
        row=np.zeros(n),
        value=value,
        time=np.zeros(n),
        tx=tx,
        ty=ty,
        tstart=tstart,
        seat=np.array([channels.index("seat1_x"), channels.index("seat2_x")], dtype=np.int64),
        inside=np.zeros(nc, dtype=np.bool_),
        closures=np.zeros(nc, dtype=np.int64),
        force=np.zeros((2, nc)),
        gap_open=np.full(nc, -np.inf),
        gap_open_time=np.zeros(nc),
        gap_start=np.zeros(nc),
        support=support.copy(),
        unseat=np.zeros(1, dtype=np.int64),
        unseat_time=np.zeros(1),
        layout=layout,
    )


@kernel(inline="always")
def in_contact_now(gap, fn):
    """Whether a corner is in contact at a step: its gap is closed (g ≤ 0 [m]) or it carried a
    normal force over the step (fn > 0 [kN]).

    The one contact test of the gap-closure count (every engine, the exported scripts and
    :func:`deckpound.models.result.in_contact` on output rows). For the penalty laws every law
    gives zero force while g > 0, so the test is g ≤ 0; the force term is there for rigid
    contact: the nonsmooth engine's impact impulse of a step can reverse the approach within
    the step, leaving g ≥ 0 at both its ends, and the impact is still a contact."""
    return gap <= 0.0 or fn > 0.0


@kernel(inline="always")
def _peak_abs(value, time, k, x, t):
    """Column k's largest |x| and the first time t [s] it was reached."""
    a = abs(x)
    if a > value[k]:
        value[k] = a
        time[k] = t


@kernel(inline="always")
def _track_corner(pk, c, k_gap, gap, fn, t):
    """Corner c at a step (t [s]) with gap [m] and normal force fn [kN] (gap column k_gap):
    the deepest gap, the closures and the largest gap (module docstring). Returns True when
    the corner's seat margin is negative (the first such corner and time kept)."""
    value, time = pk.value, pk.time
    if gap < value[k_gap]:
        value[k_gap] = gap
        time[k_gap] = t
    now = in_contact_now(gap, fn)
    if now and not pk.inside[c]:
        pk.closures[c] += 1
    pk.inside[c] = now
    # the largest gap (seat margin): the initial gap at the first call (largest still −inf)
    unseated = False
    if gap > pk.gap_open[c]:
        if pk.gap_open[c] == -np.inf:
            pk.gap_start[c] = gap
        pk.gap_open[c] = gap
        pk.gap_open_time[c] = t
        if gap - pk.gap_start[c] > pk.support[c]:
            unseated = True
            if pk.unseat[0] == 0:
                pk.unseat[0] = c + 1
                pk.unseat_time[0] = t
    return unseated


@kernel(inline="always")
def _table_means(pk, ug, seg):
    """The mean support displacement of segment ``seg``'s shake tables in x and in y [m]
    (the reference of its relative displacements)."""
    lo, hi = pk.tstart[seg], pk.tstart[seg + 1]
    mx = 0.0
    for k in range(lo, hi):
        mx += ug[pk.tx[k]]
    my = 0.0
    for k in range(lo, hi):
        my += ug[pk.ty[k]]
    if hi > lo:
        mx = mx / (hi - lo)
        my = my / (hi - lo)
    return mx, my


@kernel(inline="always")
def track_state(pk, t, u, v, g, fn, ft, fs, ug, d):
    """Update the peaks and the closures with the state of a step, column by column of the
    peak layout, without building its row (module docstring).

    t [s]; u, v (n_dof,) displacements and velocities [m, rad; m/s, rad/s]; g, fn, ft
    (n_corners,) gaps [m] and the normal and tangential forces the engine reports [kN]; fs
    the spring forces (the first ``nbs`` are the bents') [kN]; ug (n_channels,) support
    displacements [m]; d the spring deformations d = B u − S u_g [m]. Returns True when a
    corner's seat margin N − (g − g(0)) became negative at this step (the deck is unseated):
    one comparison per corner while no gap grows. The column offsets, the corner count and
    nbs come from ``pk.layout``; the statistics are those of :func:`track_step` on the row
    :func:`deckpound.analytic.kernels.system.store_standard` writes, bit for bit."""
    layout = pk.layout
    value, time = pk.value, pk.time
    c_v = velocity_column(layout)
    c_gap = gap_column(layout)
    c_fn = normal_force_column(layout)
    c_ft = tangential_force_column(layout)
    c_bent = bent_column(layout)
    base = end_column(layout)
    for k in range(len(layout.dof_columns)):
        j = layout.dof_columns[k]
        _peak_abs(value, time, C_U + k, u[j], t)
        _peak_abs(value, time, c_v + k, v[j], t)
    unseated = False
    for c in range(len(layout.corners)):
        if _track_corner(pk, c, c_gap + c, g[c], fn[c], t):
            unseated = True
        _peak_abs(value, time, c_fn + c, fn[c], t)
        _peak_abs(value, time, c_ft + c, ft[c], t)
    for i in range(layout.nbs):
        _peak_abs(value, time, c_bent + i, fs[i], t)
    n_seg = (len(layout.dof_columns) - 4) // 3
    for s in range(n_seg):
        mx, my = _table_means(pk, ug, s)
        sx, sy = layout.dof_columns[3 * s], layout.dof_columns[3 * s + 1]
        _peak_abs(value, time, base + 2 * s, u[sx] - mx, t)
        _peak_abs(value, time, base + 2 * s + 1, u[sy] - my, t)
    seats = base + 2 * n_seg
    _peak_abs(value, time, seats, u[SEAT_X[0]] - ug[pk.seat[0]], t)
    _peak_abs(value, time, seats + 1, u[SEAT_X[1]] - ug[pk.seat[1]], t)
    for i in range(layout.nbs):
        _peak_abs(value, time, seats + 2 + i, d[i], t)
    return unseated


@kernel(inline="always")
def track_step(pk, t, u, ug, d):
    """:func:`track_state` from a row: complete the step's row in ``pk.row`` (its engine
    columns written by the caller) with the relative displacements and bent deformations, then
    update the peaks and the closures from the row's columns.

    u (n_dof,) displacements [m, rad] and ug (n_channels,) support displacements [m] at the
    step, d the spring deformations d = B u − S u_g (the first ``nbs`` are the bents'), t [s].
    Returns True when a corner's seat margin became negative at this step."""
    row = pk.row
    layout = pk.layout
    c_gap = gap_column(layout)
    c_fn = normal_force_column(layout)
    base = end_column(layout)
    n_seg = (len(layout.dof_columns) - 4) // 3
    for s in range(n_seg):
        mx, my = _table_means(pk, ug, s)
        row[base + 2 * s] = u[layout.dof_columns[3 * s]] - mx
        row[base + 2 * s + 1] = u[layout.dof_columns[3 * s + 1]] - my
    seats = base + 2 * n_seg
    row[seats] = u[SEAT_X[0]] - ug[pk.seat[0]]
    row[seats + 1] = u[SEAT_X[1]] - ug[pk.seat[1]]
    for i in range(layout.nbs):
        row[seats + 2 + i] = d[i]
    value, time = pk.value, pk.time
    # the gaps: the most negative value; every other column: the largest |x| (t excluded)
    for k in range(C_U, c_gap):
        _peak_abs(value, time, k, row[k], t)
    unseated = False
    for c in range(len(layout.corners)):
        if _track_corner(pk, c, c_gap + c, row[c_gap + c], row[c_fn + c], t):
            unseated = True
    for k in range(c_fn, row.shape[0]):
        _peak_abs(value, time, k, row[k], t)
    return unseated


def step_peaks(pk: Peaks, names: list[str]) -> dict[str, tuple[float, float]]:
    """``{column: (peak, time)}`` of :func:`track_step`'s statistics, ``names`` from
    :func:`deckpound.models.result.peak_columns` (``t`` left out; a gap's peak is its smallest
    value)."""
    return {
        n: (float(pk.value[k]), float(pk.time[k]))
        for k, n in enumerate(names)
        if n != "t" and np.isfinite(pk.value[k])
    }


def _checked_names(pk: Peaks, corner_names) -> tuple[str, ...]:
    names = tuple(corner_names)
    if len(names) != len(pk.layout.corners):
        raise ValueError(
            f"corner names {list(names)}: one per corner of the peaks "
            f"({len(pk.layout.corners)}) is needed"
        )
    return names


def step_openings(pk: Peaks, corner_names) -> dict[str, tuple[float, float]]:
    """``{corner: (opening, time)}``: the largest gap opening g_c − g_c(0) over every step
    [m] (the seat-width demand; negative if the gap only closed) and when it was reached [s];
    ``corner_names`` in the corners' order (the plan's ``Corner.name``)."""
    return {
        c: (float(pk.gap_open[k] - pk.gap_start[k]), float(pk.gap_open_time[k]))
        for k, c in enumerate(_checked_names(pk, corner_names))
    }


def step_unseated(pk: Peaks, corner_names) -> tuple[str, float] | None:
    """``(corner, time [s])`` of the first unseating (:func:`track_step`), or None."""
    k = int(pk.unseat[0])
    names = _checked_names(pk, corner_names)
    return None if k == 0 else (names[k - 1], float(pk.unseat_time[0]))


def step_closures(pk: Peaks, corner_names) -> dict[str, int]:
    """Gap closures per corner counted at every step (``{"c1": n, ...}``)."""
    return {c: int(pk.closures[k]) for k, c in enumerate(_checked_names(pk, corner_names))}


def run_peaks(plan, ps) -> Peaks:
    """Zeroed :data:`Peaks` for a run on ``plan`` with the packed system ``ps`` (its support
    channels and bent springs) and the corners' support lengths: what every analytic engine's
    driver hands its step loop.

    The drivers size the output rows by the names of
    :func:`deckpound.models.engine_contract.engine_columns` and the loops write the columns of
    the plan's :func:`~deckpound.analytic.kernels.system.row_layout` (without bounds checks):
    a plan whose corners or DOF those names do not cover is refused here (ValueError)."""
    layout = row_layout(plan)
    n_named, n_layout = len(engine_columns(plan)), end_column.py_func(layout)
    if n_named != n_layout:
        raise ValueError(
            f"the plan's row layout has {n_layout} engine columns ({len(layout.corners)} "
            f"corners, {len(layout.dof_columns)} DOF), but "
            f"deckpound.models.engine_contract.engine_columns names {n_named}"
        )
    return new_peaks(
        layout,
        ps.channels,
        plan.bent_names,
        corner_support_lengths(plan),
        tuple(seg.bents for seg in plan.segments),
    )


def run_output_fields(pk: Peaks, plan) -> dict:
    """The :class:`~deckpound.models.engine_contract.RunOutput` fields of a finished loop's every-step
    statistics: ``peaks``, ``gap_closures_per_corner``, ``gap_openings`` and ``unseated``."""
    names = [c.name for c in plan.corners]
    return {
        "peaks": step_peaks(
            pk, peak_columns(engine_columns(plan), plan.bent_names, plan.relative_columns)
        ),
        "gap_closures_per_corner": step_closures(pk, names),
        "gap_openings": step_openings(pk, names),
        "unseated": step_unseated(pk, names),
    }
