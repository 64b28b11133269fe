"""Limits and contacts of the operational-space QP: viability of the position bounds and the
velocity bounds checked on the exact discrete double integrator, the linearised friction cone, Coulomb's law
of a sliding contact."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

import armctl
from armctl.controllers.osc import (
    Contact,
    ContactForceTask,
    FramePositionTask,
    JointPositionLimit,
    JointVelocityLimit,
    OperationalSpaceQP,
    PostureTask,
    TorqueLimit,
)
from tests.controllers.osc.helpers import Q_HOME

DT = 1e-3


def _run_against_upper_limit(
    limit: JointPositionLimit | JointVelocityLimit, q: np.ndarray, qd: np.ndarray, steps: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Push every joint as hard as the bounds allow towards its upper limit, integrating the exact discrete
    double integrator q⁺ = q + Δt q̇ + ½Δt² q̈, q̇⁺ = q̇ + Δt q̈; returns the q, q̇ and q̈ histories."""
    qs, qds, accs = [], [], []
    for _ in range(steps):
        lo, up = limit.bounds(SimpleNamespace(q=q, qd=qd))  # type: ignore[arg-type]
        assert (lo <= up + 1e-9).all()
        a = up
        q, qd = q + DT * qd + 0.5 * DT * DT * a, qd + DT * a
        qs.append(q)
        qds.append(qd)
        accs.append(a)
    return np.array(qs), np.array(qds), np.array(accs)


def test_position_bounds_keep_every_joint_stoppable(panda: armctl.Dynamics) -> None:
    amax = 5.0
    lim = JointPositionLimit(DT, max_deceleration=amax)
    lim.bind(panda.model)
    upper = panda.model.upper
    # from rest 0.3 rad below the limit and from 1 rad/s towards it (still viable: v² < 2 a_max gap)
    for q0, v0 in ((upper - 0.3, np.zeros(7)), (upper - 0.3, np.ones(7))):
        q, qd, acc = _run_against_upper_limit(lim, q0, v0, 3000)
        assert (q <= upper + 1e-9).all()  # never beyond the limit
        assert (acc >= -amax - 1e-9).all()  # never asks for more braking than a_max
        assert np.abs(qd[-1]).max() < 0.05 and (upper - q[-1]).max() < 1e-2  # comes to rest at the limit
    # far from the limits the bounds do not bind
    lo, up = lim.bounds(SimpleNamespace(q=0.5 * (panda.model.lower + upper), qd=np.zeros(7)))  # type: ignore[arg-type]
    assert (up > 100).all() and (lo < -100).all()


def _largest_viable_acceleration(gap: float, v: float, a_max: float, reserve: float = 0.1) -> float:
    """The viability bound from its definition, by bisection: the largest q̈ held over one step Δt (exact
    double integrator) after which the joint is still short of its limit (``gap`` ahead, moving at v towards
    it) and, if it still moves towards the limit, can stop before it braking at the plan's (1 − reserve) a_max
    (v⁺² ≤ 2 (1 − reserve) a_max gap⁺); never below −a_max (no more braking than that is asked for)."""
    a_plan = (1.0 - reserve) * a_max

    def viable(a: float) -> bool:
        gap1, v1 = gap - DT * v - 0.5 * DT * DT * a, v + DT * a
        return gap1 >= 0.0 and (v1 <= 0.0 or v1 * v1 <= 2.0 * a_plan * gap1)

    if not viable(-a_max):
        return -a_max
    lo, hi = -a_max, 1e9
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if viable(mid) else (lo, mid)
    return lo


