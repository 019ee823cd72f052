"""The values a process keeps for reuse (deckpound.models.kept): least recently used first out
under a size budget, and safe for the threads of one worker."""

from __future__ import annotations

import sys
from concurrent.futures import ThreadPoolExecutor

from deckpound.models.kept import Kept


def test_a_count_budget_drops_the_least_recently_used():
    kept = Kept(2)
    kept.put("a", 1)
    kept.put("b", 2)
    assert kept.get("a") == 1  # "a" is now the most recent
    kept.put("c", 3)
    assert kept.order() == ["a", "c"] and kept.get("b") is None and kept.total == 2


def test_a_size_budget_counts_sizes_and_refuses_a_value_too_large():
    kept = Kept(10, len)
    kept.put("x", "aaaa")
    kept.put("y", "bbbbb")
    kept.put("x", "cc")  # replaced: its old size leaves the total
    assert kept.total == 7 and kept.order() == ["y", "x"]
    kept.put("z", "d" * 11)
    assert kept.order() == [] and kept.total == 0
    kept.put("w", "e")
    kept.clear()
    assert kept.get("w") is None and kept.total == 0


def test_threads_get_and_put_while_values_are_dropped():
    kept = Kept(3)

    def use(i: int) -> bool:
        key = i % 7
        value = kept.get(key)
        if value is None:
            kept.put(key, key * 10)
            return True
        return value == key * 10

    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)  # switch threads often
    try:
        with ThreadPoolExecutor(8) as pool:
            assert all(pool.map(use, range(20000)))
    finally:
        sys.setswitchinterval(interval)
    assert len(kept.order()) <= 3 and kept.total == len(kept.order())
