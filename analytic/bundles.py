"""The named bundles the compiled step loops take, their statistics and how a loop is run.

Every step-loop kernel (:func:`~deckpound.analytic.compliance.newmark.newmark_run`,
:func:`~deckpound.analytic.nonsmooth.moreau_jean.moreau_jean_run`,
:func:`~deckpound.analytic.compliance.dormand_prince.adaptive_run`) takes the same seven bundles, all
numba-compatible namedtuples of arrays and scalars (STYLE: "hot kernels are pure functions of
arrays"; the kernels run without numba's runtime, see :mod:`deckpound.analytic._jit`, and
namedtuples of arrays need none)::

    loop(system, contact, record, options, output, work, stats)

* ``system`` — :class:`~deckpound.analytic.kernels.system.SystemArrays`: springs, mass, damping (the
  constant damping matrix ``C`` [kN·s/m] and the number of bent springs ``nbs`` included).
* ``contact`` — :data:`Contact`: the packed corner table (:mod:`.kinematics`), the per-corner
  law parameters (:mod:`.contact_laws`) and the kinematics flag.
* ``record`` — :data:`Record`: the support record at its own samples (t [s], displacement
  [m], velocity [m/s] per channel, :mod:`.support_motion`).
* ``options`` — the loop's own scalars (step, tolerances, stride, switches), a namedtuple
  defined next to the loop.
* ``output`` — :data:`Output`: the output table, the selected columns, a row buffer and the
  per-step peaks and gap closures (:mod:`.peaks`).
* ``work`` — the loop's workspace, a namedtuple with one named field per array (built by one
  function per loop; this also holds the evolving state: material and contact states).
* ``stats`` — :data:`Stats`: integer counts and float values with named indices
  (``CNT_*``, ``VAL_*``, decoded by :func:`stats_dict`) and the ``halt`` flag.

The ``halt`` flag: every loop polls it once per Newton iteration / Runge–Kutta step attempt and
ends with status :data:`RUN_INTERRUPTED`, its output rows written so far intact; Ctrl-C sets it
(:func:`deckpound.analytic.interruptible.run_loop`). The engines then re-raise KeyboardInterrupt
(default: the CLI exits 130, no partial result is cached) or, with the engine keyword
``on_interrupt="return"``, return ``Status.INTERRUPTED`` with the rows so far. The flag is a
plain memory load per iteration.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from deckpound.analytic.kernels.contact_assembly import N_LAW_DERIVATIVES
from deckpound.analytic.kernels.size_tags import corner_slots
from deckpound.analytic.kernels.support_motion import record_slopes
from deckpound.models.engine_contract import Status
from deckpound.models.errors import SceneError

__all__ = [
    "COUNT_NAMES",
    "MAX_OUTPUT_BYTES",
    "RUN_CONTACT_UNSOLVED",
    "RUN_INTERRUPTED",
    "RUN_NONFINITE",
    "RUN_NOT_CONVERGED",
    "RUN_OK",
    "RUN_SINGULAR",
    "RUN_STEP_BUDGET",
    "RUN_STEP_UNDERFLOW",
    "RUN_UNKNOWN_LAW",
    "RUN_UNSEATED",
    "VALUE_NAMES",
    "Contact",
    "ContactWork",
    "Output",
    "Record",
    "Stats",
    "check_output_size",
    "new_contact_work",
    "new_stats",
    "output_table",
    "record",
    "result_columns",
    "row_views",
    "stats_dict",
    "status_of",
]

# Each namedtuple class lives at module level under its own typename: a class made per call
# would be a new numba type (a fresh compilation every run), and a typename differing from the
# attribute name makes numba pickle the class by value (the on-disk cache never hits).

#: The contact description of a loop: ``corners`` (n_corners, N_K) corner table
#: (:func:`deckpound.analytic.kernels.kinematics.pack_corners`), ``params`` (n_corners, N_CP) law
#: parameters
#: (:func:`deckpound.analytic.kernels.contact_laws.pack_contact`), ``nonlinear`` (bool) exact
#: kinematics.
Contact = namedtuple("Contact", ["corners", "params", "nonlinear"])
#: The support record: ``t`` (n,) [s], ``disp`` (n, n_channels) [m or rad], ``vel`` (n,
#: n_channels) [m/s or rad/s] (:func:`deckpound.analytic.kernels.support_motion.support_record`) and
#: their segment slopes ``dslope``, ``vslope`` (same shapes; per second,
#: :func:`deckpound.analytic.kernels.support_motion.record_slopes`). Build with :func:`record`.
Record = namedtuple("Record", ["t", "disp", "vel", "dslope", "vslope"])


def record(tb, D, V) -> Record:
    """The :data:`Record` bundle of a support record at its own samples (slopes computed)."""
    return Record(tb, D, V, *record_slopes(tb, D, V))


#: The output: ``table`` (rows, n_selected) written row by row, ``select`` (n_selected,) int64
#: indices into the loop's full row, ``row`` the full-row buffer, ``peaks`` the peaks of the
#: columns and the gap closures over every step (:data:`deckpound.analytic.kernels.peaks.Peaks`),
#: whose ``layout`` is also the layout of the engine columns of ``row``.
Output = namedtuple("Output", ["table", "select", "row", "peaks"])
#: Statistics: ``count`` int64 (:data:`COUNT_NAMES`, indices ``CNT_*``), ``value`` float64
#: (:data:`VALUE_NAMES`, indices ``VAL_*``), ``halt`` int64 (1,) — set to 1 to stop the loop.
Stats = namedtuple("Stats", ["count", "value", "halt"])
#: Per-corner contact arrays of the compliance loops (:mod:`.contact_laws`): gaps ``g`` [m],
#: rates ``gd`` [m/s], rows ``WN``, ``WT`` (n_corners, n_dof), generalised contact force ``fc``
#: (n_dof,), forces ``lam``, ``lt`` (n_corners,) [kN], law derivatives ``der`` (n_corners,
#: N_LAW_DERIVATIVES, :mod:`deckpound.analytic.kernels.contact_assembly`), ``evaluated``
#: (n_corners,) bool, and ``corners`` the tuple (0, …, n_corners − 1):
#: numba types a tuple by its length, so ``len(cw.corners)`` is a compile-time constant of the
#: kernels (loops over the corners unroll as over a literal) while the count still comes from
#: the bundle.
ContactWork = namedtuple(
    "ContactWork", ["g", "gd", "WN", "WT", "fc", "lam", "lt", "der", "evaluated", "corners"]
)

#: Names of ``Stats.count`` entries, in index order.
COUNT_NAMES = (
    "status",
    "rows",
    "failed_step",
    "steps",
    "newton_iterations",
    "contact_events",
    "factor_reuses",
    "max_step_iterations",
    "rescued_steps",
    "contact_solves",
    "contact_steps",
    "factorisations",
    "rejected_steps",
    "rhs_calls",
    "unmoved_iterates",
    "contact_factor_reuses",
)
(
    CNT_STATUS,
    CNT_ROWS,
    CNT_FAILED_STEP,
    CNT_STEPS,
    CNT_NEWTON,
    CNT_EVENTS,
    CNT_REUSED,
    CNT_MAX_IT,
    CNT_RESCUED,
    CNT_SOLVES,
    CNT_CONTACT_STEPS,
    CNT_FACTORISATIONS,
    CNT_REJECTED,
    CNT_RHS_CALLS,
    CNT_UNMOVED,
    CNT_CONTACT_REUSED,
) = range(len(COUNT_NAMES))
#: Names of ``Stats.value`` entries, in index order: largest verified complementarity and cone
#: residuals of the contact solves [m/s], time reached [s], and the largest penetration
#: max(0, −g) over the corners at the end of **every accepted step** [m] (issue 12: the
#: output rows see only every stride-th step and missed the true maximum by a factor of 6 on
#: the benchmark).
VALUE_NAMES = ("max_complementarity", "max_cone_residual", "time", "max_penetration")
VAL_MAX_COMP, VAL_MAX_CONE, VAL_TIME, VAL_MAX_PEN = range(len(VALUE_NAMES))

# how a loop ended (Stats.count[CNT_STATUS])
RUN_OK = 0
RUN_NOT_CONVERGED = 1  # Newton did not converge
RUN_SINGULAR = 2  # singular tangent / iteration matrix
RUN_NONFINITE = 3  # non-finite state
RUN_CONTACT_UNSOLVED = 4  # no verified solution of the contact problem
RUN_STEP_BUDGET = 5  # step budget exhausted (adaptive)
RUN_INTERRUPTED = 6  # Stats.halt set (Ctrl-C)
RUN_STEP_UNDERFLOW = 7  # adaptive step size below 1e-14 s
RUN_UNKNOWN_LAW = 8  # a contact law or friction code without a kernel branch
RUN_UNSEATED = 9  # a corner's seat margin became negative: the loop stopped after that step

_STATUS = {
    RUN_OK: Status.SUCCESS,
    RUN_NOT_CONVERGED: Status.NOT_CONVERGED,
    RUN_SINGULAR: Status.SINGULAR,
    RUN_NONFINITE: Status.NONFINITE,
    RUN_CONTACT_UNSOLVED: Status.CONTACT_UNSOLVED,
    RUN_STEP_BUDGET: Status.STEP_BUDGET,
    RUN_INTERRUPTED: Status.INTERRUPTED,
    RUN_STEP_UNDERFLOW: Status.NOT_CONVERGED,
    RUN_UNSEATED: Status.UNSEATED,
}

#: Largest output table a run may allocate [bytes] (1 GiB; the engine's result copies it once
#: more): a run storing every step of 10⁷ steps would need ~2.6 GiB and is refused up front.
MAX_OUTPUT_BYTES = 1 << 30


def new_stats() -> Stats:
    """Zeroed statistics (halt flag down)."""
    return Stats(
        np.zeros(len(COUNT_NAMES), dtype=np.int64),
        np.zeros(len(VALUE_NAMES)),
        np.zeros(1, dtype=np.int64),
    )


def stats_dict(stats: Stats) -> dict:
    """The statistics as ``{name: int or float}`` (the one decoder of ``Stats``)."""
    out = {n: int(stats.count[i]) for i, n in enumerate(COUNT_NAMES)}
    out.update({n: float(stats.value[i]) for i, n in enumerate(VALUE_NAMES)})
    return out


def status_of(code: int) -> Status:
    """The engine-contract status of a loop's status code (unknown codes: NONFINITE)."""
    if code == RUN_UNKNOWN_LAW:
        raise NotImplementedError(
            "a contact law or friction model of the scene has no branch "
            "in deckpound.analytic.kernels.contact_laws (normal_law / "
            "friction_law): add it there (see "
            "deckpound.models.contact_laws_table)"
        )
    return _STATUS.get(code, Status.NONFINITE)


