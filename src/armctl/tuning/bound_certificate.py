"""The certified route of :func:`~armctl.tuning.model_bounds`, for arms whose joints are all revolute.

M(q) and the potential energy U(q) are then trigonometric polynomials, known exactly from samples
(:mod:`armctl.tuning.trig_poly`), and so are ∂g/∂q = ∂²U/∂q², C and ∂M/∂q. A branch and bound over boxes of the
joint ranges turns that into rigorous bounds. On a box with centre q₀ and half-widths r, for δ in the box:

* λ_m, λ_M: M(q₀ + δ) = M(q₀) + Σ_j δ_j ∂_jM(q₀) + R, ‖R‖ ≤ ½ rᵀ B r (B from the Fourier coefficients,
  :meth:`TrigPoly.curvature`). λ_min of the affine part is concave in δ, so its minimum over the box is at a
  vertex; hence λ_min(M) ≥ min over the 2^d vertices of λ_min(M(q₀) + Σ ±r_j ∂_jM(q₀)) − ½ rᵀBr, and likewise
  for λ_max. The remainder is also bounded relative to the mean inertia, R ⪰ −ε diag(M̄) with ε from the
  coefficients scaled by diag(M̄)^(−½), and entry by entry, R ⪰ −diag(Σ_b |R_ab| w_b / w_a) with
  w = diag(M̄)^(−½) (which keeps the shift of a light joint's row small); the best of the three is kept.
* k_g: ‖∂²U(q₀ + δ)‖ ≤ max over vertices ‖H(q₀) + Σ ±r_j ∂_jH(q₀)‖ + ½ rᵀ B_H r (a norm is convex).
* k_C and k_M: the same for the norms of the stacked maps F = [C(q, e₁) … C(q, eₙ)] and [∂₁M … ∂ₙM] (n × n²),
  whose values and first derivatives at q₀ come from the Fourier series of M: ‖F(q₀ + δ)‖ ≤ max over vertices
  ‖F(q₀) + Σ ±r_j ∂_jF(q₀)‖ + ½ rᵀ B_F r. As ‖C(q, x) y‖ = ‖F (x ⊗ y)‖ ≤ ‖F‖ ‖x‖ ‖y‖ (and the same for ∂M), ‖F‖
  bounds the constants; this last step is itself a relaxation (a unit x ⊗ y need not reach ‖F‖).

The boxes whose bound is furthest out are split first (along the dimension that contributes most to the
remainder) until the best bound is within ``tolerance`` of the best value found at a point, or ``max_boxes``
boxes have been evaluated; the bound reported is the worst over the boxes left, so it holds over the whole
ranges either way. A small slack covers round-off (a multiple of the fit's residual at random points).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from armctl._checks import FloatArray
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError
from armctl.tuning.branch_and_bound import (
    MAX_VERTEX_DIMENSION,
    Certificate,
    branch_and_bound,
    spectral_norms,
    vertices,
)
from armctl.tuning.trig_poly import TrigPoly, depends_on, stencil_derivatives


class RevoluteModel:
    """M and U of an all-revolute arm as trigonometric polynomials, fitted and checked once."""

    def __init__(self, dyn: Dynamics, seed: int = 0) -> None:
        revolute = [j.kind == "revolute" for j in dyn.model.joints]
        if not all(revolute):
            names = [j.name for j, r in zip(dyn.model.joints, revolute, strict=True) if not r]
            raise InvalidParameterError(
                f"certified bounds need an arm whose joints are all revolute; {names} are not: use method='sampled'",
                value=names,
            )
        self.dyn = dyn
        n = self.n = dyn.n
        rng = np.random.default_rng(seed)
        anchor = np.zeros(n)
        self.mass = TrigPoly(dyn.mass_matrix, n, depends_on(dyn.mass_matrix, n, rng), 2, anchor)

        def potential(q: FloatArray) -> FloatArray:
            return np.array(dyn.potential_energy(q))

        self.potential = TrigPoly(potential, n, depends_on(dyn.gravity_torque, n, rng), 1, anchor)
        checks = rng.uniform(-np.pi, np.pi, (12, n))
        res_m = self.mass.residual(dyn.mass_matrix, checks)
        grad = np.stack([self._gradient(q) for q in checks])
        res_g = float(np.abs(grad - np.stack([dyn.gravity_torque(q) for q in checks])).max())
        scale_m = self.mass.scale or 1.0
        scale_g = max(float(np.abs(grad).max()), 1e-300)
        if res_m > 1e-8 * scale_m or res_g > 1e-7 * max(scale_g, 1.0):
            raise InvalidParameterError(
                f"the model of {dyn.model.name!r} is not the trigonometric polynomial an arm of revolute joints "
                f"gives (fit residual {res_m:.3g} in M, {res_g:.3g} in g at random points), so its bounds cannot be "
                "certified this way: use method='sampled'",
                value=(res_m, res_g),
            )
        self.slack_m = 100 * res_m + 1e-12 * scale_m
        self.slack_g = 100 * res_g + 1e-12 * scale_g

    def _gradient(self, q: FloatArray) -> FloatArray:
        return np.array([self.potential.evaluate(q, (j,))[0] for j in range(self.n)])

    # ------------------------------------------------------------------------------------------ inertia
    def inertia(
        self, lo: FloatArray, hi: FloatArray, sense: int, best: float, tolerance: float, max_boxes: int
    ) -> Certificate:
        """λ_m (sense −1: a lower bound of min λ_min) or λ_M (+1: an upper bound of max λ_max) over [lo, hi]."""
        poly, dyn, n = self.mass, self.dyn, self.n
        act = poly.active
        d = len(act)
        mean = np.real(poly.coef[np.all(poly.freqs == 0, axis=1)][0]) if len(poly.coef) else np.eye(n)
        weights = np.maximum(np.abs(np.diag(mean)), 1e-300)
        s = 1.0 / np.sqrt(weights)
        b_abs = poly.curvature(spectral_norms) if d else np.zeros((0, 0))
        b_rel = poly.curvature(lambda c: spectral_norms(c * s[:, None] * s[None, :])) if d else np.zeros((0, 0))
        # entrywise: |R_ab| ≤ ½ rᵀ B^{ab} r, then R ⪰ −diag(Σ_b |R_ab| w_b / w_a) for any w > 0; w = diag(M̄)^(−½)
        # keeps the shift of a light joint's row small (its couplings to heavy joints are scaled down)
        k_abs = np.abs(poly.freqs).astype(float)
        b_entry = np.einsum("kj,kl,kab->abjl", k_abs, k_abs, np.abs(poly.coef)) if d else np.zeros((n, n, 0, 0))
        ratio = s[None, :] / s[:, None]  # w_b / w_a with w = s
        signs = vertices(d)
        eye, wdiag = np.eye(n), np.diag(weights)
        anchor = (lo + hi) / 2

        def evaluate(c: FloatArray, r: FloatArray) -> tuple[float, float]:
            q = anchor.copy()
            q[act] = c
            m0, dm = stencil_derivatives(dyn.mass_matrix, q, act, 2)
            e_abs = float(0.5 * r @ b_abs @ r) + self.slack_m
            e_rel = float(0.5 * r @ b_rel @ r)
            value = float(np.linalg.eigvalsh(m0)[0 if sense < 0 else -1])
            if d > MAX_VERTEX_DIMENSION:  # Weyl: the linear part moves eigenvalues by at most Σ r_j ‖∂_jM‖
                spread = float(np.sum(r * np.linalg.norm(dm, 2, axis=(1, 2))))
                return -sense * (value + sense * (spread + e_abs)), -sense * value
            corners = m0 + np.einsum("vj,jab->vab", signs * r, dm)
            if sense < 0:
                shift = np.sum(0.5 * np.einsum("abjl,j,l->ab", b_entry, r, r) * ratio, axis=1) + self.slack_m
                shifts = np.stack([e_abs * eye, e_rel * wdiag + self.slack_m * eye, np.diag(shift)])
                low = np.linalg.eigvalsh(corners[None] - shifts[:, None])[..., 0]  # (3 bounds, vertices)
                return float(low.min(axis=1).max()), value
            shifts = np.stack([e_abs * eye, e_rel * wdiag + self.slack_m * eye])
            high = np.linalg.eigvalsh(corners[None] + shifts[:, None])[..., -1]
            return -float(high.max(axis=1).min()), -value

        # the remainder's weight per pair of angles: the relative one for λ_M, the light rows' shift for λ_m
        b_split = b_rel if sense > 0 or not d else np.einsum("abjl,ab->ajl", b_entry, ratio).max(axis=0)

        def split(r: FloatArray) -> int:
            return int(np.argmax(r * (b_split @ r))) if r.size else 0

        return self._run(evaluate, lo, hi, act, split, sense, best, tolerance, max_boxes, 10 * self.slack_m)

    # ------------------------------------------------------------------------------------------ gravity
    def gravity(self, lo: FloatArray, hi: FloatArray, best: float, tolerance: float, max_boxes: int) -> Certificate:
        """An upper bound of max ‖∂g/∂q‖₂ over [lo, hi] (k_g)."""
        poly, n = self.potential, self.n
        act = poly.active
        d = len(act)
        k = poly.freqs.astype(float)
        c = poly.coef.reshape(-1)
        full = np.zeros((len(k), n))
        full[:, act] = k
        hess = -np.einsum("ki,kj,k->kij", full, full, c)  # H_k = −k kᵀ c_k
        dhess = 1j * np.einsum("km,kij->kmij", k, hess)  # ∂_m H_k = i k_m H_k (over the active m)
        sizes = np.abs(c) * np.sum(k * k, axis=1)  # ‖k kᵀ‖ |c_k|
        b_h = np.einsum("kj,kl,k->jl", np.abs(k), np.abs(k), sizes)
        signs = vertices(d)
        anchor = (lo + hi) / 2

        def evaluate(cc: FloatArray, r: FloatArray) -> tuple[float, float]:
            q = anchor.copy()
            q[act] = cc
            phase = np.exp(1j * (k @ q[act]))
            h0 = np.real(np.tensordot(phase, hess, 1))
            value = float(np.abs(np.linalg.eigvalsh(h0)).max())
            remainder = 0.5 * r @ b_h @ r + self.slack_g
            if not d:
                return -(value + remainder), -value
            dh = np.real(np.tensordot(phase, dhess, 1))
            if d > MAX_VERTEX_DIMENSION:
                spread = float(np.sum(r * np.linalg.norm(dh, 2, axis=(1, 2))))
                return -(value + spread + remainder), -value
            corners = h0 + np.einsum("vj,jab->vab", signs * r, dh)
            outer = float(np.abs(np.linalg.eigvalsh(corners)).max()) + remainder
            return -outer, -value

        def split(r: FloatArray) -> int:
            return int(np.argmax(r * (b_h @ r))) if r.size else 0

        return self._run(evaluate, lo, hi, act, split, 1, best, tolerance, max_boxes, 10 * self.slack_g)

    # ------------------------------------------------------------------------------- Coriolis and ∂M/∂q
    def _stack_coefficients(self, kind: str) -> FloatArray:
        """Fourier coefficients (K, n, n²) of F = [C(q, e₁) … C(q, eₙ)] (``"coriolis"``) or [∂₁M … ∂ₙM]."""
        poly, n = self.mass, self.n
        k = np.zeros((len(poly.freqs), n))
        k[:, poly.active] = poly.freqs
        dm = 1j * k[:, :, None, None] * poly.coef[:, None, :, :]  # (K, j, a, b): ∂_j M
        return self._stack(dm, kind)

    @staticmethod
    def _stack(dm: np.ndarray, kind: str) -> np.ndarray:
        """F from D[j] = ∂_jM (any leading batch axis): Γ[i, j, m] = ½(∂_m M_ij + ∂_j M_im − ∂_i M_jm)."""
        if kind == "coriolis":
            gamma = 0.5 * (
                np.einsum("...mij->...ijm", dm) + np.einsum("...jim->...ijm", dm) - np.einsum("...ijm->...ijm", dm)
            )
            return np.moveaxis(gamma, -1, -2).reshape((*dm.shape[:-3], dm.shape[-1], -1))  # columns (m, j)
        return np.moveaxis(dm, -3, -2).reshape((*dm.shape[:-3], dm.shape[-1], -1))  # [∂₁M … ∂ₙM]: (a, (j, b))

    def stacked_norm(self, lo: FloatArray, hi: FloatArray, kind: str, tolerance: float, max_boxes: int) -> Certificate:
        """An upper bound of max ‖F(q)‖₂ over [lo, hi] for F of :meth:`_stack_coefficients`: at a box centre F
        and ∂F/∂q_l from the Fourier series of M (its first and second derivatives), then the vertices of the
        affine part plus ½ rᵀ B r (‖∂²F/∂q_l∂q_m‖ ≤ B_lm)."""
        poly, n = self.mass, self.n
        act = poly.active
        d = len(act)
        k = poly.freqs.astype(float)
        sizes = spectral_norms(self._stack_coefficients(kind)) if d else np.zeros(0)
        b_f = np.einsum("kj,kl,k->jl", np.abs(k), np.abs(k), sizes)
        flat = poly.coef.reshape(len(poly.coef), -1)
        signs = vertices(d)
        anchor = (lo + hi) / 2

        def evaluate(c: FloatArray, r: FloatArray) -> tuple[float, float]:
            if not d:
                return -self.slack_m, 0.0
            phase = np.exp(1j * (k @ c))
            first = np.real((1j * k * phase[:, None]).T @ flat).reshape(d, n, n)  # ∂_j M at c
            second = np.real((-(k[:, :, None] * k[:, None, :]).reshape(len(k), -1) * phase[:, None]).T @ flat)
            second = second.reshape(d, d, n, n)  # ∂_l ∂_j M at c
            dm = np.zeros((n, n, n))
            dm[act] = first
            ddm = np.zeros((d, n, n, n))
            ddm[:, act] = second
            f0 = self._stack(dm, kind)
            df = self._stack(ddm, kind)  # (l, n, n²): ∂_l F
            value = float(np.linalg.norm(f0, 2))
            remainder = 0.5 * r @ b_f @ r + self.slack_m
            if d > MAX_VERTEX_DIMENSION:
                spread = float(np.sum(r * np.linalg.norm(df, 2, axis=(1, 2))))
                return -(value + spread + remainder), -value
            corners = f0 + np.einsum("vl,lab->vab", signs * r, df)
            gram = corners @ corners.transpose(0, 2, 1)
            outer = float(np.sqrt(max(np.linalg.eigvalsh(gram)[:, -1].max(), 0.0))) + remainder
            return -outer, -value

        def split(r: FloatArray) -> int:
            return int(np.argmax(r * (b_f @ r))) if r.size else 0

        lower, found, where, boxes, converged = branch_and_bound(
            evaluate, lo[act], hi[act], split, tolerance, max_boxes, 0.0, 10 * self.slack_m
        )
        q = None
        if where is not None:
            q = anchor.copy()
            q[act] = where
        return Certificate(-lower, -found, q, boxes, converged)

    def _run(
        self,
        evaluate: Callable[[FloatArray, FloatArray], tuple[float, float]],
        lo: FloatArray,
        hi: FloatArray,
        act: list[int],
        split: Callable[[FloatArray], int],
        sense: int,
        best: float,
        tolerance: float,
        max_boxes: int,
        atol: float,
    ) -> Certificate:
        """Branch and bound over the active angles; ``sense`` −1 for a minimum, +1 for a maximum (``evaluate``
        then works on negated values, as :func:`branch_and_bound` minimises); ``best``: a value attained at some
        point, the incumbent to beat (where is then None unless a box centre beats it)."""
        lower, found, where, boxes, converged = branch_and_bound(
            evaluate, lo[act], hi[act], split, tolerance, max_boxes, -best if sense > 0 else best, atol
        )
        q = None
        if where is not None:
            q = (lo + hi) / 2
            q[act] = where
        if sense > 0:
            return Certificate(-lower, -found, q, boxes, converged)
        return Certificate(lower, found, q, boxes, converged)
