"""Values a process keeps for reuse: a least-recently-used table under a size budget, safe for
the threads of one worker.

A sweep applies one record pair at many levels (IDA, stripes), in the threads of a Dask worker
as well as in one process: what the cases share (a record file's parse, the measure of an
unscaled pair) is computed once and kept here. The key names the content the value was computed
from (e.g. a SHA-256 of its bytes), so a changed input is a new key, never a stale value.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Any

__all__ = ["Kept"]


class Kept:
    """Values by key, the least recently used dropped first while their total size exceeds
    ``budget`` (``size(value)``: 1 by default, so the budget is a count); a value larger than
    the budget alone is not kept. Every table operation holds the table's lock; what computes
    a value runs outside it, so threads compute different values at once."""

    def __init__(self, budget: float, size: Callable[[Any], float] = lambda value: 1) -> None:
        self.budget = budget
        self._size = size
        self._values: OrderedDict[Hashable, Any] = OrderedDict()
        self._total = 0.0
        self._lock = threading.Lock()

    def get(self, key: Hashable) -> Any | None:
        """The value kept under ``key`` (now the most recently used), or None."""
        with self._lock:
            value = self._values.get(key)
            if value is not None:
                self._values.move_to_end(key)
            return value

    def put(self, key: Hashable, value: Any) -> None:
        """Keep ``value`` under ``key``, then drop the least recently used over the budget."""
        with self._lock:
            old = self._values.pop(key, None)
            if old is not None:
                self._total -= self._size(old)
            self._values[key] = value
            self._total += self._size(value)
            while self._values and self._total > self.budget:
                _, dropped = self._values.popitem(last=False)
                self._total -= self._size(dropped)

    @property
    def total(self) -> float:
        """The total size of the values kept (at most the budget)."""
        with self._lock:
            return self._total

    def order(self) -> list[Hashable]:
        """The keys, least recently used first."""
        with self._lock:
            return list(self._values)

    def clear(self) -> None:
        with self._lock:
            self._values.clear()
            self._total = 0.0
