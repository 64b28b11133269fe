"""The QP of the operational-space controller: its rows against the Dynamics API (an independent
evaluation of the same Lagrange model), its solution against hand-written task accelerations, build
separately from solve, and proxsuite against qpsolvers."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import armctl
from armctl.controllers.osc import (
    Contact,
    ContactForceTask,
    FrameOrientationTask,
    FramePoseTask,
    FramePositionTask,
    JointVelocityLimit,
    OperationalSpaceQP,
    PostureTask,
    QPProblem,
    TorqueLimit,
)
from tests.controllers.osc.helpers import Q_HOME, panda_dynamics


def _state(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    return Q_HOME + rng.uniform(-0.3, 0.3, 7), rng.uniform(-0.5, 0.5, 7)


def test_equality_rows_are_the_equation_of_motion(panda: armctl.Dynamics, rng: np.random.Generator) -> None:
    """Any x with A x = b has τ = inverse_dynamics(q, q̇, q̈) (friction included)."""
    dyn = panda_dynamics(friction=True)
    task = FramePositionTask()
    task.set_target([0.4, 0.0, 0.5])
    ctrl = OperationalSpaceQP(dyn, [task], limits=[TorqueLimit()])
    for _ in range(3):
        q, qd = _state(rng)
        p = ctrl.build(0.0, q, qd, armctl.Reference(q)).problem(0)
        qdd = rng.normal(size=7)
        tau = np.linalg.solve(p.A[:, 7:], p.b - p.A[:, :7] @ qdd)  # A = [M, −I]: τ from the rows
        np.testing.assert_allclose(tau, dyn.inverse_dynamics(q, qd, qdd), atol=1e-9)


def test_contact_force_enters_as_minus_jacobian_transpose(rng: np.random.Generator) -> None:
    """With a contact force f (environment on the robot), τ = inverse_dynamics(q, q̇, q̈, wrench=h_e) with
    h_e = [−f; 0], the wrench the arm exerts."""
    dyn = panda_dynamics()
    contact = Contact(mode="fixed", mu=0.8)
    task = FramePositionTask()
    task.set_target([0.4, 0.0, 0.5])
    ctrl = OperationalSpaceQP(dyn, [task, ContactForceTask(contact, [0.0, 0.0, 10.0])], limits=[], contacts=[contact])
    q, qd = _state(rng)
    p = ctrl.build(0.0, q, qd, armctl.Reference(q)).problem(0)
    v = p.variables
    qdd, f = rng.normal(size=7), rng.normal(size=3)
    x = np.zeros(p.nx)
    x[v["qdd"]] = qdd
    x[v[contact.name]] = f
    tau = p.A[:7] @ x - p.b[:7]  # the rows read M q̈ − τ − J_cᵀ f = −(C q̇ + g); x has τ = 0
    np.testing.assert_allclose(tau, dyn.inverse_dynamics(q, qd, qdd, wrench=np.r_[-f, 0, 0, 0]), atol=1e-9)


def test_solution_realises_the_pd_task_acceleration(rng: np.random.Generator) -> None:
    """One pose task, no limits binding: J q̈ + J̇ q̇ equals ẍ* = a_ref + K_d(V_ref − V) + K_p e, all written
    here independently (rotation error from scipy, J̇q̇ from a finite difference of the frame velocity)."""
    dyn = panda_dynamics()
    q, qd = _state(rng)
    pose0 = dyn.frame_pose(q)
    target = pose0.copy()
    target[:3, 3] += [0.02, -0.01, 0.03]
    target[:3, :3] = Rotation.from_rotvec([0.05, -0.02, 0.1]).as_matrix() @ pose0[:3, :3]
    twist, acc = rng.normal(size=6) * 0.1, rng.normal(size=6) * 0.1
    kp, kd = np.array([100.0, 150.0, 200.0, 80.0, 90.0, 60.0]), 30.0
    task = FramePoseTask(kp=kp, kd=kd)
    task.set_target(target, twist, acc)
    ctrl = OperationalSpaceQP(dyn, [task, PostureTask(7, kp=10.0, priority=1)], limits=[TorqueLimit()])
    sol = ctrl.solve(0.0, q, qd, armctl.Reference(q))
    J = dyn.jacobian(q)
    V = J @ qd
    e = np.r_[target[:3, 3] - pose0[:3, 3], Rotation.from_matrix(target[:3, :3] @ pose0[:3, :3].T).as_rotvec()]
    xdd_star = acc + kd * (twist - V) + kp * e
    h = 1e-7  # J̇ q̇ = d/dt (J(q) q̇) at q̈ = 0
    drift = (dyn.jacobian(q + h * qd) @ qd - dyn.jacobian(q - h * qd) @ qd) / (2 * h)
    np.testing.assert_allclose(J @ sol.qdd + drift, xdd_star, atol=1e-5)
    # and the torque is what the plant needs for that q̈
    np.testing.assert_allclose(sol.tau, dyn.inverse_dynamics(q, qd, sol.qdd), atol=1e-6)


def test_build_is_separate_from_solve_and_inspectable(panda: armctl.Dynamics) -> None:
    task = FramePoseTask()
    task.set_target(panda.frame_pose(Q_HOME))
    ctrl = OperationalSpaceQP(panda, [task, PostureTask(7)], limits=[TorqueLimit()])
    p = ctrl.build(0.0, Q_HOME, np.zeros(7), armctl.Reference(Q_HOME)).problem(0)
    assert isinstance(p, QPProblem)
    assert (p.H.shape, p.A.shape, p.C.shape) == ((14, 14), (7, 14), (7, 14))
    assert (p.nx, p.me, p.mi) == (14, 7, 7)  # the counts of QPArrays, which a named problem is too
    assert p.eq_names[3] == "dynamics[panda_joint4]" and p.ineq_names[6] == "torque_limit[panda_joint7]"
    np.testing.assert_allclose(p.H, p.H.T)
    assert np.linalg.eigvalsh(p.H).min() > 0
    np.testing.assert_allclose(p.u, panda.model.effort_limit)
    with pytest.raises(ValueError):
        p.H[0, 0] = 1.0  # read-only
    assert ctrl.last_solution is None  # building solved nothing


def test_qpsolvers_and_proxsuite_agree(panda: armctl.Dynamics, rng: np.random.Generator) -> None:
    """At each of several states in turn (the proxsuite path warm-starts and reuses its QP objects, so a
    solution that went stale between calls would show), against qpsolvers' own call of ProxQP, cold and to a
    tolerance 1e4 times tighter."""
    from armctl.controllers.osc.solve import QpsolversSolver

    tasks = []
    for solver in ("proxsuite", QpsolversSolver("proxqp", eps_abs=1e-10, eps_rel=0.0)):
        task = FramePoseTask(kp=300.0)
        task.set_target(panda.frame_pose(Q_HOME))
        tasks.append(
            OperationalSpaceQP(
                panda, [task, PostureTask(7, weight=1e-2)], limits=[TorqueLimit(scale=0.2)], solver=solver
            )
        )
    previous = None
    for _ in range(3):
        q, qd = _state(rng)
        a, b = (c.solve(0.0, q, qd, armctl.Reference(Q_HOME)) for c in tasks)
        np.testing.assert_allclose(a.x, b.x, atol=1e-6 * np.abs(b.x).max())  # eps_abs = 1e-6 on the residuals
        assert a.problem(0).violations(a.x) == {}
        assert previous is None or np.abs(a.x - previous).max() > 1.0  # the states differ, so do the steps
        previous = a.x.copy()


def test_warm_start_reuses_the_previous_solution(panda: armctl.Dynamics) -> None:
    """ProxQP warm-started from the previous period's QP needs fewer iterations at the next state than a fresh
    (cold) solver on the same QP, and reaches the same answer. The target is 10 cm away, so that neither solve
    is trivial."""
    from armctl.controllers.osc.solve import ProxQPSolver

    task = FramePoseTask()
    target = panda.frame_pose(Q_HOME)
    target[:3, 3] += [0.1, 0.0, -0.05]
    task.set_target(target)
    ctrl = OperationalSpaceQP(panda, [task, PostureTask(7)], limits=[TorqueLimit()])
    ref = armctl.Reference(Q_HOME)
    qd = np.full(7, 0.1)
    first = ctrl.build(0.0, Q_HOME, qd, ref).arrays(0)
    second = ctrl.build(0.001, Q_HOME + 1e-4, qd, ref).arrays(0)
    warm, cold = ProxQPSolver(), ProxQPSolver()
    warm.solve_raw(first)
    a, b = warm.solve_raw(second), cold.solve_raw(second)
    assert 0 < a.iterations < b.iterations
    np.testing.assert_allclose(a.x, b.x, atol=1e-4 * np.abs(b.x).max())
    warm.reset()
    assert warm.solve_raw(second).iterations == b.iterations  # cold again


def test_a_warm_start_takes_the_new_state_dependent_bounds(panda: armctl.Dynamics) -> None:
    """The velocity limit's bound q̈ ≤ (q̇_max − q̇)/Δt changes with the state while its rows C stay the same:
    a controller warm-started from a period at rest must take the new bound (written out here), as a cold one
    does, when the joints come within 0.5 mrad/s of the limit."""

    def make() -> OperationalSpaceQP:
        return OperationalSpaceQP(
            panda, [PostureTask(7, kp=100.0)], limits=[TorqueLimit(), JointVelocityLimit(1e-3, limit=1.0)]
        )

    ref = armctl.Reference(Q_HOME + 0.5)  # the posture pulls every joint up, at ~50 rad/s²
    warm, cold = make(), make()
    warm(0.0, Q_HOME, np.zeros(7), ref)  # at rest: the bound, 1000 rad/s², is far
    qd = np.full(7, 0.9995)
    bound = (1.0 - qd) / 1e-3  # 0.5 rad/s²
    a_warm = warm.solve(0.001, Q_HOME, qd, ref).qdd
    a_cold = cold.solve(0.001, Q_HOME, qd, ref).qdd
    np.testing.assert_allclose(a_cold, bound, atol=1e-5)  # the bound binds every joint
    np.testing.assert_allclose(a_warm, bound, atol=1e-5)


def test_lagrange_backend_gives_the_same_step() -> None:
    """The finite-difference J̇q̇ of the generic path against Pinocchio's classical acceleration."""
    pin_dyn = armctl.Dynamics(armctl.models.planar_3r())
    lag_dyn = armctl.Dynamics(armctl.models.planar_3r(), backend="lagrange")
    q, qd = np.array([0.3, 0.8, -0.6]), np.array([0.7, -0.4, 0.9])
    out = []
    for dyn in (pin_dyn, lag_dyn):
        task = FramePositionTask(kp=50.0, weight=[1.0, 1.0, 0.0])  # the arm is planar: z is not a task
        task.set_target(pin_dyn.frame_pose(q)[:3, 3] + [0.05, -0.02, 0.0], [0.1, 0.0, 0.0])
        ctrl = OperationalSpaceQP(dyn, [task, PostureTask(3, weight=1e-3)], limits=[TorqueLimit(100.0)])
        out.append(ctrl.solve(0.0, q, qd, armctl.Reference(q)).x)
    np.testing.assert_allclose(out[0], out[1], atol=1e-6)


