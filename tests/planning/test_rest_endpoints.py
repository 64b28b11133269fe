"""A rest-to-rest trajectory rests at its start pose before 0 and at its end pose after T: time_optimal must
refuse a path whose start or end pose the arm cannot hold within the (margin-reduced) torque limit, and the
dense check must see those rest states — while poses passed through in motion need not be holdable.

Reference values: the pendulum's holding torque m g ℓ_c sin q written out from the model's own parameters
(mass, centre of mass, gravity vector), not from the library's dynamics."""

from __future__ import annotations

import math

import numpy as np
import pytest

import armctl
from armctl.errors import InfeasibleError
from armctl.planning import (
    GridTiming,
    LinePath,
    Trajectory,
    check_trajectory,
    joint_limits,
    time_optimal,
)
from tests.planning._common import PENDULUM_INERTIA

MODEL = armctl.models.pendulum()


def _holding_torque(q: float) -> float:
    """m |g| ℓ_c sin q: the torque that holds the rod at rest at angle q (q = 0 hangs down), from the model's
    mass, centre of mass and gravity; valid because the rod, its axis and gravity are mutually orthogonal."""
    joint = MODEL.joints[0]
    com, gravity, axis = np.asarray(joint.link.com), np.asarray(MODEL.gravity), np.asarray(joint.axis)
    assert abs(axis @ com) < 1e-15 and abs(axis @ gravity) < 1e-15 and abs(com @ gravity) > 0  # hangs at q = 0
    return float(joint.link.mass * np.linalg.norm(gravity) * np.linalg.norm(com) * math.sin(q))


def _pendulum(coulomb: float = 0.0) -> armctl.Dynamics:
    return armctl.Dynamics(MODEL.with_friction(coulomb=coulomb))  # no viscous friction


def test_end_pose_the_arm_cannot_hold_is_refused() -> None:
    # the case: toppra "throws" the rod to 1.2 rad, braking on the last stage, but it cannot rest there
    need = _holding_torque(1.2)
    assert 4.5 < need < 4.6  # 2 · 9.81 · 0.25 · sin 1.2 = 4.572 N·m
    with pytest.raises(
        InfeasibleError,
        match=r"joint 0 \('joint1'\) torque at the end pose .*gravity alone needs "
        r"4\.572 N·m, the limit is 4\.5: .*cannot hold itself at rest",
    ) as e:
        time_optimal(_pendulum(), LinePath([0.2], [1.2]), torque_limit=4.5, grid=100)
    v = e.value.value
    assert v["endpoint"] == "end" and v["s"] == 1.0 and v["joint"] == 0 and v["constraint"] == "torque"
    assert v["needed"] == pytest.approx(need, rel=1e-9)
    assert v["limit"] == 4.5
    assert e.value.problem is not None


def test_start_pose_the_arm_cannot_hold_is_refused() -> None:
    with pytest.raises(InfeasibleError, match=r"torque at the start pose .*gravity alone needs 4\.572 N·m") as e:
        time_optimal(_pendulum(), LinePath([1.2], [0.2]), torque_limit=4.5, grid=100)
    v = e.value.value
    assert v["endpoint"] == "start" and v["s"] == 0.0
    assert v["needed"] == pytest.approx(_holding_torque(1.2), rel=1e-9)


def test_torque_margin_applies_to_the_rest_poses() -> None:
    # ±5 N·m holds the rod at 1.2 rad (4.572 N·m), but planning with 80 % of it (±4 N·m) cannot
    path = LinePath([0.2], [1.2])
    assert _holding_torque(1.2) < 5.0
    time_optimal(_pendulum(), path, torque_limit=5.0)
    with pytest.raises(
        InfeasibleError, match=r"end pose .*the limit is 4 \(80 % of the range, torque_margin=0\.2\)"
    ) as e:
        time_optimal(_pendulum(), path, torque_limit=5.0, torque_margin=0.2)
    assert e.value.value["limit"] == pytest.approx(5.0 * (1 - 0.2), rel=1e-12)
    assert e.value.value["needed"] == pytest.approx(_holding_torque(1.2), rel=1e-9)


def test_poses_passed_in_motion_need_not_be_holdable() -> None:
    # 0.2 → 2.9 rad swings over the horizontal (π/2), where holding needs m g ℓ_c = 4.905 N·m > 4.5; both ends
    # are holdable, and the work 4.5 N·m × 2.7 rad exceeds the potential energy gained (m g ℓ_c (cos 0.2 − cos 2.9))
    dyn = _pendulum()
    assert _holding_torque(math.pi / 2) > 4.5
    assert max(_holding_torque(0.2), _holding_torque(2.9)) < 4.5
    traj = time_optimal(dyn, LinePath([0.2], [2.9]), torque_limit=4.5, grid=100)
    assert traj.check.ok(1e-2)
    assert traj.check.reports["torque"].rest is None
    t = np.linspace(0.0, traj.duration, 2002)[1:-1]
    smp = traj.sample(t)
    assert smp.q[0, 0] < math.pi / 2 < smp.q[-1, 0]  # it does pass the pose it could not hold
    tau = np.array([dyn.inverse_dynamics(q, qd, qdd) for q, qd, qdd in zip(smp.q, smp.qd, smp.qdd, strict=True)])
    assert np.abs(tau).max() <= 4.5 * 1.01


