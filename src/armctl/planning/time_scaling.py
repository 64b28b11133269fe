"""The classic dynamic time scaling (Hollerbach 1984): slow a trajectory down uniformly until it fits the limits.

Replacing t by t' = r t (r > 1 slower, r < 1 faster) gives q̇_r = q̇/r, q̈_r = q̈/r² and, since the Coriolis
terms are quadratic in q̇, the torque

    τ_r = d / r² + e / r + h,   d = M q̈ + C(q, q̇) q̇,   e = F_v q̇,   h = g + F_c(sgn q̇)

(sgn q̇ does not change with r). Without viscous friction this is Hollerbach's τ_r = (τ − h)/r² + h, and the
smallest r that keeps joint j within [lower_j, upper_j] at one sample is √(d / (upper_j − h)) for d > 0,
√(d / (lower_j − h)) for d < 0. With it, z = 1/r must stay below the smallest positive root of
d z² + e z + (h − upper) = 0 and of −d z² − e z + (lower − h) = 0; for p(z) = d z² + e z + c₀ with c₀ < 0
that root is z = −2 c₀ / (e + √(e² − 4 d c₀)) (none when the discriminant is negative or the denominator is not
positive). Velocity and acceleration limits give z ≤ v_max/|q̇| and z² ≤ a_max/|q̈|. The scale factor is
r = 1 / min z over the samples and joints: closed form, no search. It needs h within the torque bounds
(at r → ∞ only gravity and Coulomb friction remain).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from armctl._checks import FloatArray, whole_number
from armctl.dynamics.base import Dynamics
from armctl.errors import InfeasibleError, InvalidParameterError
from armctl.planning._batch import friction_torques, rigid_torques
from armctl.planning.limits import joint_limits
from armctl.planning.timing import ScaledTiming
from armctl.planning.trajectory import Trajectory
from armctl.planning.verify import check_trajectory


@dataclass(frozen=True)
class UniformScaling:
    """Result of :func:`uniform_time_scaling`.

    Attributes
    ----------
    factor : float
        r (new duration = r × old).
    trajectory : Trajectory
        The scaled trajectory, with its dense ``check``.
    kind : str
        The limit that binds.
    joint : int
        The joint where it binds.
    t : float
        The time [s] of the original trajectory where it binds.
    """

    factor: float
    trajectory: Trajectory
    kind: str
    joint: int
    t: float

    @property
    def duration(self) -> float:
        return self.trajectory.duration


def _first_root(d: FloatArray, e: FloatArray, c0: FloatArray) -> FloatArray:
    """Smallest positive root of d z² + e z + c₀ (c₀ < 0), inf where there is none."""
    disc = e * e - 4.0 * d * c0
    root = np.sqrt(np.maximum(disc, 0.0))
    den = e + root
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where((disc >= 0) & (den > 0), -2.0 * c0 / den, np.inf)
    return z


def _speed_root(v: FloatArray, lower: FloatArray, upper: FloatArray, power: int) -> FloatArray:
    """Largest z with lower ≤ v z^power ≤ upper (bounds straddling 0)."""
    with np.errstate(divide="ignore"):
        lim = np.where(v > 0, upper / v, np.where(v < 0, lower / v, np.inf))
    return lim if power == 1 else np.sqrt(lim)


def uniform_time_scaling(
    dyn: Dynamics,
    trajectory: Trajectory,
    vel_limit: Any = None,
    acc_limit: Any = None,
    torque_limit: Any = None,
    *,
    torque_margin: float = 0.0,
    samples: int = 1001,
) -> UniformScaling:
    """The smallest uniform scale factor r that makes a trajectory respect the limits, and the scaled
    trajectory.

    The factor is found at ``samples`` evenly spaced times; the scaled trajectory's ``check`` looks 10 times more
    densely (between those samples the limits may be exceeded a little, and the check says by how much).

    Parameters
    ----------
    dyn : Dynamics
        The arm.
    trajectory : Trajectory
        The trajectory to scale.
    vel_limit, acc_limit, torque_limit : optional
        [rad/s], [rad/s²], [N·m]: None (not imposed), ``"model"`` (the model's velocity / effort limits; not for
        acceleration), a scalar, an (n,) vector (symmetric) or (n, 2) bounds.
    torque_margin : float, optional
        Plan with the torque bounds shrunk by this fraction, in [0, 1).
    samples : int, optional
        How many evenly spaced times set the factor.

    Returns
    -------
    UniformScaling

    Raises
    ------
    InfeasibleError
        Gravity and Coulomb friction alone exceed a torque bound somewhere along the path (no slowing down
        helps).
    """
    if not isinstance(dyn, Dynamics):
        raise InvalidParameterError(f"dyn must be an armctl.Dynamics, got {type(dyn).__name__}", value=dyn)
    if not isinstance(trajectory, Trajectory):
        raise InvalidParameterError(
            f"trajectory must be an armctl.planning.Trajectory, got {type(trajectory).__name__}", value=trajectory
        )
    if trajectory.n != dyn.n:
        raise InvalidParameterError(f"the trajectory has {trajectory.n} joints, the arm {dyn.n}", value=trajectory)
    samples = whole_number(samples, "samples", 2)
    limits = joint_limits(dyn.model, vel_limit, acc_limit, torque_limit, torque_margin)
    smp = trajectory.sample(num=samples)
    z_by_kind: dict[str, FloatArray] = {}
    if limits.velocity is not None:
        z_by_kind["velocity"] = _speed_root(smp.qd, limits.velocity.lower, limits.velocity.upper, 1)
    if limits.acceleration is not None:
        z_by_kind["acceleration"] = _speed_root(smp.qdd, limits.acceleration.lower, limits.acceleration.upper, 2)
    tau = limits.planned_torque
    if tau is not None:
        h = rigid_torques(dyn, smp.q, np.zeros_like(smp.qd), np.zeros_like(smp.qdd))
        d = rigid_torques(dyn, smp.q, smp.qd, smp.qdd) - h
        fr = friction_torques(dyn, smp.qd, smp.dq)
        fv = np.array([j.friction.viscous for j in dyn.model.joints])
        e = fv * smp.qd
        h = h + fr - e  # gravity + Coulomb
        out = (h >= tau.upper) | (h <= tau.lower)
        if out.any():
            k, j = np.argwhere(out)[0]
            bound = tau.upper[j] if h[k, j] >= tau.upper[j] else tau.lower[j]
            raise InfeasibleError(
                f"joint {j} ({dyn.model.joint_names[j]!r}) torque at s = {smp.s[k]:.3g} (t = {smp.t[k]:.3g} s): "
                f"gravity and Coulomb friction alone need {h[k, j]:.4g} N·m, the limit is {bound:.4g}; no uniform "
                "slowing down fits the limits",
                value={"joint": int(j), "s": float(smp.s[k]), "needed": float(h[k, j]), "limit": float(bound)},
            )
        z_by_kind["torque"] = np.minimum(_first_root(d, e, h - tau.upper), _first_root(-d, -e, tau.lower - h))
    kind = min(z_by_kind, key=lambda k: float(z_by_kind[k].min()))
    z = z_by_kind[kind]
    k, j = np.unravel_index(int(np.argmin(z)), z.shape)
    zmin = float(z[k, j])
    if not np.isfinite(zmin):  # the trajectory does not move: any speed-up fits
        raise InvalidParameterError("the trajectory never loads any limit (it does not move)", value=trajectory)
    r = 1.0 / zmin
    timing = ScaledTiming(trajectory.timing, r)
    scaled_path = Trajectory(trajectory.path, timing)
    # checked 10 times more densely than r was found, so that the check sees what happens between the samples
    # (checked at the same times, a sharp spline's 0.5 % acceleration excess between them was reported as 0)
    dense = scaled_path.sample(np.linspace(0.0, scaled_path.duration, 10 * (samples - 1) + 1))
    check = check_trajectory(dyn, scaled_path, limits, samples=dense)
    scaled = Trajectory(trajectory.path, timing, check, {"factor": r, "binding": (kind, int(j))})
    return UniformScaling(r, scaled, kind, int(j), float(smp.t[k]))