def test_slacks_report_how_far_each_task_is_from_met(panda: armctl.Dynamics) -> None:
    """Slack variables equal the (weighted) residuals; they vanish for a task that can be met (the position
    task, priority 0) and not for the posture below it, which gives way."""
    sols = []
    for slacks in (False, True):
        task = FramePositionTask(kp=100.0)
        task.set_target(panda.frame_pose(Q_HOME)[:3, 3] + [0.05, 0.0, 0.0])
        ctrl = OperationalSpaceQP(
            panda, [task, PostureTask(7, kp=50.0, weight=1e-2, priority=1)], limits=[TorqueLimit()], slacks=slacks
        )
        sols.append(ctrl.solve(0.0, Q_HOME, np.zeros(7), armctl.Reference(Q_HOME)))
    plain, slack = sols
    np.testing.assert_allclose(plain.x, slack.x, atol=1e-6)
    assert slack.slacks is not None
    w = np.sqrt(1e-2)
    np.testing.assert_allclose(slack.slacks["posture"], w * slack.residuals["posture"], atol=1e-6)
    assert np.abs(slack.slacks["position[tool]"]).max() < 1e-3 < np.abs(slack.slacks["posture"]).max()


def test_controllers_pickle_for_process_pools(rng: np.random.Generator) -> None:
    """An OSC controller (pose, contact-force and posture tasks, a contact, the default limits) and the
    closed-form baseline survive a pickle round trip, as a process-pool sweep needs: the copy, rebuilt on its
    own workspace, gives the original's torques (both starting cold) at several states in turn."""
    import pickle

    from armctl.controllers.osc import ClosedFormOSC

    dyn = panda_dynamics()
    contact = Contact(mode="sliding", mu=0.5, slip_velocity=1e-3)
    pose = FramePoseTask(kp=200.0)
    pose.set_target(dyn.frame_pose(Q_HOME))
    qp = OperationalSpaceQP(
        dyn,
        [pose, ContactForceTask(contact, [0.0, 0.0, 5.0], weight=0.1), PostureTask(7, weight=1e-3)],
        contacts=[contact],
    )
    closed = ClosedFormOSC(dyn, pose, PostureTask(7, kp=25.0))
    for ctrl in (qp, closed):
        ctrl(0.0, Q_HOME, np.zeros(7), armctl.Reference(Q_HOME))  # its layouts and level plans exist
        copy = pickle.loads(pickle.dumps(ctrl))
        if ctrl is qp:  # the copy's plans belong to the copy's layouts (once they were keyed by the originals' ids)
            plans, layouts = copy.builder._level_plans, list(copy.builder._layouts.values())
            assert plans and all(any(k is lay for lay in layouts) for k in plans)
        ctrl.reset()
        for _ in range(3):
            q, qd = _state(rng)
            ref = armctl.Reference(q)
            np.testing.assert_allclose(copy(0.0, q, qd, ref), ctrl(0.0, q, qd, ref), rtol=1e-6, atol=1e-6)


