"""The one timing harness of the benchmark scripts (``scripts/bench_*.py``): medians of wall time.

Speed targets live in these benchmarks, measured side by side in one run, never in timed unit tests.
"""

from __future__ import annotations

import statistics
import time
from typing import Callable


def median_seconds(fn: Callable[[], object], *, repeats: int, warmup: int = 1) -> float:
    """Median wall time of ``fn()`` over ``repeats`` calls after ``warmup`` untimed calls, seconds."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def median_ms(fn: Callable[[], object], *, repeats: int, warmup: int = 0) -> float:
    """:func:`median_seconds` in milliseconds (no warm-up call by default)."""
    return float(median_seconds(fn, repeats=repeats, warmup=warmup) * 1000.0)
