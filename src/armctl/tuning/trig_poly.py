"""Functions of the joint angles that are trigonometric polynomials, known exactly from samples.

In an arm whose joints are all revolute, each joint rotates what follows it by R(q_j), whose entries are
cos q_j, sin q_j and constants. So every link's position is of degree ≤ 1 in each (cos q_j, sin q_j), the
potential energy U too, and the mass matrix M = Σ m Jᵥᵀ Jᵥ + J_ωᵀ R I Rᵀ J_ω (+ the rotors' constant terms) of
degree ≤ 2 in each q_j:

    f(q) = Σ_k c_k exp(i k·q),   k ∈ {−D, …, D}^d   (D = 2 for M, D = 1 for U)

over the d angles f depends on. Such an f is fixed exactly by its values on the grid of N = 2D + 1 points
2πm/N per angle (the discrete Fourier transform gives the c_k), and so are its derivatives, as finite sums:

    ∂f/∂q_j (q) = Σ_{m=1}^{N−1} w_m f(q + 2πm/N e_j),   w_m = (1/N) Σ_k i k exp(−2πi k m/N)

(no step size, no truncation error). :class:`TrigPoly` holds the coefficients, evaluates f and its derivatives,
and bounds their variation: ‖∂²f/∂q_j∂q_l‖ ≤ Σ_k |k_j k_l| ‖c_k‖ everywhere. Whether f really is such a
polynomial is checked, not assumed: the fit must reproduce f at random points (:meth:`TrigPoly.residual`).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable

import numpy as np

from armctl._checks import FloatArray


def grid_nodes(degree: int) -> FloatArray:
    """The N = 2D + 1 sample angles 2πm/N of a degree-D trigonometric polynomial in one angle."""
    n = 2 * degree + 1
    return 2 * np.pi * np.arange(n) / n


def derivative_weights(degree: int) -> FloatArray:
    """w_m with f'(q) = Σ_m w_m f(q + 2πm/N) for every trigonometric polynomial f of degree ≤ D (w_0 = 0)."""
    n = 2 * degree + 1
    k = np.fft.fftfreq(n, 1.0 / n)
    t = grid_nodes(degree)
    return np.real(np.array([np.sum(1j * k * np.exp(-1j * k * tm)) for tm in t]) / n)


def depends_on(fn: Callable[[FloatArray], FloatArray], n: int, rng: np.random.Generator) -> list[int]:
    """The angles ``fn`` depends on, found by moving each one at three random points (a variable it ignores
    leaves it unchanged to round-off; the fit's check at random points catches a wrong answer)."""
    points = rng.uniform(-np.pi, np.pi, (3, n))
    base = [np.asarray(fn(q), dtype=float) for q in points]
    scale = max(float(np.abs(b).max()) for b in base) or 1.0
    active = []
    for j in range(n):
        moved = 0.0
        for q, b in zip(points, base, strict=True):
            for shift in (1.1, 2.3):
                p = q.copy()
                p[j] += shift
                moved = max(moved, float(np.abs(np.asarray(fn(p)) - b).max()))
        if moved > 1e-11 * scale:
            active.append(j)
    return active


class TrigPoly:
    """An array-valued f(q) = Σ_k c_k exp(i k·q[active]) of degree ≤ ``degree`` in each active angle, fitted to
    ``fn`` on the sample grid (the other angles held at ``anchor``)."""

    def __init__(
        self, fn: Callable[[FloatArray], FloatArray], n: int, active: list[int], degree: int, anchor: FloatArray
    ) -> None:
        self.n, self.active, self.degree = n, list(active), degree
        d = len(self.active)
        nodes = grid_nodes(degree)
        size = len(nodes)
        first = np.asarray(fn(anchor), dtype=float)
        self.shape = first.shape
        samples = np.empty((size,) * d + self.shape)
        q = anchor.astype(float).copy()
        for idx in itertools.product(range(size), repeat=d):
            q[self.active] = nodes[list(idx)]
            samples[idx] = fn(q)
        coef = np.fft.fftn(samples, axes=tuple(range(d))) / size**d if d else samples.astype(complex)
        freq1 = np.fft.fftfreq(size, 1.0 / size).astype(int)
        self.freqs = (
            np.stack(np.meshgrid(*[freq1] * d, indexing="ij"), -1).reshape(-1, d) if d else np.zeros((1, 0), int)
        )
        self.coef = coef.reshape((-1, *self.shape))
        keep = np.abs(self.coef).reshape(len(self.coef), -1).max(axis=1) > 0  # exact zeros cost nothing to drop
        self.freqs, self.coef = self.freqs[keep], self.coef[keep]
        self.scale = float(np.abs(samples).max()) if samples.size else 0.0

    def _phases(self, qs: FloatArray) -> FloatArray:
        return np.exp(1j * (np.atleast_2d(qs)[:, self.active] @ self.freqs.T))

    def evaluate(self, qs: FloatArray, orders: tuple[int, ...] = ()) -> FloatArray:
        """f (``orders`` empty) or the derivative ∂^|orders| f / ∂q_{orders[0]} ∂q_{orders[1]} … at the points
        ``qs`` (B, n) [positions in the full q]: a (B, *shape) array."""
        weight = np.ones(len(self.freqs), dtype=complex)
        for j in orders:
            if j not in self.active:
                return np.zeros((len(np.atleast_2d(qs)), *self.shape))
            weight = weight * (1j * self.freqs[:, self.active.index(j)])
        flat = self.coef.reshape(len(self.coef), -1) * weight[:, None]
        return np.real(self._phases(qs) @ flat).reshape((-1, *self.shape))

    def residual(self, fn: Callable[[FloatArray], FloatArray], points: FloatArray) -> float:
        """max |fit − fn| over ``points``: round-off if ``fn`` is such a polynomial."""
        fit = self.evaluate(points)
        return max(float(np.abs(fit[i] - np.asarray(fn(p))).max()) for i, p in enumerate(points))

    def curvature(self, norm: Callable[[np.ndarray], FloatArray]) -> FloatArray:
        """B (d×d) with sup_q ‖∂²f/∂q_j∂q_l‖ ≤ B_jl over the active angles (the triangle inequality over the
        terms), each coefficient measured by ``norm`` (an upper bound of the norm used)."""
        k = np.abs(self.freqs).astype(float)
        sizes = norm(self.coef)
        return np.einsum("kj,kl,k->jl", k, k, sizes)

    def slopes(self, norm: Callable[[np.ndarray], FloatArray]) -> FloatArray:
        """L (d,) with sup_q ‖∂f/∂q_j‖ ≤ L_j over the active angles."""
        return np.abs(self.freqs).astype(float).T @ norm(self.coef)


def stencil_derivatives(
    fn: Callable[[FloatArray], FloatArray], q: FloatArray, active: list[int], degree: int
) -> tuple[FloatArray, FloatArray]:
    """(f(q), (∂f/∂q_j (q) for j in ``active``)) of a trigonometric polynomial of degree ≤ ``degree`` in each
    angle, exactly, from 1 + 2D·d evaluations of ``fn``."""
    f0 = np.asarray(fn(q), dtype=float)
    w, nodes = _STENCILS.get(degree) or _STENCILS.setdefault(degree, (derivative_weights(degree), grid_nodes(degree)))
    out = np.zeros((len(active), *f0.shape))
    p = q.copy()
    for a, j in enumerate(active):
        for m in range(1, len(nodes)):
            p[j] = q[j] + nodes[m]
            out[a] += w[m] * fn(p)
        p[j] = q[j]
    return f0, out


_STENCILS: dict[int, tuple[FloatArray, FloatArray]] = {}
