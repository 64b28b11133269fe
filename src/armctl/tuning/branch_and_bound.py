"""Branch and bound over boxes of the joint ranges, for the certified bounds of :mod:`armctl.tuning.bounds`."""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from armctl._checks import FloatArray

#: up to this many varying angles a box is bounded at its 2^d vertices; beyond, by Weyl's inequality
MAX_VERTEX_DIMENSION = 8


@dataclass(frozen=True)
class Certificate:
    """A rigorous bound over the ranges, ``best`` the most extreme value met at a box centre (at ``where``),
    ``boxes`` evaluated, ``converged``: the bound is within the tolerance of ``best``."""

    bound: float
    best: float
    where: FloatArray | None
    boxes: int
    converged: bool


def branch_and_bound(
    evaluate: Callable[[FloatArray, FloatArray], tuple[float, float]],
    lo: FloatArray,
    hi: FloatArray,
    split: Callable[[FloatArray], int],
    tolerance: float,
    max_boxes: int,
    best: float,
    atol: float = 0.0,
) -> tuple[float, float, FloatArray | None, int, bool]:
    """Minimise over the box [lo, hi]: ``evaluate(c, r)`` gives (a lower bound over the box with centre c and
    half-widths r, the value at c). Stops when the lower bound is within ``tolerance`` |best| + ``atol`` of the
    best value or after ``max_boxes`` boxes. Returns (lower bound over the whole box, best value, its centre or
    None if the ``best`` given was never improved, boxes evaluated, converged)."""
    heap: list[tuple[float, int, FloatArray, FloatArray]] = []
    where: FloatArray | None = None
    count = 0

    def push(c: FloatArray, r: FloatArray) -> None:
        nonlocal best, where, count
        lower, value = evaluate(c, r)
        count += 1
        if value < best:
            best, where = value, c
        heapq.heappush(heap, (min(lower, value), count, c, r))

    push((lo + hi) / 2, (hi - lo) / 2)
    converged = False
    while True:
        lower, _, c, r = heap[0]
        if best - lower <= tolerance * abs(best) + atol:
            converged = True
            break
        if count >= max_boxes or not r.size or r.max() <= 0:
            break
        heapq.heappop(heap)
        j = split(r)
        for side in (-1.0, 1.0):
            rr = r.copy()
            rr[j] /= 2
            cc = c.copy()
            cc[j] += side * rr[j]
            push(cc, rr)
    return heap[0][0], best, where, count, converged


def vertices(d: int) -> FloatArray:
    """The 2^d sign patterns (±1, …, ±1): the vertices of a box relative to its centre, in half-widths."""
    return np.array(list(itertools.product((-1.0, 1.0), repeat=d)), dtype=float).reshape(2**d, d)


def spectral_norms(coef: np.ndarray) -> FloatArray:
    """Spectral norms of a stack of (complex) matrices, via the largest eigenvalue of A Aᴴ."""
    a = coef.reshape(len(coef), coef.shape[1], -1)
    gram = a @ np.conj(a.transpose(0, 2, 1))
    return np.sqrt(np.maximum(np.linalg.eigvalsh(gram)[:, -1], 0.0))
