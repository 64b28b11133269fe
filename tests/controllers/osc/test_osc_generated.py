"""The q̈-only QP's data from generated code (``OperationalSpaceQP(..., compile="auto")``, the default, or
``compile=True``) against the QP the NumPy builder shows on Pinocchio's terms (``compile=False``), and the
controller on it against an independent solver (quadprog)."""

from __future__ import annotations

import pickle
from functools import cache

import numpy as np
import pytest

import armctl
from armctl.controllers.osc import (
    FrameOrientationTask,
    FramePoseTask,
    FramePositionTask,
    JointPositionLimit,
    JointVelocityLimit,
    Limit,
    OperationalSpaceQP,
    PostureTask,
    TorqueLimit,
)
from armctl.errors import InvalidParameterError
from tests.controllers.osc.helpers import quadprog_solvers

from .conftest import Q_HOME

qpsolvers = quadprog_solvers()


@cache
def _dynamics(friction: bool = False, compile: bool = True) -> armctl.Dynamics:
    model = armctl.models.panda()
    if friction:
        model = model.with_friction(viscous=0.5, coulomb=[0.8, 0.8, 0.8, 0.8, 0.3, 0.3, 0.3])
    return armctl.Dynamics(model, compile=compile)


def _pose_and_posture(dyn: armctl.Dynamics) -> list:  # type: ignore[type-arg]
    pose = FramePoseTask(kp=400.0)
    target = dyn.frame_pose(Q_HOME)
    target[:3, 3] += [0.1, 0.0, -0.05]
    pose.set_target(target)
    return [pose, PostureTask(7, kp=100.0, weight=1e-3)]


class _Turning:
    """A rotation target turning about the world's z at 0.5 rad/s from ``rot0`` (picklable, as a sweep needs)."""

    def __init__(self, rot0: np.ndarray) -> None:
        self.rot0 = rot0

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        c, s = np.cos(0.5 * t), np.sin(0.5 * t)
        rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        return rz @ self.rot0, np.array([0.0, 0.0, 0.5]), np.zeros(3)


def _three_frames(dyn: armctl.Dynamics) -> list:  # type: ignore[type-arg]
    """A position task on the wrist (joint 5's frame), an orientation task on the tool with a trajectory, and a
    posture task with a fixed target and gains of its own per joint."""
    position = FramePositionTask(frame="panda_joint5", kp=[50.0, 80.0, 120.0], weight=[1.0, 2.0, 0.5])
    position.set_target(dyn.frame_pose(Q_HOME, "panda_joint5")[:3, 3] + [0.02, -0.03, 0.01], [0.1, 0.0, 0.0])
    orientation = FrameOrientationTask(kp=200.0, weight=0.3)
    orientation.set_trajectory(_Turning(dyn.frame_pose(Q_HOME)[:3, :3]))
    posture = PostureTask(7, kp=np.linspace(20.0, 80.0, 7), weight=1e-2)
    posture.set_target(Q_HOME + 0.1, np.full(7, 0.05))
    return [position, orientation, posture]