def test_position_bounds_are_the_largest_viable_accelerations(panda: armctl.Dynamics) -> None:
    """Both sides against the definition of viability (found by bisection, not by the module's closed form)."""
    amax = np.linspace(3.0, 9.0, 7)
    lim = JointPositionLimit(DT, max_deceleration=amax, margin=0.01)
    lim.bind(panda.model)
    lo_lim, up_lim = panda.model.lower + 0.01, panda.model.upper - 0.01
    rng = np.random.default_rng(5)
    states = [(rng.uniform(lo_lim - 0.02, up_lim + 0.02), rng.uniform(-3.0, 3.0, 7)) for _ in range(40)]
    # 5 mm from a limit at 2.5 rad/s towards it: too fast to stop, on both sides; 1 mm from it, less than
    # half a step away at 2.5 rad/s, or moving away at 3 rad/s
    states += [
        (up_lim - 0.005, np.full(7, 2.5)),
        (lo_lim + 0.005, np.full(7, -2.5)),
        (up_lim - 0.001, np.full(7, 2.5)),
        (up_lim - 0.001, np.full(7, -3.0)),
        (rng.uniform(up_lim - 0.05, up_lim), rng.uniform(-1.0, 3.0, 7)),
    ]
    for q, qd in states:
        lo, up = lim.bounds(SimpleNamespace(q=q, qd=qd))  # type: ignore[arg-type]
        for i in range(7):
            expected_up = _largest_viable_acceleration(up_lim[i] - q[i], qd[i], amax[i])
            expected_lo = -_largest_viable_acceleration(q[i] - lo_lim[i], -qd[i], amax[i])
            assert up[i] == pytest.approx(expected_up, rel=1e-9, abs=1e-6)
            assert lo[i] == pytest.approx(expected_lo, rel=1e-9, abs=1e-6)
    with pytest.raises(ValueError, match="read-only"):  # taken at bind: an edit in place would be ignored
        lim.upper[0] = 0.0


def test_position_bounds_brake_a_joint_that_cannot_stop_in_time(panda: armctl.Dynamics) -> None:
    lim = JointPositionLimit(DT, max_deceleration=5.0)
    lim.bind(panda.model)
    q0 = panda.model.upper - 0.01
    lo, up = lim.bounds(SimpleNamespace(q=q0, qd=np.full(7, 2.0)))  # type: ignore[arg-type]
    np.testing.assert_allclose(up, -5.0)  # v²/(2 gap) = 200 > a_max: brake at a_max
    assert (lo <= up).all()


def test_velocity_bounds_hold_the_velocity_limit(panda: armctl.Dynamics) -> None:
    lim = JointVelocityLimit(DT)
    lim.bind(panda.model)
    _, qd, _ = _run_against_upper_limit(lim, Q_HOME.copy(), np.zeros(7), 200)
    assert (qd <= panda.model.velocity_limit + 1e-9).all()
    np.testing.assert_allclose(qd[-1], panda.model.velocity_limit, rtol=1e-9)


def test_velocity_bounds_brake_an_over_fast_joint_at_a_max(panda: armctl.Dynamics) -> None:
    """A joint already beyond ±q̇_max is asked to brake at exactly a_max, either way (module docstring: each
    bound clamped to ±a_max), while its other bound stays (∓q̇_max − q̇)/Δt; both written out here."""
    amax = np.linspace(4.0, 10.0, 7)
    lim = JointVelocityLimit(DT, limit=1.0, max_deceleration=amax)
    lim.bind(panda.model)
    sign = np.array([1.0, -1.0, 1.0, -1.0, 1.0, -1.0, 1.0])
    # 0.5 rad/s too fast, and just too fast: 1.5 a_max Δt beyond the limit (between a_max and 2 a_max to brake)
    for excess in (np.full(7, 0.5), 1.5 * amax * DT):
        qd = sign * (1.0 + excess)
        lo, up = lim.bounds(SimpleNamespace(q=Q_HOME, qd=qd))  # type: ignore[arg-type]
        pos, neg = sign > 0, sign < 0
        np.testing.assert_allclose(up[pos], -amax[pos], rtol=1e-12)
        np.testing.assert_allclose(lo[pos], (-1.0 - qd[pos]) / DT, rtol=1e-12)
        np.testing.assert_allclose(lo[neg], amax[neg], rtol=1e-12)
        np.testing.assert_allclose(up[neg], (1.0 - qd[neg]) / DT, rtol=1e-12)


