"""Subnormal numbers in the compiled step loops: flushed to zero or kept (``subnormals``).

A quantity that decays freely passes through the subnormal range (|x| < 2.2e-308, IEEE 754
gradual underflow) on its way to zero. On x86-64 every floating-point operation with a
subnormal input or output takes a microcode assist, many times slower than a normal operation. On the
benchmark, the free seat rotations decay through that range once pounding stops
(t > 13.6 s), and from then on every step pays for numbers that are zero for any physical
purpose (the ``subnormals`` row of ``deckpound bench --skips`` measures the whole run).

``subnormals = "flush"`` sets the FTZ (flush-to-zero, bit 15) and DAZ (denormals-are-zero,
bit 6) bits of the SSE control register MXCSR for the duration of a step loop, in the thread
that runs it, and restores the register when the loop ends. Every result that would be
subnormal becomes ±0 (an absolute change below 2.2e-308 per operation), and what follows from
it can differ by as little: on the benchmark, in all three analytic integrators, every stored
value larger than :data:`UNCHANGED_ABOVE` in magnitude is bit-identical with ``"keep"`` (the
seat rotations and their rates differ below 1e-287 rad, rad/s; checked by the tests). ``"keep"`` leaves the IEEE
default, as OpenSees (its own C++ arithmetic) always does.

The MXCSR access is x86-64 only (:data:`FLUSH_AVAILABLE`); on other machines the loops keep
subnormals and the engines say so in their notes (:func:`flush_note`).

Kernels::

    saved = flush_enter(opt.flush_subnormals)   # at the start of the loop kernel
    ...                                         # the step loop
    flush_leave(saved)                          # before it returns
"""

from __future__ import annotations

import platform

import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from deckpound.analytic._jit import kernel
from deckpound.models.scene_settings import SUBNORMALS_UNCHANGED_ABOVE

__all__ = [
    "FLUSH_AVAILABLE",
    "FTZ_DAZ",
    "SMALLEST_NORMAL",
    "UNCHANGED_ABOVE",
    "flush_enter",
    "flush_leave",
    "flush_note",
]

#: MXCSR bits FTZ (results flushed to zero, bit 15) and DAZ (subnormal inputs read as zero, bit 6)
FTZ_DAZ = 0x8040
#: the smallest positive normal float64; below it the loops in "flush" mode store ±0
SMALLEST_NORMAL = float(np.finfo(np.float64).tiny)
#: magnitude above which the tests require "flush" and "keep" results to be bit-identical
UNCHANGED_ABOVE = SUBNORMALS_UNCHANGED_ABOVE
#: True where the loops can flush subnormals (the SSE control register of x86-64)
FLUSH_AVAILABLE = platform.machine().lower() in ("x86_64", "amd64")


def _mxcsr_call(builder, name, ptr):
    fnty = ir.FunctionType(ir.VoidType(), [ir.IntType(8).as_pointer()])
    fn = cgutils.get_or_insert_function(builder.module, fnty, name)
    builder.call(fn, [builder.bitcast(ptr, ir.IntType(8).as_pointer())])


@intrinsic
def _read_mxcsr(typingctx):
    """The calling thread's MXCSR (0 where there is none)."""

    def codegen(context, builder, signature, args):
        i64 = ir.IntType(64)
        if not FLUSH_AVAILABLE:
            return ir.Constant(i64, 0)
        slot = cgutils.alloca_once(builder, ir.IntType(32))
        _mxcsr_call(builder, "llvm.x86.sse.stmxcsr", slot)
        return builder.zext(builder.load(slot), i64)

    return types.int64(), codegen


@intrinsic
def _write_mxcsr(typingctx, value):
    """Set the calling thread's MXCSR (nothing where there is none)."""

    def codegen(context, builder, signature, args):
        if FLUSH_AVAILABLE:
            i32 = ir.IntType(32)
            slot = cgutils.alloca_once(builder, i32)
            builder.store(builder.trunc(args[0], i32), slot)
            _mxcsr_call(builder, "llvm.x86.sse.ldmxcsr", slot)
        return context.get_dummy_value()

    return types.none(types.int64), codegen


@kernel(inline="always")
def flush_enter(flush):
    """Start flushing subnormals in this thread when ``flush`` is true; returns the MXCSR to
    restore with :func:`flush_leave` (-1: nothing was changed)."""
    if not flush:
        return -1
    saved = _read_mxcsr()
    _write_mxcsr(saved | FTZ_DAZ)
    return saved


@kernel(inline="always")
def flush_leave(saved):
    """Restore the MXCSR that :func:`flush_enter` returned."""
    if saved >= 0:
        _write_mxcsr(saved)


def flush_note(field: str, mode: str) -> list[str]:
    """The engine note for ``field = mode`` on a machine that cannot flush (else none)."""
    if mode == "flush" and not FLUSH_AVAILABLE:
        return [
            f"{field} = 'flush' needs the SSE control register of x86-64; on this machine "
            f"({platform.machine() or 'unknown'}) the loops keep subnormal numbers (IEEE "
            "gradual underflow), as with 'keep'"
        ]
    return []