def _states(count: int, seed: int = 0) -> list[tuple[float, np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(seed)
    return [(0.01 * k, Q_HOME + rng.normal(0.0, 0.1, 7), rng.normal(0.0, 0.3, 7)) for k in range(count)]


@pytest.mark.parametrize(("make", "friction"), [(_pose_and_posture, False), (_three_frames, True)])
def test_generated_data_is_the_qp_the_numpy_builder_shows(make, friction: bool) -> None:  # type: ignore[no-untyped-def]
    """On random states the generated H, g, c, M, h', task rows and unconstrained minimum equal those of the
    public problem that ``ctrl.build(...).problem(0)`` assembles from Pinocchio's terms, with τ substituted:
    H_q̈ = H_q̈q̈ + ε MᵀM, g_q̈ = g_q̈ + ε Mᵀh' (M = A's first block, h' = −b), c = the task rows' ‖W^½ b‖² + ε‖h'‖²,
    q̈₀ = −H_q̈⁻¹ g_q̈ (numpy)."""
    dyn = _dynamics(friction)
    ctrl = OperationalSpaceQP(dyn, make(dyn), limits=[TorqueLimit()])
    gen = ctrl._qdd_qp(ctrl.builder.layout()).generated
    assert gen is not None
    eps = ctrl.builder.regularization
    ref = armctl.Reference(Q_HOME - 0.05, np.full(7, 0.1), np.full(7, -0.2))
    for t, q, qd in _states(20, seed=1):
        gen.run(q, qd, t, ref)
        step = ctrl.build(t, q, qd, ref)
        p = step.problem(0)
        mass, hf = p.A[:, :7], -p.b
        h_red = p.H[:7, :7] + eps * mass.T @ mass
        g_red = p.g[:7] + eps * mass.T @ hf
        lev = step.levels[0]
        scale = 1.0 + np.abs(g_red).max()
        np.testing.assert_allclose(gen.M, mass, atol=1e-12)
        np.testing.assert_allclose(gen.hf, hf, atol=1e-10)
        jr = np.column_stack((lev.jr[:, :7], lev.jr[:, -1]))  # [J | b] on q̈ (the τ columns are zero)
        assert not lev.jr[:, 7:14].any()
        np.testing.assert_allclose(gen.rows, jr, atol=1e-9 * (1 + np.abs(jr).max()))
        np.testing.assert_allclose(gen.H, h_red, atol=1e-10 * np.abs(h_red).max())
        np.testing.assert_allclose(gen.g, g_red, atol=1e-10 * scale)
        np.testing.assert_allclose(gen.c[0], lev.t @ lev.t + eps * hf @ hf, rtol=1e-10)
        qdd0 = -np.linalg.solve(h_red, g_red)
        np.testing.assert_allclose(gen.qdd0, qdd0, atol=1e-7 * (1 + np.abs(qdd0).max()))
        np.testing.assert_allclose(gen.tau0, mass @ gen.qdd0 + hf, atol=1e-9)


def test_on_compiled_dynamics_the_torque_is_the_cold_optimum_of_an_independent_solver() -> None:
    """400 random states through one controller on ``compile=True`` (its QP data from generated code): τ equals
    quadprog's optimum of the QP the controller shows, solved cold, within 1e-4 N·m, on states that bind the
    torque limits and states that do not; and the same τ as the controller on Pinocchio's terms."""
    dyn, plain = _dynamics(), _dynamics(compile=False)
    ctrl = OperationalSpaceQP(dyn, _pose_and_posture(dyn), limits=[TorqueLimit()])
    numpy_path = OperationalSpaceQP(plain, _pose_and_posture(plain), limits=[TorqueLimit()], compile=False)
    assert ctrl._qdd_qp(ctrl.builder.layout()).generated is not None
    assert numpy_path._qdd_qp(numpy_path.builder.layout()).generated is None
    ref = armctl.Reference(Q_HOME)
    errors, binding = [], 0
    for t, q, qd in _states(400):
        tau = ctrl(t, q, qd, ref)
        p = ctrl.build(t, q, qd, ref).problem(0)
        best = np.asarray(qpsolvers.solve_problem(p.to_qpsolvers(), "quadprog").x)[p.variables["tau"]]
        errors.append(float(np.abs(tau - best).max()))
        binding += bool((np.abs(np.abs(best) - dyn.model.effort_limit) < 1e-6).any())
        np.testing.assert_allclose(tau, numpy_path(t, q, qd, ref), atol=1e-6)
    assert 50 < binding < 400
    assert max(errors) <= 1e-4, (int(np.argmax(errors)), max(errors))
    assert ctrl.fallback_counts.get("failed", 0) == 0


def test_the_last_solution_of_a_generated_step_is_the_public_problems() -> None:
    """After a step on generated data, ``last_solution`` shows the same problem, residuals and solution as the
    controller on Pinocchio's terms, and the optimality check passes again."""
    dyn, plain = _dynamics(), _dynamics(compile=False)
    ctrl = OperationalSpaceQP(dyn, _three_frames(dyn))
    other = OperationalSpaceQP(plain, _three_frames(plain), compile=False)
    ref = armctl.Reference(Q_HOME)
    for t, q, qd in _states(10, seed=4):
        ctrl(t, q, qd, ref)
        other(t, q, qd, ref)
        a, b = ctrl.last_solution, other.last_solution
        assert a is not None and b is not None
        pa, pb = a.problem(0), b.problem(0)
        for name in ("H", "g", "A", "b", "C", "l", "u"):
            np.testing.assert_allclose(getattr(pa, name), getattr(pb, name), rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(a.x, b.x, atol=1e-6)
        for name, r in a.residuals.items():
            np.testing.assert_allclose(r, b.residuals[name], atol=1e-6)
        assert ctrl.verify_last_step()


def test_gains_and_weights_changed_between_steps_take_effect_in_the_generated_code() -> None:
    """Gains and weights are inputs of the generated code: changed between steps (a new kp, a new weight), the
    compiled controller gives the torque of a controller on Pinocchio's terms with the same changes."""
    dyn, plain = _dynamics(), _dynamics(compile=False)
    tasks, others = _pose_and_posture(dyn), _pose_and_posture(plain)
    ctrl = OperationalSpaceQP(dyn, tasks, limits=[TorqueLimit(scale=2.0)])
    other = OperationalSpaceQP(plain, others, limits=[TorqueLimit(scale=2.0)], compile=False)
    ref = armctl.Reference(Q_HOME)
    t, q, qd = _states(1, seed=2)[0]
    before = ctrl(t, q, qd, ref)
    for pair in (tasks, others):
        pair[0].kp = [300.0, 300.0, 300.0, 100.0, 100.0, 100.0]
        pair[1].weight = 0.1
    after = ctrl(t, q, qd, ref)
    np.testing.assert_allclose(after, other(t, q, qd, ref), atol=1e-6)
    assert np.abs(after - before).max() > 1.0


def test_limits_that_read_the_state_hold_on_the_generated_path() -> None:
    """Position and velocity limits (bounds that depend on q and q̇) on the generated path: the same τ as on
    Pinocchio's terms, from states near the limits."""
    dyn, plain = _dynamics(), _dynamics(compile=False)
    ctrl = OperationalSpaceQP(dyn, _pose_and_posture(dyn))
    other = OperationalSpaceQP(plain, _pose_and_posture(plain), compile=False)
    assert ctrl._qdd_qp(ctrl.builder.layout()).generated is not None
    upper = dyn.model.upper
    ref = armctl.Reference(Q_HOME)
    rng = np.random.default_rng(3)
    for _ in range(30):
        q = np.minimum(Q_HOME + rng.normal(0.0, 0.5, 7), upper - 1e-3)
        qd = rng.normal(0.0, 1.0, 7)
        np.testing.assert_allclose(ctrl(0.0, q, qd, ref), other(0.0, q, qd, ref), atol=1e-6)


def test_what_the_code_does_not_take_stays_on_the_numpy_path() -> None:
    """A task subclass (its kinematics may be its own) or a limit of a user's (its bounds may read more than q and
    q̇) keeps the controller on Pinocchio's terms; so does ``compile=False``, and ``"auto"`` on a backend whose
    model the generated code is not (the Lagrange backend's rotor coupling)."""

    class MyPose(FramePoseTask):
        pass

    class MyLimit(Limit):
        variable = "tau"
        kind = "my_limit"

        def bounds(self, state):  # type: ignore[no-untyped-def]
            return -50.0 * np.ones(7), 50.0 * np.ones(7)

    dyn = _dynamics()
    pose = MyPose()
    pose.set_target(dyn.frame_pose(Q_HOME))
    for tasks, limits in (
        ([pose], [TorqueLimit()]),
        (_pose_and_posture(dyn), [MyLimit()]),
    ):
        ctrl = OperationalSpaceQP(dyn, tasks, limits=limits)
        assert ctrl._qdd_qp(ctrl.builder.layout()).generated is None
        assert np.isfinite(ctrl(0.0, Q_HOME, np.zeros(7), armctl.Reference(Q_HOME))).all()
    ctrl = OperationalSpaceQP(dyn, _pose_and_posture(dyn), limits=[JointPositionLimit(), JointVelocityLimit()])
    assert ctrl._qdd_qp(ctrl.builder.layout()).generated is not None
    ctrl = OperationalSpaceQP(dyn, _pose_and_posture(dyn), compile=False)
    assert ctrl._qdd_qp(ctrl.builder.layout()).generated is None
    lagrange = armctl.Dynamics(armctl.models.planar_2r(), backend="lagrange")
    posture = [PostureTask(2, kp=50.0)]
    assert OperationalSpaceQP(lagrange, posture)._qdd_qp(ctrl.builder.layout()).generated is None


def test_the_default_takes_generated_code_on_pinocchios_dynamics() -> None:
    """``compile="auto"``: a controller on ``Dynamics(model)`` (not compiled) takes its QP data from generated
    code, with the τ of the NumPy path."""
    plain = _dynamics(compile=False)
    ctrl = OperationalSpaceQP(plain, _pose_and_posture(plain), limits=[TorqueLimit()])
    other = OperationalSpaceQP(plain, _pose_and_posture(plain), limits=[TorqueLimit()], compile=False)
    assert ctrl._qdd_qp(ctrl.builder.layout()).generated is not None
    ref = armctl.Reference(Q_HOME)
    for t, q, qd in _states(20, seed=6):
        np.testing.assert_allclose(ctrl(t, q, qd, ref), other(t, q, qd, ref), atol=1e-6)


def test_without_a_compiler_auto_warns_once_and_true_raises(monkeypatch, tmp_path) -> None:  # type: ignore[no-untyped-def]
    """No C compiler (``CC`` a missing program, an empty cache): ``"auto"`` takes the NumPy path with one
    PerformanceWarning naming the fix; ``compile=True`` raises BackendError; ``compile="yes"`` is refused."""
    from armctl.controllers.osc.controller import FALLBACK
    from armctl.errors import BackendError, PerformanceWarning

    monkeypatch.setenv("CC", "no-such-compiler-armctl")
    monkeypatch.setenv("ARMCTL_CACHE", str(tmp_path))
    FALLBACK.reset()
    dyn = armctl.Dynamics(armctl.models.planar_2r())
    with pytest.warns(PerformanceWarning, match="no C compiler") as caught:
        first = OperationalSpaceQP(dyn, [PostureTask(2, kp=50.0)])
        OperationalSpaceQP(dyn, [PostureTask(2, kp=60.0)])
    assert len(caught) == 1
    assert first._qdd_qp(first.builder.layout()).generated is None
    assert np.isfinite(first(0.0, np.zeros(2), np.zeros(2), armctl.Reference([0.1, 0.2]))).all()
    with pytest.raises(BackendError):
        OperationalSpaceQP(dyn, [PostureTask(2, kp=50.0)], compile=True)
    with pytest.raises(InvalidParameterError, match="compile must be True"):
        OperationalSpaceQP(dyn, [PostureTask(2, kp=50.0)], compile="yes")


def test_out_of_scale_rows_on_the_generated_path_are_refused_by_name() -> None:
    """A target 10 000 km away on the compiled controller: the same refusal as on Pinocchio's terms, naming the
    task, its error and its gain."""
    dyn = _dynamics()
    tasks = _pose_and_posture(dyn)
    far = dyn.frame_pose(Q_HOME)
    far[:3, 3] += [1e7, 0.0, 0.0]
    tasks[0].set_target(far)
    ctrl = OperationalSpaceQP(dyn, tasks, limits=[TorqueLimit()])
    with pytest.raises(InvalidParameterError, match=r"task 'pose\[tool\]' asks for .* its kp reaches 400"):
        ctrl(0.0, Q_HOME, np.zeros(7), armctl.Reference(Q_HOME))


def test_a_compiled_controller_pickles() -> None:
    """A controller on generated code crosses a pickle (as a sweep's worker receives it) and gives the same τ."""
    dyn = _dynamics()
    ctrl = OperationalSpaceQP(dyn, _three_frames(dyn))
    ref = armctl.Reference(Q_HOME)
    t, q, qd = _states(1, seed=5)[0]
    tau = ctrl(t, q, qd, ref)
    copy = pickle.loads(pickle.dumps(ctrl))
    assert copy._qdd_qp(copy.builder.layout()).generated is not None
    np.testing.assert_allclose(copy(t, q, qd, ref), tau, atol=1e-12)


def test_a_closed_loop_run_on_the_generated_path_is_the_numpy_paths_run() -> None:
    """A reachable target that drives a joint onto its velocity limit (0.78 m, kp 100), 1 s with the default
    limits (torque, position viability, velocity) in closed loop on the Panda: the controller on compile=True gives
    the run of the controller on Pinocchio's terms (joint positions within 1e-6 rad at every sample), and its
    steps took the generated path."""
    from armctl import sim

    dyn, plain = _dynamics(), _dynamics(compile=False)
    runs = []
    for d in (dyn, plain):
        target = d.frame_pose(Q_HOME)
        target[:3, 3] = 0.78 * np.array([-0.91, 0.15, 0.38]) / np.linalg.norm([-0.91, 0.15, 0.38])
        pose = FramePoseTask(kp=100.0)
        pose.set_target(target)
        ctrl = OperationalSpaceQP(d, [pose, PostureTask(7, kp=100.0, weight=1e-3)], compile=d is dyn)
        runs.append(sim.simulate(plain, ctrl, armctl.Reference(Q_HOME), 1.0, q0=Q_HOME))
        if d is dyn:
            assert ctrl._qdd_qp(ctrl.builder.layout()).generated is not None
    ratio = np.abs(runs[0].qd) / dyn.model.velocity_limit
    assert (ratio > 0.999).sum() > 100  # the velocity limits bind
    np.testing.assert_allclose(runs[0].q, runs[1].q, atol=1e-6)


def test_each_reference_reaches_the_posture_rows_of_the_generated_code() -> None:
    """A posture task following the controller's reference, then a fixed target, then the reference again: the
    generated step's τ is the NumPy path's at every call, whether the Reference object is a new one, the same
    one again or a subclass."""

    class Shifted(armctl.Reference):
        pass

    def make(compile: bool) -> tuple[OperationalSpaceQP, PostureTask]:
        pose = FramePoseTask(kp=400.0)
        pose.set_target(_dynamics().frame_pose(Q_HOME))
        posture = PostureTask(7, kp=100.0, weight=1e-2)
        return OperationalSpaceQP(_dynamics(compile=compile), [pose, posture], compile=compile), posture

    (ctrl, posture), (numpy_path, numpy_posture) = make(True), make(False)
    assert ctrl.uses_generated_code
    rng = np.random.default_rng(4)
    refs = [armctl.Reference(Q_HOME + rng.normal(0.0, 0.2, 7), rng.normal(0.0, 0.3, 7)) for _ in range(3)]
    refs += [refs[0], refs[0], Shifted(Q_HOME - 0.1), refs[0]]
    q, qd = Q_HOME + 0.05, np.full(7, 0.1)
    for k, ref in enumerate(refs):
        if k == 4:  # a fixed target, then the reference again
            posture.set_target(Q_HOME + 0.2)
            numpy_posture.set_target(Q_HOME + 0.2)
        if k == 5:
            posture.set_target(None)
            numpy_posture.set_target(None)
        np.testing.assert_allclose(ctrl(0.0, q, qd, ref), numpy_path(0.0, q, qd, ref), atol=1e-9)
