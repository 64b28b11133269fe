"""Textbook stability conditions on gains, from the bounds of :func:`~armctl.tuning.model_bounds`.

Each function returns a :class:`~armctl.tuning.verdict.Verdict` (holds, margin, the inequality with its numbers,
the source) before any simulation:

* :func:`pd_desired_gravity_condition`: PD with constant gravity compensation g(q_d);
* :func:`pid_condition`: PID without gravity compensation, tuned as Kelly, Santibáñez & Loría;
* :func:`~armctl.tuning.inertia_estimate.computed_torque_condition`: computed torque with a constant or wrong
  inertia estimate M̂, and the tracking error bound it gives;
* :func:`sampled_data_condition`: the critical gain of the sampled-data loop (zero-order hold, measurement
  delay) over the inertia range [λ_m, λ_M] instead of at one nominal inertia.

The continuous-time conditions say nothing about sampling, and the sampled-data one nothing about the
nonlinear coupling; ``armctl bench``'s stability maps draw both beside simulated cells.
"""

from __future__ import annotations

import math

from numpy.typing import ArrayLike

from armctl._checks import scalar, whole_number
from armctl.tuning.bounds import ModelBounds
from armctl.tuning.inertia_estimate import computed_torque_condition
from armctl.tuning.sampled import _gain_crossings, _stable_ranges
from armctl.tuning.verdict import Verdict, certified_inputs, eigen_range, inequality

__all__ = [
    "Verdict",
    "computed_torque_condition",
    "pd_desired_gravity_condition",
    "pid_condition",
    "sampled_data_condition",
]

KELLY_2005 = "Kelly, Santibáñez & Loría, Control of Robot Manipulators in Joint Space, Springer 2005"


def pd_desired_gravity_condition(bounds: ModelBounds, kp: ArrayLike) -> Verdict:
    """PD with desired gravity compensation, τ = K_p (q_d − q) − K_d q̇ + g(q_d), at a constant set-point q_d.

    The closed loop has a unique equilibrium, q = q_d, and it is globally asymptotically stable for every
    K_d ≻ 0 if

        λ_min(K_p) > k_g

    (Kelly 1997, "PD control with desired gravity compensation of robotic manipulators: a review", Int. J.
    Robotics Research 16(5); Kelly, Santibáñez & Loría 2005, ch. 7). The condition is sufficient: below it, a
    second equilibrium may appear (K_p (q_d − q) = g(q) − g(q_d) at some q ≠ q_d), and the arm may settle there.

    Parameters
    ----------
    bounds
        :func:`~armctl.tuning.model_bounds` of the arm over the ranges the motion stays in.
    kp
        K_p [N·m/rad]: a scalar, a vector (diagonal) or a symmetric positive definite matrix.

    Returns
    -------
    Verdict
        margin λ_min(K_p) − k_g [N·m/rad], factor λ_min(K_p)/k_g (inf without gravity); details ``kp_min``,
        ``k_g``.
    """
    certified = certified_inputs(bounds, "k_g")
    kp_min, _ = eigen_range(kp, len(bounds.joint_ranges), "kp")
    kg = bounds.k_g
    return Verdict(
        "PD with desired gravity compensation",
        holds=kp_min > kg,
        margin=kp_min - kg,
        factor=kp_min / kg if kg > 0 else math.inf,
        unit="N·m/rad",
        condition=inequality(f"λ_min(K_p) = {kp_min:.5g}", ">", f"k_g = {kg:.5g}", kp_min > kg),
        certified=certified,
        source=f"Kelly 1997 (Int. J. Robotics Research 16(5)); {KELLY_2005}, ch. 7",
        details={"kp_min": kp_min, "k_g": kg},
    )


def pid_condition(bounds: ModelBounds, kp: ArrayLike, kd: ArrayLike, ki: ArrayLike) -> Verdict:
    """PID without gravity compensation, τ = K_p q̃ + K_d (q̇_d − q̇) + K_i ∫ q̃ dt, q̃ = q_d − q, at a constant
    set-point: the tuning of Kelly, Santibáñez & Loría (2005, ch. 9), which makes q = q_d asymptotically
    stable (locally; the domain of attraction grows with the gains):

        λ_min(K_i) > 0,
        λ_min(K_p) > k_g,
        λ_min(K_d) > λ_max(K_i) / (λ_min(K_p) − k_g) · λ_M² / λ_m.

    Parameters
    ----------
    bounds
        :func:`~armctl.tuning.model_bounds` of the arm.
    kp, kd, ki
        K_p [N·m/rad], K_d [N·m·s/rad], K_i [N·m/(rad·s)]: scalars, vectors (diagonal) or s.p.d. matrices.

    Returns
    -------
    Verdict
        margin λ_min(K_d) − the K_d the tuning requires [N·m·s/rad] (−inf if λ_min(K_p) ≤ k_g), factor
        λ_min(K_d) over it; details ``kd_required``, ``kp_margin`` (λ_min(K_p) − k_g), ``kp_min``, ``kd_min``,
        ``ki_max``.
    """
    certified = certified_inputs(bounds, "lambda_min", "lambda_max", "k_g")
    n = len(bounds.joint_ranges)
    kp_min, _ = eigen_range(kp, n, "kp")
    kd_min, _ = eigen_range(kd, n, "kd")
    _, ki_max = eigen_range(ki, n, "ki")
    kg, lm, lM = bounds.k_g, bounds.lambda_min, bounds.lambda_max
    kp_margin = kp_min - kg
    text = inequality(f"λ_min(K_p) = {kp_min:.5g}", ">", f"k_g = {kg:.5g}", kp_margin > 0)
    if kp_margin > 0:
        required = ki_max / kp_margin * lM * lM / lm
        margin, factor = kd_min - required, kd_min / required
        kd_text = inequality(f"λ_min(K_d) = {kd_min:.5g}", ">", f"{required:.5g}", margin > 0)
        text = f"{text} and {kd_text}"
    else:
        required, margin, factor = math.inf, -math.inf, 0.0
    return Verdict(
        "PID (Kelly, Santibáñez & Loría tuning)",
        holds=kp_margin > 0 and margin > 0,
        margin=margin,
        factor=factor,
        unit="N·m·s/rad",
        condition=text,
        certified=certified,
        source=f"{KELLY_2005}, ch. 9",
        details={"kd_required": required, "kp_margin": kp_margin, "kp_min": kp_min, "kd_min": kd_min, "ki_max": ki_max},
    )


