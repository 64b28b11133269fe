"""The sampled route of :func:`~armctl.tuning.model_bounds`: the model's constants at a point, and their extremes
over the joint ranges estimated on a large sample refined by local optimisation.

At a configuration q:

* λ_min(M(q)), λ_max(M(q)) [kg·m²];
* ‖∂g/∂q (q)‖₂ [N·m/rad], ∂g/∂q by central differences of :meth:`~armctl.Dynamics.gravity_torque`;
* max ‖C(q, x) y‖ over unit x, y [kg·m²], with C(q, x) = Σ_k x_k C(q, e_k) (C is linear in q̇);
* max ‖Σ_j u_j ∂M/∂q_j (q) z‖ over unit u, z [kg·m²/rad], ∂M/∂q_j by central differences.

The last two are norms of bilinear maps, found by alternating power iterations (a local maximum; two starts).
Every extreme reported is attained at the point reported: an estimate from inside (the true λ_m is at most the
estimate, the true λ_M and k's at least).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from armctl._checks import FloatArray
from armctl.dynamics.base import Dynamics

#: the constants, in the order they are reported
QUANTITIES = ("lambda_min", "lambda_max", "k_g", "k_c", "k_m")
#: +1: the extreme is a maximum; −1: a minimum
SENSE = {"lambda_min": -1, "lambda_max": 1, "k_g": 1, "k_c": 1, "k_m": 1}


def bilinear_norm(maps: FloatArray, start: FloatArray | None = None, iterations: int = 60) -> tuple[float, FloatArray]:
    """(max ‖Σ_k x_k A_k y‖ over unit x, y, the x attaining it) for ``maps`` = (A_1, …, A_m) stacked as an
    (m, p, r) array.

    Alternating maximisation: for fixed x the best y gives σ_max(Σ_k x_k A_k), for fixed y the best x gives
    σ_max([A_1 y … A_m y]); no step decreases the value, which is attained at the unit (x, y) of the step. From
    ``start`` (a previous x, e.g. at a nearby configuration), else from two starts: the best rank-one fit of the
    top singular vector of [A_1 … A_m], and the largest A_k. A local maximum, so at most the true norm, which is
    at most σ_max([A_1 … A_m])."""
    m = maps.shape[0]
    if not np.any(maps):
        return 0.0, np.eye(m)[0]
    if start is not None:
        starts = [start]
    else:
        stacked = maps.transpose(1, 0, 2).reshape(maps.shape[1], -1)  # [A_1 … A_m]: p × (m r)
        top = np.linalg.svd(stacked)[2][0].reshape(m, -1)  # ≈ x ⊗ y where the map is nearly rank one in x ⊗ y
        starts = [np.linalg.svd(top)[0][:, 0], np.eye(m)[int(np.argmax(np.linalg.norm(maps, axis=(1, 2))))]]
    best, best_x = -1.0, starts[0]
    for x in starts:
        value = -1.0
        for _ in range(iterations):
            a_x = np.tensordot(x, maps, axes=1)  # Σ x_k A_k
            y = np.linalg.svd(a_x)[2][0]
            _, s, vt = np.linalg.svd((maps @ y).T)  # columns A_k y
            x = vt[0]
            if s[0] <= value * (1 + 1e-10):
                break
            value = float(s[0])
        if value > best:
            best, best_x = value, x
    return best, best_x


class PointConstants:
    """The constants of ``dyn`` at single configurations (see the module docstring); ``step`` [rad] of the
    central differences."""

    def __init__(self, dyn: Dynamics, step: float = 1e-6) -> None:
        self.dyn = dyn
        self.n = dyn.n
        self.step = step
        self._eye = np.eye(self.n)

    def gravity_jacobian(self, q: FloatArray) -> FloatArray:
        h, g = self.step, self.dyn.gravity_torque
        return np.column_stack([(g(q + h * e) - g(q - h * e)) / (2 * h) for e in self._eye])

    def coriolis_maps(self, q: FloatArray) -> FloatArray:
        """(C(q, e_1), …, C(q, e_n)) as an (n, n, n) array."""
        return np.stack([self.dyn.coriolis_matrix(q, e) for e in self._eye])

    def mass_derivatives(self, q: FloatArray) -> FloatArray:
        """(∂M/∂q_1, …, ∂M/∂q_n) as an (n, n, n) array."""
        h, m = self.step, self.dyn.mass_matrix
        return np.stack([(m(q + h * e) - m(q - h * e)) / (2 * h) for e in self._eye])

    def function(self, name: str, warm: bool = False) -> Callable[[FloatArray], float]:
        """q ↦ the constant ``name`` at q. ``warm``: the bilinear norms start from the x of the previous call
        alone (for a local optimisation, whose calls are at nearby points), else from the cold starts too."""
        if name == "lambda_min":
            return lambda q: float(np.linalg.eigvalsh(self.dyn.mass_matrix(q))[0])
        if name == "lambda_max":
            return lambda q: float(np.linalg.eigvalsh(self.dyn.mass_matrix(q))[-1])
        if name == "k_g":
            return lambda q: float(np.linalg.norm(self.gravity_jacobian(q), 2))
        if name in ("k_c", "k_m"):
            maps = self.coriolis_maps if name == "k_c" else self.mass_derivatives
            last: list[FloatArray] = []

            def norm(q: FloatArray) -> float:
                a = maps(q)
                value, x = bilinear_norm(a, last[0] if warm and last else None)
                if last and not warm:
                    again, x_again = bilinear_norm(a, last[0])
                    if again > value:
                        value, x = again, x_again
                last[:] = [x]
                return value

            return norm
        raise KeyError(name)

    def all(self, q: FloatArray) -> dict[str, float]:
        eig = np.linalg.eigvalsh(self.dyn.mass_matrix(q))
        return {
            "lambda_min": float(eig[0]),
            "lambda_max": float(eig[-1]),
            "k_g": float(np.linalg.norm(self.gravity_jacobian(q), 2)),
            "k_c": bilinear_norm(self.coriolis_maps(q))[0],
            "k_m": bilinear_norm(self.mass_derivatives(q))[0],
        }


def _refine(
    fn: Callable[[FloatArray], float], sense: int, q0: FloatArray, lo: FloatArray, hi: FloatArray
) -> FloatArray:
    """A local extremum of ``fn`` in the box from q0 (L-BFGS-B, central-difference gradients)."""
    from scipy.optimize import minimize

    h = 1e-5 * np.maximum(1.0, hi - lo)

    def f(q: FloatArray) -> float:
        return -sense * fn(np.clip(q, lo, hi))

    def grad(q: FloatArray) -> FloatArray:
        out = np.empty(len(q))
        for j in range(len(q)):
            e = np.zeros(len(q))
            e[j] = h[j]
            out[j] = (f(q + e) - f(q - e)) / (2 * h[j])
        return out

    fixed = hi <= lo  # a joint held at one value: nothing to optimise along it
    res = minimize(f, q0, jac=grad, method="L-BFGS-B", bounds=list(zip(lo, hi, strict=True)), options={"maxiter": 40})
    q = np.clip(res.x, lo, hi)
    q[fixed] = lo[fixed]
    return q


def search_extremes(
    dyn: Dynamics,
    lo: FloatArray,
    hi: FloatArray,
    samples: int,
    refine: int,
    seed: int,
    quantities: tuple[str, ...] = QUANTITIES,
) -> dict[str, tuple[float, FloatArray]]:
    """For each constant, (its extreme value, the q it is attained at) over the box [lo, hi]: ``samples`` points
    (uniform, with the box's centre), then ``refine`` local optimisations from the best of them.

    The bilinear norms (k_C, k_M) cost a few singular value decompositions each, so the sample is ranked by
    their cheap upper bound, the spectral norm of the stacked maps [A_1 … A_n], and only the best tenth (at least
    ``refine`` points) is evaluated exactly."""
    rng = np.random.default_rng(seed)
    points = np.vstack([(lo + hi) / 2, lo + (hi - lo) * rng.random((max(samples - 1, 0), len(lo)))])
    pc = PointConstants(dyn)
    values = {k: np.empty(len(points)) for k in quantities}
    for i, q in enumerate(points):
        if "lambda_min" in quantities or "lambda_max" in quantities:
            eig = np.linalg.eigvalsh(dyn.mass_matrix(q))
            if "lambda_min" in quantities:
                values["lambda_min"][i] = eig[0]
            if "lambda_max" in quantities:
                values["lambda_max"][i] = eig[-1]
        if "k_g" in quantities:
            values["k_g"][i] = np.linalg.norm(pc.gravity_jacobian(q), 2)
        if "k_c" in quantities:
            values["k_c"][i] = _stacked_norm(pc.coriolis_maps(q))
        if "k_m" in quantities:
            values["k_m"][i] = _stacked_norm(pc.mass_derivatives(q))
    out: dict[str, tuple[float, FloatArray]] = {}
    for k in quantities:
        sense = SENSE[k]
        fn = pc.function(k)
        order = np.argsort(-sense * values[k])
        if k in ("k_c", "k_m"):  # the exact norm on the best tenth of the ranking by its upper bound
            top = order[: max(len(order) // 10, refine, 1)]
            exact = np.array([fn(points[i]) for i in top])
            order = top[np.argsort(-exact)]
            best_val, best_q = float(exact.max()), points[order[0]].copy()
        else:
            best_val, best_q = float(values[k][order[0]]), points[order[0]].copy()
        for idx in order[:refine]:
            q = _refine(pc.function(k, warm=True), sense, points[idx], lo, hi)
            v = fn(q)  # evaluated again at the point reported (cold starts included)
            if sense * (v - best_val) > 0:
                best_val, best_q = v, q
        out[k] = (best_val, best_q)
    return out


def _stacked_norm(maps: FloatArray) -> float:
    """σ_max([A_1 … A_m]) ≥ the bilinear norm of (A_k)."""
    return float(np.linalg.norm(maps.transpose(1, 0, 2).reshape(maps.shape[1], -1), 2))