def test_a_lower_priority_level_is_solved_not_dropped(panda: armctl.Dynamics, rng: np.random.Generator) -> None:
    """Position (level 0) above orientation (level 1), no limits: six task rows on seven joints with free
    torques, so both levels are met exactly. (With its default ``eps_dual_inf`` ProxQP reports the second level
    DUAL_INFEASIBLE — its test for an unbounded QP fires on the ε-flat directions of a strictly convex one — and
    a controller that kept the first level's answer would ignore the orientation task: residual 340 rad/s².)"""
    for _ in range(6):
        q = Q_HOME + rng.uniform(-0.3, 0.3, 7)
        qd = rng.uniform(-0.5, 0.5, 7)
        pose = panda.frame_pose(q)
        pos, ori = FramePositionTask(priority=0), FrameOrientationTask(priority=1)
        pos.set_target(pose[:3, 3] + [0.05, -0.03, 0.04])
        ori.set_target(Rotation.from_rotvec([0.3, -0.2, 0.4]).as_matrix() @ pose[:3, :3])
        sol = OperationalSpaceQP(panda, [pos, ori], limits=[]).solve(0.0, q, qd, armctl.Reference(q))
        assert sol.level_status == ("solved", "solved")
        for name, r in sol.residuals.items():
            assert np.abs(r).max() < 1e-3, (name, r)


