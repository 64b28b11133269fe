"""Timing helpers for the benchmarks: medians of interleaved rounds, so that a noisy shared machine slows
the reference and the candidate alike and their ratio holds."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable


def per_call(fn: Callable[[], object], number: int) -> float:
    """Seconds per call of ``fn`` over ``number`` calls."""
    t0 = time.perf_counter()
    for _ in range(number):
        fn()
    return (time.perf_counter() - t0) / number


def interleaved(candidates: dict[str, Callable[[], object]], number: int = 1000, rounds: int = 15
                ) -> dict[str, float]:
    """Median seconds per call of each candidate, measured in alternating rounds."""
    for fn in candidates.values():  # warm-up
        per_call(fn, max(1, number // 10))
    samples: dict[str, list[float]] = {k: [] for k in candidates}
    for _ in range(rounds):
        for name, fn in candidates.items():
            samples[name].append(per_call(fn, number))
    return {k: statistics.median(v) for k, v in samples.items()}
