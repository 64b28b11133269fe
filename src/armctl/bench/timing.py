"""Timing helpers for the benchmarks: medians of interleaved rounds, so that a noisy shared machine slows
the reference and the candidate alike and their ratio holds."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable


def per_call(fn: Callable[[], object], number: int, clock: Callable[[], float] = time.perf_counter) -> float:
    """Seconds per call of ``fn`` over ``number`` calls (``clock``: wall time by default;
    ``time.process_time`` for this process's CPU time)."""
    t0 = clock()
    for _ in range(number):
        fn()
    return (clock() - t0) / number


def interleaved_samples(
    candidates: dict[str, Callable[[], object]],
    number: int = 1000,
    rounds: int = 15,
    clock: Callable[[], float] = time.perf_counter,
) -> dict[str, list[float]]:
    """Seconds per call of each candidate in each of ``rounds`` alternating rounds (after a warm-up)."""
    for fn in candidates.values():
        per_call(fn, max(1, number // 10), clock)
    samples: dict[str, list[float]] = {k: [] for k in candidates}
    for _ in range(rounds):
        for name, fn in candidates.items():
            samples[name].append(per_call(fn, number, clock))
    return samples


def interleaved(
    candidates: dict[str, Callable[[], object]],
    number: int = 1000,
    rounds: int = 15,
    clock: Callable[[], float] = time.perf_counter,
) -> dict[str, float]:
    """Median seconds per call of each candidate, measured in alternating rounds."""
    return {k: statistics.median(v) for k, v in interleaved_samples(candidates, number, rounds, clock).items()}


def paired_ratio(
    candidate: Callable[[], object], reference: Callable[[], object], number: int = 200, rounds: int = 75
) -> dict[str, float]:
    """Cost of ``candidate`` relative to ``reference``: in each round both run ``number`` calls back to back
    and their ratio is taken; returns the median ratio with its quartiles (``ratio_q1``, ``ratio_q3``), and
    the median seconds per call of each. Pairing the ratio round by round cancels the slow swings of a
    shared machine's speed, which a ratio of separate medians keeps."""
    per_call(candidate, max(1, number // 10))  # warm-up
    per_call(reference, max(1, number // 10))
    cand: list[float] = []
    ref: list[float] = []
    for k in range(rounds):
        if k % 2:  # alternate which goes first
            ref.append(per_call(reference, number))
            cand.append(per_call(candidate, number))
        else:
            cand.append(per_call(candidate, number))
            ref.append(per_call(reference, number))
    ratios = sorted(c / r for c, r in zip(cand, ref, strict=True))
    q1, med, q3 = statistics.quantiles(ratios, n=4)
    return {
        "ratio": med,
        "ratio_q1": q1,
        "ratio_q3": q3,
        "candidate_s": statistics.median(cand),
        "reference_s": statistics.median(ref),
    }
