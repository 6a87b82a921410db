"""Timing helper shared by the benchmarks."""

from __future__ import annotations

import time


def best_of(fn, repeats: int) -> float:
    """The shortest wall time [s] of ``repeats`` calls of ``fn()`` (the least disturbed one)."""
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best