def test_fixed_contact_force_stays_in_the_friction_pyramid(panda: armctl.Dynamics) -> None:
    """Asking for a tangential force twice what friction allows: the QP returns the force on the pyramid's
    boundary, inside the true cone ‖f_t‖ ≤ μ f_n."""
    mu = 0.5
    contact = Contact(mode="fixed", mu=mu, facets=4)
    force_task = ContactForceTask(contact, [10.0, 0.0, 10.0], weight=1.0)
    ctrl = OperationalSpaceQP(
        panda, [force_task, PostureTask(7, weight=1e-3)], limits=[TorqueLimit()], contacts=[contact]
    )
    sol = ctrl.solve(0.0, Q_HOME, np.zeros(7), armctl.Reference(Q_HOME))
    f = sol.forces[contact.name]
    fn, ft = f[2], f[:2]
    assert fn > 0
    assert np.linalg.norm(ft) <= mu * fn + 1e-6
    # on a boundary facet of the inscribed pyramid: max_i |t_i·f| = μ cos(π/4) f_n
    t = contact.tangents
    np.testing.assert_allclose(np.abs(t @ f).max(), mu * math.cos(math.pi / 4) * fn, rtol=1e-5)
    # and the contact point does not accelerate (fixed contact, at rest): J_v q̈ + J̇q̇ = 0
    np.testing.assert_allclose(panda.jacobian(Q_HOME)[:3] @ sol.qdd, 0.0, atol=1e-6)


def test_sliding_contact_force_follows_coulomb(panda: armctl.Dynamics) -> None:
    mu = 0.4
    contact = Contact(mode="sliding", mu=mu, slip_velocity=1e-4)
    task = FramePositionTask(kp=100.0, weight=[1.0, 1.0, 0.0])
    task.set_target(panda.frame_pose(Q_HOME)[:3, 3] + [0.05, 0.0, 0.0], [0.1, 0.0, 0.0])
    ctrl = OperationalSpaceQP(
        panda,
        [task, ContactForceTask(contact, 10.0, weight=1.0), PostureTask(7, weight=1e-3)],
        limits=[TorqueLimit()],
        contacts=[contact],
    )
    v_tool = np.array([0.08, -0.06, 0.0])  # sliding along the surface
    qd = np.linalg.pinv(panda.jacobian(Q_HOME)[:3]) @ v_tool
    f = ctrl.solve(0.0, Q_HOME, qd, armctl.Reference(Q_HOME)).forces[contact.name]
    np.testing.assert_allclose(f[2], 10.0, rtol=1e-6)  # the force task of a sliding contact: normal only
    np.testing.assert_allclose(f[:2], -mu * f[2] * v_tool[:2] / np.linalg.norm(v_tool), rtol=1e-3)


def test_fixed_contact_damps_the_contact_point_velocity(panda: armctl.Dynamics) -> None:
    """A fixed contact whose point still moves (v_c ≠ 0): the solved q̈ gives it the classical acceleration
    −k_d v_c (module docstring: J_c q̈ + J̇_c q̇ = −k_d v_c). Reference: Pinocchio's classical frame acceleration
    and frame velocity of (q, q̇, q̈) on a Panda built here from the URDF, fingers locked closed."""
    import pinocchio as pin

    kd = 50.0
    contact = Contact(mode="fixed", mu=0.8, kd=kd)
    ctrl = OperationalSpaceQP(
        panda, [PostureTask(7, weight=1e-2), ContactForceTask(contact, [0.0, 0.0, 10.0])], limits=[], contacts=[contact]
    )
    qd = np.array([0.3, -0.2, 0.1, 0.4, -0.3, 0.2, 0.1])
    sol = ctrl.solve(0.0, Q_HOME, qd, armctl.Reference(Q_HOME))
    full = pin.buildModelFromUrdf(str(armctl.models.robot_description("panda_description/urdf/panda.urdf")))
    fingers = [full.getJointId(f"panda_finger_joint{i}") for i in (1, 2)]
    pm = pin.buildReducedModel(full, fingers, pin.neutral(full))
    pd = pm.createData()
    pin.forwardKinematics(pm, pd, Q_HOME, qd, sol.qdd)
    pin.updateFramePlacements(pm, pd)
    fid = pm.getFrameId("panda_hand_tcp")
    vel = pin.getFrameVelocity(pm, pd, fid, pin.LOCAL_WORLD_ALIGNED).linear
    acc = pin.getFrameClassicalAcceleration(pm, pd, fid, pin.LOCAL_WORLD_ALIGNED).linear
    assert np.linalg.norm(vel) > 0.1  # the point moves: the damping is at work
    np.testing.assert_allclose(acc, -kd * vel, atol=1e-6)