def test_at_rest_friction_counts_neither_for_nor_against_the_arm() -> None:
    # at rest the actuator holds gravity alone: F_c = 0.3 N·m of the motion just ended is not added (ending
    # upward at 1.2 rad needs 4.572 N·m, within 4.7, although gravity + F_c = 4.872 is not), and stiction is not
    # counted on to hold the arm (4.572 − 0.3 would fit 4.5; the start pose of the way down is still refused)
    dyn = _pendulum(coulomb=0.3)
    up, down = LinePath([0.2], [1.2]), LinePath([1.2], [0.2])
    assert _holding_torque(1.2) < 4.7 < _holding_torque(1.2) + 0.3
    traj = time_optimal(dyn, up, torque_limit=4.7)
    assert traj.check.ok(1e-2)
    assert traj.check.reports["torque"].value <= 4.7 * (1 + 1e-2)
    assert _holding_torque(1.2) - 0.3 < 4.5 < _holding_torque(1.2)
    with pytest.raises(InfeasibleError, match=r"start pose .*gravity alone needs 4\.572") as e:
        time_optimal(dyn, down, torque_limit=4.5)
    assert e.value.value["needed"] == pytest.approx(_holding_torque(1.2), rel=1e-9)


@pytest.mark.parametrize(("start", "end", "rest"), [(0.2, 1.2, "end"), (1.2, 0.2, "start")])
def test_dense_check_covers_the_rest_states(start: float, end: float, rest: str) -> None:
    # a hand-made TOPP-RA timing: ṡ² = 0, 1, 0 at s = 0, ½, 1, so s̈ = ±1 (|q̈| = 1 rad/s²) and T = 2 s. In motion
    # |τ| ≤ M + m g ℓ_c sin 0.7 or −M + m g ℓ_c sin 1.2 (4.28 N·m), within 4.5; at rest at 1.2 rad: 4.572
    dyn = _pendulum()
    traj = Trajectory(LinePath([start], [end]), GridTiming([0.0, 0.5, 1.0], [0.0, 1.0, 0.0]))
    assert traj.duration == pytest.approx(2.0, rel=1e-15)
    moving = max(PENDULUM_INERTIA + _holding_torque(0.7), -PENDULUM_INERTIA + _holding_torque(1.2))
    assert moving < 4.5
    smp = traj.sample(np.linspace(0.0, 2.0, 2001))
    tau = np.array([dyn.inverse_dynamics(q, qd, qdd) for q, qd, qdd in zip(smp.q, smp.qd, smp.qdd, strict=True)])
    assert np.abs(tau).max() == pytest.approx(moving, rel=1e-6)  # the motion itself fits

    check = check_trajectory(dyn, traj, joint_limits(dyn.model, torque_limit=4.5))
    report = check.reports["torque"]
    assert not check.ok(1e-2)
    assert report.rest == rest and report.s == (1.0 if rest == "end" else 0.0)
    assert report.ratio == pytest.approx(_holding_torque(1.2) / 4.5, rel=1e-9)
    assert f"rest at the {rest} pose" in str(report)
    # a limit that holds the rod passes, the rest state still being the worst sample
    fine = check_trajectory(dyn, traj, joint_limits(dyn.model, torque_limit=4.6))
    assert fine.ok() and fine.reports["torque"].rest == rest
    assert fine.reports["torque"].ratio == pytest.approx(_holding_torque(1.2) / 4.6, rel=1e-9)


@pytest.mark.parametrize(("lower", "upper"), [(-4.5, 4.5), (-8.0, 4.0)])
def test_rest_excess_is_normalised_like_the_mid_path_one(lower: float, upper: float) -> None:
    """The ``excess`` of the error for an end pose the arm cannot hold (the rod horizontal, π/2) is the
    normalised violation (|g| − upper)/half-range — (|g| − L)/L for ±L, utilisation − 1 as in the dense check —
    with |g| = m |g| ℓ_c written out from the model (_holding_torque); and it is the figure reported for the same
    overload met mid-path (0 → π passes π/2 at the gridpoint s = 0.5; viscous friction keeps the arm from
    carrying its speed through, so toppra finds no timing there)."""
    dyn = armctl.Dynamics(MODEL.with_friction(viscous=1.0, coulomb=0.0))
    need = _holding_torque(math.pi / 2)
    expected = (need - upper) / (0.5 * (upper - lower))
    assert expected > 0.05  # 4.905 N·m against 4.5 (0.090) and 4 (0.151)
    bounds = np.array([[lower, upper]])
    with pytest.raises(InfeasibleError, match="end pose") as rest:
        time_optimal(dyn, LinePath([0.0], [math.pi / 2]), torque_limit=bounds, grid=100)
    with pytest.raises(InfeasibleError, match=r"torque at s = 0\.5 .*gravity alone needs 4\.905") as mid:
        time_optimal(dyn, LinePath([0.0], [math.pi]), torque_limit=bounds, grid=100)
    assert rest.value.value["endpoint"] == "end" and "endpoint" not in mid.value.value
    assert rest.value.value["needed"] == pytest.approx(need, rel=1e-9)
    assert rest.value.value["excess"] == pytest.approx(expected, rel=1e-9)
    assert mid.value.value["excess"] == pytest.approx(expected, rel=1e-9)
