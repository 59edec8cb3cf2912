"""What the benchmark scripts (``scripts/bench_*.py``) share: the timing harness (medians of wall time), their
command line's start and their closing report.

Speed targets live in these benchmarks, measured side by side in one run, never in timed unit tests.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path
from typing import Callable


def bench_parser(doc: str) -> argparse.ArgumentParser:
    """A benchmark script's argument parser: the first paragraph of its docstring ``doc`` as the description,
    and the required ``--json PATH`` that its record is written to; the script adds its own options."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument("--json", type=Path, required=True, help="output JSON file")
    return parser


def report(json_path: Path, *lines: str) -> None:
    """Print a benchmark's summary ``lines``, then the JSON file its record was written to."""
    for line in lines:
        print(line)
    print(f"wrote {json_path}")


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
