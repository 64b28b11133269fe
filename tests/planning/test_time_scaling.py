"""Uniform (Hollerbach) time scaling: the closed-form factor against a brute-force search on the closed-form
pendulum, the scaled trajectory at its limit, and the case no slowing down can fix."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

import armctl
from armctl.errors import InfeasibleError
from armctl.planning import LinePath, PolynomialTiming, SplinePath, Trajectory, uniform_time_scaling
from tests.planning.helpers import PANDA_WAYPOINTS, PENDULUM_GRAVITY, PENDULUM_INERTIA, panda

VISCOUS = 0.05  # the library pendulum's viscous friction [N·m·s/rad]


def _pendulum_torque(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """The pendulum's equation of motion written out: M q̈ + m g ℓ sin q + F_v q̇."""
    return PENDULUM_INERTIA * qdd + PENDULUM_GRAVITY * np.sin(q) + VISCOUS * qd


def _slowest_unfit(rs: np.ndarray, fits: Callable[[float], bool]) -> float:
    """The brute-force factor: the first r of the increasing ``rs`` beyond the last one that does not fit
    (every slower scaling fits too); rs[0] if all fit."""
    ok = np.array([fits(r) for r in rs])
    return float(rs[np.flatnonzero(~ok).max() + 1]) if not ok.all() else float(rs[0])


def test_closed_form_factor_matches_a_brute_force_search() -> None:
    dyn = armctl.Dynamics(armctl.models.pendulum())
    nominal = Trajectory(LinePath([-0.3], [1.2]), PolynomialTiming(0.4))
    limit = 8.0
    result = uniform_time_scaling(dyn, nominal, torque_limit=limit, samples=401)
    smp = nominal.sample(num=401)
    q, qd, qdd = smp.q[:, 0], smp.qd[:, 0], smp.qdd[:, 0]

    def fits(r: float) -> bool:  # slowed by r: q̇/r, q̈/r²
        return bool((np.abs(_pendulum_torque(q, qd / r, qdd / r**2)) <= limit).all())

    rs = np.linspace(0.2, 5.0, 4801)
    assert result.factor == pytest.approx(_slowest_unfit(rs, fits), abs=rs[1] - rs[0])
    assert result.kind == "torque" and result.joint == 0
    assert result.duration == pytest.approx(0.4 * result.factor)


@pytest.mark.parametrize(
    ("start", "end", "kind", "bounds"),
    [
        (-0.3, 1.2, "torque", (-3.0, 40.0)),  # braking at the top pulls below −3 N·m
        (1.2, -0.3, "velocity", (-0.5, 5.0)),  # moving down: q̇ < 0 meets the tight lower bound
        (-0.3, 1.2, "acceleration", (-1.0, 50.0)),  # q̈ takes both signs: the lower bound is the tighter
    ],
)
def test_asymmetric_bounds_bind_on_their_own_side(
    start: float, end: float, kind: str, bounds: tuple[float, float]
) -> None:
    """With (lower, upper) bounds whose lower side is the tighter one, the closed-form factor equals a brute-force
    search over r on the closed-form pendulum (τ, q̇/r, q̈/r² checked against both sides); the upper side alone
    would allow a faster scaling, so the lower side is what binds."""
    dyn = armctl.Dynamics(armctl.models.pendulum())
    nominal = Trajectory(LinePath([start], [end]), PolynomialTiming(0.4))
    arg = {"torque": "torque_limit", "velocity": "vel_limit", "acceleration": "acc_limit"}[kind]
    result = uniform_time_scaling(dyn, nominal, samples=401, **{arg: np.array([bounds])})
    smp = nominal.sample(num=401)
    q, qd, qdd = smp.q[:, 0], smp.qd[:, 0], smp.qdd[:, 0]

    def value(r: float) -> np.ndarray:  # slowed by r: q̇/r, q̈/r²
        return {
            "torque": lambda: _pendulum_torque(q, qd / r, qdd / r**2),
            "velocity": lambda: qd / r,
            "acceleration": lambda: qdd / r**2,
        }[kind]()

    lower, upper = bounds
    rs = np.linspace(0.2, 20.0, 19801)
    r_brute = _slowest_unfit(rs, lambda r: bool(((value(r) >= lower) & (value(r) <= upper)).all()))
    assert _slowest_unfit(rs, lambda r: bool((value(r) <= upper).all())) < 0.8 * r_brute  # the lower side binds
    assert result.factor == pytest.approx(r_brute, abs=rs[1] - rs[0])
    assert result.kind == kind and result.joint == 0


def test_scaled_trajectory_sits_at_its_limit() -> None:
    dyn = panda(friction=True)
    nominal = Trajectory(SplinePath(PANDA_WAYPOINTS), PolynomialTiming(1.0))
    result = uniform_time_scaling(dyn, nominal, vel_limit="model", acc_limit=10.0, torque_limit="model")
    smp = result.trajectory.sample(num=1001)
    inner = slice(1, -1)  # at rest the model's kinetic friction is zero
    tau = np.array(
        [
            dyn.inverse_dynamics(q, qd, qdd)
            for q, qd, qdd in zip(smp.q[inner], smp.qd[inner], smp.qdd[inner], strict=True)
        ]
    )
    used = max(
        (np.abs(tau) / dyn.model.effort_limit).max(),
        (np.abs(smp.qd) / dyn.model.velocity_limit).max(),
        (np.abs(smp.qdd) / 10.0).max(),
    )
    assert used == pytest.approx(1.0, abs=2e-3)
    assert result.trajectory.check.ok(2e-3)
    faster = Trajectory(nominal.path, PolynomialTiming(0.99 * result.duration))  # the same law, 1 % too fast
    again = uniform_time_scaling(dyn, faster, vel_limit="model", acc_limit=10.0, torque_limit="model")
    assert again.factor == pytest.approx(1 / 0.99, rel=1e-9)


def test_gravity_beyond_the_limit_cannot_be_scaled_away() -> None:
    dyn = armctl.Dynamics(armctl.models.pendulum())
    nominal = Trajectory(LinePath([0.0], [3.0]), PolynomialTiming(1.0))
    with pytest.raises(InfeasibleError, match="gravity and Coulomb friction alone need") as e:
        uniform_time_scaling(dyn, nominal, torque_limit=3.0)
    assert e.value.value["needed"] == pytest.approx(PENDULUM_GRAVITY * math.sin(3.0 * e.value.value["s"]), rel=1e-6)


def test_check_sees_between_the_samples_that_set_the_factor() -> None:
    # a sharp spline: between the evenly spaced samples that set r, |q̈| exceeds its limit a little; checked at
    # those same samples, the excess was reported as 0
    dyn = armctl.Dynamics(armctl.models.planar_2r())
    eps = 0.02
    wp = np.array([[0.0, 0.0], [1.0, 0.0], [1.0 + eps, eps], [1.0 + 2 * eps, 3 * eps], [2.0, 0.6]])
    scaled = uniform_time_scaling(dyn, Trajectory(SplinePath(wp), PolynomialTiming(1.0)), acc_limit=50.0).trajectory
    true_excess = float(np.abs(scaled.sample(num=400001).qdd).max()) / 50.0 - 1.0
    assert true_excess > 1e-3  # the case is what it should be
    assert 0.5 * true_excess < scaled.check.worst_excess <= true_excess * (1 + 1e-9)
