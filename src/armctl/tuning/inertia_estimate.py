"""Computed torque with a constant or wrong inertia estimate M̂: when it stays stable, and how well it tracks.

The law τ = M̂ v + C q̇ + g, v = q̈_d + K_d ė + K_p e (e = q_d − q), on the arm M q̈ + C q̇ + g = τ gives

    ë + K_d ė + K_p e = η,    η = E(q) v − M⁻¹ ñ,    E(q) = I − M(q)⁻¹ M̂

(ñ the error in the velocity and gravity terms, zero when only the inertia is wrong). The robust-control
chapters of the textbooks rest on ‖E(q)‖ ≤ α < 1 over the ranges (Siciliano, Sciavicco, Villani & Oriolo,
*Robotics: Modelling, Planning and Control*, 2009, §8.5.3, who pick M̂ = 2/(1/λ_m + 1/λ_M)·I, for which
α = (λ_M − λ_m)/(λ_M + λ_m) < 1 on every arm; Spong, Hutchinson & Vidyasagar, *Robot Modeling and Control*,
2006, ch. 9, robust inverse dynamics). For computed torque without their extra robust term, the small-gain
theorem (peak-to-peak, each joint's error loop a linear filter) closes the argument: with z = K_d ė + K_p e = H η
and e = G η per joint,

    H(s) = (k_d s + k_p) / (s² + k_d s + k_p),   G(s) = 1 / (s² + k_d s + k_p),

‖η‖ ≤ α (‖q̈_d‖ + ‖z‖) + δ, so that if α γ < 1, with γ = max over joints of ‖h‖₁ (the L1 norm of H's impulse
response, ≥ 1), the loop is stable and, after the transient of the initial error,

    ‖e‖ ≤ max_j ‖g_j‖₁ · (α a + δ) / (1 − α γ),    a = sup ‖q̈_d‖,  δ = sup ‖M⁻¹ ñ‖

(‖g‖₁ = 1/k_p for a damping ratio ≥ 1). α < 1 alone, the textbook premise, is reported beside it. Both are
sufficient conditions for the continuous-time loop: they ignore sampling, which at high gains is what fails
first (see :func:`~armctl.tuning.conditions.sampled_data_condition`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, per_joint, real_array, scalar, whole_number
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError
from armctl.tuning.bounds import ModelBounds
from armctl.tuning.verdict import Verdict, certified_inputs, eigen_range, inequality


def impulse_l1_norms(kp: float, kd: float) -> tuple[float, float]:
    """(‖g‖₁, ‖h‖₁): L1 norms of the impulse responses of G = 1/(s² + k_d s + k_p) and H = (k_d s + k_p) G
    (peak-to-peak gains), to about 1e-6 relative; (inf, inf) unless k_p, k_d > 0."""
    if not (kp > 0 and kd > 0):
        return math.inf, math.inf
    disc = kd * kd - 4 * kp
    decay = kd / 2 if disc <= 0 else (kd - math.sqrt(disc)) / 2  # slowest pole −decay
    t = np.linspace(0.0, 60.0 / decay, 400001)
    if abs(disc) <= 1e-12 * kd * kd:
        p = -kd / 2
        g, dg = t * np.exp(p * t), (1 + p * t) * np.exp(p * t)
    elif disc > 0:
        r = math.sqrt(disc)
        p1, p2 = (-kd + r) / 2, (-kd - r) / 2
        g = (np.exp(p1 * t) - np.exp(p2 * t)) / (p1 - p2)
        dg = (p1 * np.exp(p1 * t) - p2 * np.exp(p2 * t)) / (p1 - p2)
    else:
        s, w = -kd / 2, math.sqrt(-disc) / 2
        g = np.exp(s * t) * np.sin(w * t) / w
        dg = np.exp(s * t) * (s * np.sin(w * t) + w * np.cos(w * t)) / w
    h = kd * dg + kp * g
    return float(np.trapezoid(np.abs(g), t)), float(np.trapezoid(np.abs(h), t))


def robust_inertia_estimate(bounds: ModelBounds) -> tuple[float, float]:
    """The constant estimate M̂ = c I with the smallest worst-case ‖I − M⁻¹M̂‖ over the ranges
    (Siciliano et al. §8.5.3).

    Parameters
    ----------
    bounds : ModelBounds
        :func:`~armctl.tuning.model_bounds` of the arm.

    Returns
    -------
    tuple of float
        (c, α): c = 2 λ_m λ_M / (λ_m + λ_M) [kg·m²] and α = (λ_M − λ_m) / (λ_M + λ_m).
    """
    lm, lM = bounds.lambda_min, bounds.lambda_max
    return 2 * lm * lM / (lm + lM), (lM - lm) / (lM + lm)


def _alpha(
    bounds: ModelBounds, estimate: Any, dynamics: Dynamics | None, samples: int, seed: int
) -> tuple[float, bool, str]:
    """(α ≥ sup ‖I − M⁻¹M̂‖ over the ranges, whether it rests on the bounds alone, how it was found)."""
    n = len(bounds.joint_ranges)
    lm, lM = bounds.lambda_min, bounds.lambda_max
    est = real_array(estimate, "inertia_estimate")
    if est.ndim == 0 or (est.shape == (n, n) and np.allclose(est, est[0, 0] * np.eye(n), rtol=0, atol=0)):
        c = float(est) if est.ndim == 0 else float(est[0, 0])
        if not c > 0:
            raise InvalidParameterError(f"inertia_estimate must be > 0, got {c}", value=estimate)
        # eig(M⁻¹ c) = c/λ, λ ∈ [λ_m, λ_M]: the norm of the symmetric I − c M⁻¹ is max |1 − c/λ|
        return max(abs(1 - c / lm), abs(1 - c / lM)), True, f"M̂ = {c:.5g} I: max |1 − c/λ| over [λ_m, λ_M]"
    e_min, e_max = eigen_range(est, n, "inertia_estimate")
    if dynamics is None:
        # I − M⁻¹M̂ = M^(−½) (I − M^(−½) M̂ M^(−½)) M^(½): the middle factor's eigenvalues lie in
        # 1 − [e_min/λ_M, e_max/λ_m], and the outer ones cost at most √(λ_M/λ_m)
        worst = max(abs(1 - e_min / lM), abs(1 - e_max / lm))
        return math.sqrt(lM / lm) * worst, True, "general M̂: √(λ_M/λ_m) max |1 − σ| from the bounds"
    if not isinstance(dynamics, Dynamics):
        raise InvalidParameterError(
            f"dynamics must be an armctl.Dynamics, got {type(dynamics).__name__}", value=dynamics
        )
    lo, hi = bounds.joint_ranges[:, 0], bounds.joint_ranges[:, 1]
    rng = np.random.default_rng(seed)
    worst = 0.0
    for q in lo + (hi - lo) * rng.random((samples, n)):
        worst = max(worst, float(np.linalg.norm(np.eye(n) - np.linalg.solve(dynamics.mass_matrix(q), est), 2)))
    return worst, False, f"general M̂: max ‖I − M⁻¹M̂‖ over {samples} sampled configurations"


def computed_torque_condition(
    bounds: ModelBounds,
    inertia_estimate: ArrayLike,
    kp: ArrayLike,
    kd: ArrayLike,
    max_acceleration: float = 0.0,
    bias_error: float = 0.0,
    dynamics: Dynamics | None = None,
    samples: int = 2000,
    seed: int = 0,
) -> Verdict:
    """Computed torque with a constant inertia estimate M̂ (see the module docstring): stable if α γ < 1.

    Parameters
    ----------
    bounds
        :func:`~armctl.tuning.model_bounds` of the arm.
    inertia_estimate
        M̂ [kg·m²]: a scalar c (M̂ = c I) or an s.p.d. n×n matrix. For c I, α comes from λ_m, λ_M exactly; for
        another matrix, from a sample of the ranges if ``dynamics`` is given (``samples``, ``seed``), else a
        cruder bound from λ_m, λ_M.
    kp, kd
        K_p [1/s²], K_d [1/s]: scalars or (n,) vectors (diagonal gains).
    max_acceleration
        a = sup ‖q̈_d‖ of the reference [rad/s²] (0 for a set-point).
    bias_error
        δ = sup ‖M⁻¹ (n̂ − n)‖ [rad/s²] if the velocity and gravity terms are wrong too (0: exact).
    dynamics : Dynamics, optional
        The arm, to sample α for a matrix estimate.
    samples : int, optional
        How many configurations of the ranges that sample takes.
    seed : int, optional
        Its random seed.

    Returns
    -------
    Verdict
        margin 1 − α γ, factor 1/(α γ); details ``alpha``, ``alpha_below_one`` (the textbook premise),
        ``gamma`` (max ‖h‖₁), ``g_l1`` (max ‖g‖₁ [s²]), ``error_bound`` [rad] (inf if the condition fails),
        ``robust_estimate`` and ``robust_alpha`` (:func:`robust_inertia_estimate`), ``alpha_from``.
    """
    n = len(bounds.joint_ranges)
    certified = certified_inputs(bounds, "lambda_min", "lambda_max")
    kps = per_joint(kp, n, "kp")
    kds = per_joint(kd, n, "kd")
    if not (np.all(kps > 0) and np.all(kds > 0) and np.isfinite(kps).all() and np.isfinite(kds).all()):
        raise InvalidParameterError(f"kp and kd must be finite and > 0, got {kps.tolist()}, {kds.tolist()}", value=kp)
    a = scalar(max_acceleration, "max_acceleration", nonnegative=True)
    delta = scalar(bias_error, "bias_error", nonnegative=True)
    alpha, from_bounds, how = _alpha(bounds, inertia_estimate, dynamics, whole_number(samples, "samples", 1), seed)
    norms: FloatArray = np.array([impulse_l1_norms(p, d) for p, d in zip(kps, kds, strict=True)])
    g_l1, gamma = float(norms[:, 0].max()), float(norms[:, 1].max())
    loop = alpha * gamma
    holds = loop < 1.0
    bound = g_l1 * (alpha * a + delta) / (1.0 - loop) if holds else math.inf
    c_best, alpha_best = robust_inertia_estimate(bounds)
    return Verdict(
        "computed torque with a constant inertia estimate",
        holds=holds,
        margin=1.0 - loop,
        factor=1.0 / loop if loop > 0 else math.inf,
        unit="",
        condition=inequality(f"α γ = {alpha:.4g} × {gamma:.4g} = {loop:.4g}", "<", "1", holds)
        + " (α = sup ‖I − M⁻¹M̂‖, γ = max ‖h‖₁)",
        certified=certified and from_bounds,
        source=(
            "small gain on ë + K_d ė + K_p e = (I − M⁻¹M̂) v; the premise α < 1 of Siciliano et al. 2009 §8.5.3 "
            "and Spong, Hutchinson & Vidyasagar 2006 ch. 9"
        ),
        details={
            "alpha": alpha,
            "alpha_below_one": alpha < 1.0,
            "gamma": gamma,
            "g_l1": g_l1,
            "error_bound": bound,
            "robust_estimate": c_best,
            "robust_alpha": alpha_best,
            "alpha_from": how,
        },
    )