def new_contact_work(n_corners: int, n_dof: int) -> ContactWork:
    """Zeroed :data:`ContactWork` of ``n_corners`` corners on ``n_dof`` DOF (per-corner
    vectors, rows and law derivatives each views of one block)."""
    return ContactWork(
        fc=np.zeros(n_dof),
        evaluated=np.zeros(n_corners, dtype=np.bool_),
        corners=corner_slots(n_corners),
        der=np.zeros((n_corners, N_LAW_DERIVATIVES)),
        **row_views(("g", "gd", "lam", "lt"), n_corners),
        **row_views(("WN", "WT"), n_corners, n_dof),
    )


def row_views(names, *shape, dtype=np.float64) -> dict:
    """``{name: zeroed array of shape}``, all views of one contiguous block (locality)."""
    block = np.zeros((len(names),) + shape, dtype=dtype)
    return {n: block[i] for i, n in enumerate(names)}


def check_output_size(rows: int, columns: int, field: str = "run.output_dt") -> None:
    """Refuse (SceneError naming ``field``) an output table above :data:`MAX_OUTPUT_BYTES`."""
    size = 8 * int(rows) * int(columns)
    if size > MAX_OUTPUT_BYTES:
        raise SceneError(
            field,
            f"gives {rows} output rows x {columns} columns = "
            f"{size / 2**30:.2f} GiB of output; at most "
            f"{MAX_OUTPUT_BYTES / 2**30:g} GiB is allowed: store fewer rows "
            f"(a larger {field})",
        )


def output_table(rows: int, columns: int, field: str = "run.output_dt") -> np.ndarray:
    """The zeroed output table of a step loop, (rows, columns) [column units], refused above
    :data:`MAX_OUTPUT_BYTES` (:func:`check_output_size`).

    Column-major (Fortran order): each column is one contiguous block, so the result's columns
    are views of the table (:func:`result_columns`), not copies: a run holds its output once.
    The loop writes one row per output step, a strided store per column; its arithmetic does
    not depend on the layout."""
    check_output_size(rows, columns, field)
    return np.zeros((int(rows), int(columns)), order="F")


def result_columns(table: np.ndarray, rows: int, names) -> dict[str, np.ndarray]:
    """The first ``rows`` rows of each column of ``table`` as read-only views, by name.

    Read-only arrays are handed to :class:`deckpound.models.result.Result` as they are (it
    copies only writeable ones), so the table is the run's one copy of its histories."""
    out = {}
    for i, name in enumerate(names):
        col = table[:rows, i]
        col.flags.writeable = False
        out[name] = col
    return out