def sampled_data_condition(
    bounds: ModelBounds,
    kp: float,
    kd: float,
    period: float,
    delay: int = 1,
    inertia_estimate: ArrayLike | None = None,
) -> Verdict:
    """The sampled PD loop (:class:`~armctl.tuning.SampledDataAnalysis`: double integrator, zero-order hold,
    ``delay`` periods of measurement delay) over the arm's whole inertia range instead of one nominal inertia.

    With the inertia frozen at M, each eigen-direction of the loop is a double integrator driven by the gains
    scaled by σ, an eigenvalue of M⁻¹ times what stands for the inertia in the law:

    * ``inertia_estimate=None``: a model-free PD (PD + gravity), kp [N·m/rad], kd [N·m·s/rad]; σ = eig(M⁻¹) ∈
      [1/λ_M, 1/λ_m];
    * ``inertia_estimate`` M̂ (a scalar or an s.p.d. matrix [kg·m²]): computed torque τ = M̂ (K_p e + K_d ė) + …
      with kp [1/s²], kd [1/s]; σ = eig(M⁻¹M̂) ∈ [λ_min(M̂)/λ_M, λ_max(M̂)/λ_m] (1 for an exact model).

    The loop is stable for every frozen inertia in the range if [σ_lo, σ_hi] lies in one stable range of the
    multiplier of (kp, kd). This is the classic frozen-inertia argument, not a proof for an inertia that varies
    along the motion; it does show how the nominal critical gain shrinks on the arm's lightest direction.

    Parameters
    ----------
    bounds : ModelBounds
        :func:`~armctl.tuning.model_bounds` of the arm (λ_m, λ_M).
    kp, kd : float
        The gains, in the units above.
    period : float
        The control period [s], > 0.
    delay : int, optional
        Periods of measurement delay.
    inertia_estimate : array_like, optional
        M̂ for computed torque (see above); None for a model-free PD.

    Returns
    -------
    Verdict
        factor: how much both gains can be scaled up before a direction in the range goes unstable (> 1 holds;
        for an unstable loop, < 1: the scaling below which every direction is stable, 0 if none is); margin:
        factor − 1; details ``critical_kp`` (kp times factor), ``sigma_range``, ``stable_ranges``.
    """
    names = ("lambda_min", "lambda_max")
    certified = certified_inputs(bounds, *names)
    kp = scalar(kp, "kp (a scalar gain: the frozen-inertia argument needs K_p = kp I)", positive=True)
    kd = scalar(kd, "kd (a scalar gain)", nonnegative=True)
    t = scalar(period, "period", positive=True)
    d = whole_number(delay, "delay (in periods)")
    lm, lM = bounds.lambda_min, bounds.lambda_max
    if inertia_estimate is None:
        lo, hi = 1.0 / lM, 1.0 / lm
        what = "PD on the inertia range"
    else:
        e_min, e_max = eigen_range(inertia_estimate, len(bounds.joint_ranges), "inertia_estimate")
        lo, hi = e_min / lM, e_max / lm
        what = "computed torque with M̂ on the inertia range"
    ranges = _stable_ranges(kp, kd, t, d, _gain_crossings(kp, kd, t, d))
    inside = [r for r in ranges if r[0] < lo and hi < r[1]]
    if inside:  # gains scaled by f map σ to f σ: inside until f σ_hi reaches the range's top
        factor = inside[0][1] / hi
    else:  # the scaling below which every σ is in the range that starts at 0, if there is one
        factor = ranges[0][1] / hi if ranges and ranges[0][0] == 0.0 else 0.0
    return Verdict(
        f"sampled-data loop ({what})",
        holds=bool(inside),
        margin=factor - 1.0,
        factor=factor,
        unit="(gain multiplier − 1)",
        condition=(
            f"σ ∈ [{lo:.4g}, {hi:.4g}] inside a stable range of the gain multiplier "
            f"{[(round(a, 6), round(b, 6)) for a, b in ranges]} (T = {t:g} s, delay {d})"
        ),
        certified=certified,
        source="zero-order-hold double integrator with measurement delay (armctl.tuning.SampledDataAnalysis), "
        "frozen at each inertia in [λ_m, λ_M]",
        details={"critical_kp": kp * factor, "sigma_range": (lo, hi), "stable_ranges": ranges},
    )