class _CascadeOnly:
    """ProxQPSolver without ``solve_raw``: the controller takes its generic path (StepQP, solve_cascade)."""

    def __init__(self) -> None:
        from armctl.controllers.osc.solve import ProxQPSolver

        self._s = ProxQPSolver()

    def solve(self, p: QPProblem, slot: int = 0) -> object:
        return self._s.solve(p, slot)

    def reset(self) -> None:
        self._s.reset()


def test_the_single_level_path_is_the_generic_one(rng: np.random.Generator) -> None:
    """A controller with one priority level solves without the step's intermediate objects and puts
    last_solution together only when asked: torques, logs, the solution (x, residuals, forces) and the QP it
    shows are those of the generic path (StepQP + solve_cascade, taken with a solver lacking ``solve_raw``),
    with friction, the default (state-dependent) limits and a contact switched on and off."""
    dyn = panda_dynamics(friction=True)
    contact = Contact(mode="sliding", mu=0.5, slip_velocity=1e-3)

    def make(solver: object) -> OperationalSpaceQP:
        pose = FramePoseTask(kp=200.0)
        pose.set_target(dyn.frame_pose(Q_HOME))
        tasks = [pose, ContactForceTask(contact, [0.0, 0.0, 5.0], weight=0.1), PostureTask(7, weight=1e-3)]
        return OperationalSpaceQP(dyn, tasks, contacts=[contact], solver=solver)

    lean, generic = make("proxsuite"), make(_CascadeOnly())
    assert lean.last_solution is None
    for k in range(6):
        contact.active = k % 3 != 2
        q, qd = _state(rng)
        ref = armctl.Reference(q)
        np.testing.assert_allclose(lean(0.0, q, qd, ref), generic(0.0, q, qd, ref), rtol=1e-7, atol=1e-7)
        assert lean.last_log.keys() == generic.last_log.keys()
        a, b = lean.last_solution, generic.last_solution
        assert a is lean.last_solution  # put together once
        np.testing.assert_allclose(a.x, b.x, rtol=1e-7, atol=1e-7)
        assert a.forces.keys() == b.forces.keys() == ({contact.name} if contact.active else set())
        for name, r in b.residuals.items():
            np.testing.assert_allclose(a.residuals[name], r, rtol=1e-6, atol=1e-6)
        pa, pb = a.problem(0), b.problem(0)
        assert pa.eq_names == pb.eq_names and pa.ineq_names == pb.ineq_names
        for name in ("H", "g", "A", "b", "C", "l", "u"):
            np.testing.assert_allclose(getattr(pa, name), getattr(pb, name), rtol=1e-12, atol=1e-12, err_msg=name)
    lean.reset()
    assert lean.last_solution is None
