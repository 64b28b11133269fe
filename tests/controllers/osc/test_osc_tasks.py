"""Tasks of the operational-space QP: errors, Jacobians and drifts against finite differences of the
frame pose and scipy's rotations; the three forms of a gain."""

from __future__ import annotations

import warnings

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import armctl
from armctl.controllers.osc import FrameOrientationTask, FramePoseTask, FramePositionTask, PostureTask
from armctl.controllers.osc.state import ModelEvaluator
from armctl.controllers.osc.tasks.rotation import rotation_error
from tests.controllers.osc.helpers import Q_HOME, panda_dynamics


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 10_000), st.floats(0.0, np.pi))
def test_rotation_error_is_the_rotation_vector(seed: int, angle: float) -> None:
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    rot = Rotation.random(random_state=seed).as_matrix()
    rot_ref = Rotation.from_rotvec(angle * axis).as_matrix() @ rot
    w = np.array(rotation_error(rot_ref, rot))
    if angle < np.pi - 1e-6:
        np.testing.assert_allclose(w, angle * axis, atol=1e-9)
    else:  # at π the axis sign is arbitrary
        assert min(np.abs(w - angle * axis).max(), np.abs(w + angle * axis).max()) < 1e-6


@settings(max_examples=80, deadline=None)
@given(st.integers(0, 10_000), st.sampled_from([1e-9, 0.3, 2.0, 3.1, np.pi - 1e-3, np.pi - 1e-6, np.pi]))
def test_rotation_error_of_a_rounded_target(seed: int, angle: float) -> None:
    """A target rounded to four decimals (which the target check accepts: R Rᵀ = I to 1e-4) is not quite a
    rotation; its error must still be the rotation vector to the rounding's order, also near a half-turn, where
    an earlier formula (θ from the trace, then the antisymmetric part over 2 sin θ) was off by up to π."""
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    rot = Rotation.random(random_state=seed).as_matrix()
    rot_ref = np.round(Rotation.from_rotvec(angle * axis).as_matrix() @ rot, 4)
    w = rotation_error(rot_ref, rot)
    off = np.abs(w - angle * axis).max()
    if angle > np.pi - 1e-2:  # the axis sign is arbitrary at π, and ill-determined just below it
        off = min(off, np.abs(w + angle * axis).max())
    assert off < 5e-4


def test_frame_kinematics_against_finite_differences(rng: np.random.Generator) -> None:
    """J from ``position(q + h δ) − position(q − h δ)``, J̇q̇ from ``J(q + h q̇) q̇ − J(q − h q̇) q̇`` — for both
    the Pinocchio one-pass path and the generic path of any backend."""
    dyn = panda_dynamics()
    q, qd = Q_HOME + rng.uniform(-0.4, 0.4, 7), rng.uniform(-1, 1, 7)
    h = 1e-6
    jac_fd = np.zeros((3, 7))
    for i in range(7):
        d = np.zeros(7)
        d[i] = h
        jac_fd[:, i] = (dyn.frame_pose(q + d)[:3, 3] - dyn.frame_pose(q - d)[:3, 3]) / (2 * h)
    drift_fd = (dyn.jacobian(q + h * qd) @ qd - dyn.jacobian(q - h * qd) @ qd) / (2 * h)
    fk = ModelEvaluator(dyn).evaluate(q, qd).frame("panda_link7")
    fk_tool = ModelEvaluator(dyn).evaluate(q, qd).frame(None)
    np.testing.assert_allclose(fk_tool.jacobian[:3], jac_fd, atol=1e-8)
    np.testing.assert_allclose(fk_tool.drift, drift_fd, atol=1e-6)
    np.testing.assert_allclose(fk.position, dyn.frame_pose(q, "panda_link7")[:3, 3], atol=1e-12)
    np.testing.assert_allclose(fk_tool.velocity, dyn.jacobian(q) @ qd, atol=1e-12)


def test_one_evaluator_follows_the_state(rng: np.random.Generator) -> None:
    """The same evaluator at successive states gives each state's M, h = C q̇ + g and frame placements (its
    arrays are views of a workspace rewritten in place: they must never be a stale copy), for two frames read
    in turn."""
    dyn = panda_dynamics()
    ev = ModelEvaluator(dyn)
    for _ in range(4):
        q, qd = Q_HOME + rng.uniform(-0.8, 0.8, 7), rng.uniform(-1, 1, 7)
        state = ev.evaluate(q, qd)
        np.testing.assert_allclose(state.mass, dyn.mass_matrix(q), atol=1e-12)
        np.testing.assert_allclose(state.bias, dyn.inverse_dynamics(q, qd, np.zeros(7)), atol=1e-10)
        for frame in (None, "panda_link4"):
            fk, pose = state.frame(frame), dyn.frame_pose(q, frame)
            np.testing.assert_allclose(fk.position, pose[:3, 3], atol=1e-12)
            np.testing.assert_allclose(fk.rotation, pose[:3, :3], atol=1e-12)


def test_the_three_forms_of_a_gain_agree(panda: armctl.Dynamics) -> None:
    state = ModelEvaluator(panda).evaluate(Q_HOME + 0.1, np.full(7, 0.2))
    out = []
    for kp, kd in ((50.0, 10.0), (np.full(3, 50.0), np.full(3, 10.0)), (50.0 * np.eye(3), 10.0 * np.eye(3))):
        task = FrameOrientationTask(kp=kp, kd=kd)
        task.set_target(Rotation.from_rotvec([0.1, 0.2, -0.1]).as_matrix())
        out.append(task.residual(state, 0.0, armctl.Reference(Q_HOME))[1])
    np.testing.assert_allclose(out[0], out[1], rtol=1e-12)
    np.testing.assert_allclose(out[0], out[2], rtol=1e-12)
    aniso = FramePositionTask(kp=[10.0, 20.0, 30.0], kd=[1.0, 2.0, 3.0])
    aniso.set_target([0.5, 0.0, 0.5])
    _, b = aniso.residual(state, 0.0, armctl.Reference(Q_HOME))
    fk = state.frame(None)
    expected = np.array([10.0, 20, 30]) * ([0.5, 0.0, 0.5] - fk.position) - [1.0, 2, 3] * fk.velocity[:3] - fk.drift[:3]
    np.testing.assert_allclose(b, expected, atol=1e-12)


def test_default_kd_is_critical_damping_for_every_form_of_kp() -> None:
    # scalar and vector: 2√k_p entry by entry; matrix: the K_d with K_d² = 4 K_p, symmetric, whose error
    # dynamics ë + K_d ė + K_p e = 0 have every eigenvalue double (critically damped), checked here on the
    # companion matrix's spectrum
    assert np.allclose(FramePositionTask(kp=49.0).kd, 14.0 * np.eye(3), rtol=1e-15)
    np.testing.assert_allclose(FramePositionTask(kp=[4.0, 9.0, 100.0]).kd, np.diag([4.0, 6.0, 20.0]), rtol=1e-14)
    rng = np.random.default_rng(3)
    a = rng.standard_normal((6, 6))
    kp = a @ a.T + 6.0 * np.eye(6)
    kd = FramePoseTask(kp=kp).kd
    np.testing.assert_allclose(kd, kd.T, atol=1e-12)
    np.testing.assert_allclose(kd @ kd, 4.0 * kp, rtol=1e-10, atol=1e-10)
    companion = np.block([[np.zeros((6, 6)), np.eye(6)], [-kp, -kd]])
    poles = np.sort(np.linalg.eigvals(companion).real)
    np.testing.assert_allclose(poles[0::2], poles[1::2], rtol=1e-4)  # in pairs: −√λ_i twice
    np.testing.assert_allclose(poles[0::2], -np.sqrt(np.linalg.eigvalsh(kp))[::-1], rtol=1e-4)


def test_posture_follows_the_reference_unless_fixed(panda: armctl.Dynamics) -> None:
    state = ModelEvaluator(panda).evaluate(Q_HOME, np.zeros(7))
    task = PostureTask(7, kp=4.0, kd=1.0)
    ref = armctl.Reference(Q_HOME + 0.1, np.full(7, 0.5), np.full(7, 2.0))
    J, b = task.residual(state, 0.0, ref)
    assert J is None
    np.testing.assert_allclose(b, 2.0 + 1.0 * 0.5 + 4.0 * 0.1)
    task.set_target(Q_HOME)
    np.testing.assert_allclose(task.residual(state, 0.0, ref)[1], 0.0)


def test_pose_task_residual_is_the_textbook_law(panda: armctl.Dynamics) -> None:
    """ẍ* − J̇q̇ = ẍ_ref + K_d (V_ref − J q̇) + K_p [p_ref − p; log(R_ref Rᵀ)] − J̇q̇ with full 6×6 gains, written out
    with SciPy's rotation vector; a subclass that overrides ``kinematics`` is used by the residual too; an
    np.matrix target is taken as the same pose."""
    state = ModelEvaluator(panda).evaluate(Q_HOME + 0.1, np.full(7, 0.2))
    b = np.random.default_rng(3).uniform(-1.0, 1.0, (6, 6))
    kp, kd = 50.0 * (np.eye(6) + 0.05 * b @ b.T), 10.0 * np.eye(6) + 0.05 * (b + b.T)  # SPD, not diagonal
    target = np.eye(4)
    target[:3, :3] = Rotation.from_rotvec([0.1, -0.2, 0.3]).as_matrix()
    target[:3, 3] = [0.4, 0.1, 0.5]
    twist, acc = np.array([0.1, 0.0, -0.1, 0.2, 0.0, 0.1]), np.array([0.0, 1.0, 0.0, 0.0, -1.0, 0.5])
    task = FramePoseTask(kp=kp, kd=kd)
    task.set_target(target, twist, acc)
    fk = state.frame(None)
    e = np.concatenate([target[:3, 3] - fk.position, Rotation.from_matrix(target[:3, :3] @ fk.rotation.T).as_rotvec()])
    expected = acc + kd @ (twist - fk.jacobian @ state.qd) + kp @ e - fk.drift
    ref = armctl.Reference(Q_HOME)
    np.testing.assert_allclose(task.residual(state, 0.0, ref)[1], expected, rtol=1e-10, atol=1e-10)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PendingDeprecationWarning)  # NumPy's, on making an np.matrix
        as_matrix = np.matrix(target)
    task.set_target(as_matrix, twist, acc)
    np.testing.assert_allclose(task.residual(state, 0.0, ref)[1], expected, rtol=1e-10, atol=1e-10)

    class Shifted(FramePoseTask):
        def kinematics(self, s, t, r):  # type: ignore[no-untyped-def]
            J, d, err, ed, a = super().kinematics(s, t, r)
            return J, d, err + np.array([0.0, 0.0, 0.05, 0.0, 0.0, 0.0]), ed, a

    shifted = Shifted(kp=kp, kd=kd)
    shifted.set_target(target, twist, acc)
    np.testing.assert_allclose(shifted.residual(state, 0.0, ref)[1], expected + kp[:, 2] * 0.05, rtol=1e-10, atol=1e-10)


def test_posture_residual_is_the_textbook_law(panda: armctl.Dynamics) -> None:
    """ẍ* = q̈_ref + K_d (q̇_ref − q̇) + K_p (q_ref − q) with full 7×7 gains, written out; a gain reassigned
    later takes effect; a subclass that overrides ``kinematics`` is used by the residual too."""
    rng = np.random.default_rng(5)
    q, qd = Q_HOME + rng.uniform(-0.3, 0.3, 7), rng.uniform(-1.0, 1.0, 7)
    state = ModelEvaluator(panda).evaluate(q, qd)
    b = rng.uniform(-1.0, 1.0, (7, 7))
    kp, kd = 40.0 * (np.eye(7) + 0.05 * b @ b.T), 8.0 * np.eye(7) + 0.05 * (b + b.T)  # SPD, not diagonal
    ref = armctl.Reference(Q_HOME + 0.2, rng.uniform(-1, 1, 7), rng.uniform(-3, 3, 7))
    task = PostureTask(7, kp=kp, kd=kd)
    J, got = task.residual(state, 0.0, ref)
    assert J is None
    np.testing.assert_allclose(got, ref.qdd + kd @ (ref.qd - qd) + kp @ (ref.q - q), rtol=1e-12, atol=1e-12)
    task.kp = 3.0
    np.testing.assert_allclose(
        task.residual(state, 0.0, ref)[1], ref.qdd + kd @ (ref.qd - qd) + 3.0 * (ref.q - q), rtol=1e-12, atol=1e-12
    )

    class Offset(PostureTask):
        def kinematics(self, s, t, r):  # type: ignore[no-untyped-def]
            J, d, err, ed, a = super().kinematics(s, t, r)
            return J, d, err + 0.01, ed, a

    offset = Offset(7, kp=kp, kd=kd)
    np.testing.assert_allclose(
        offset.residual(state, 0.0, ref)[1],
        ref.qdd + kd @ (ref.qd - qd) + kp @ (ref.q - q + 0.01),
        rtol=1e-12,
        atol=1e-12,
    )


@settings(max_examples=100, deadline=None)
@given(
    st.integers(0, 10_000),
    st.sampled_from([0.0, 1e-12, 1e-7, 3e-6, 1e-3, 0.3, 2.0, 3.1, np.pi - 1e-5, np.pi - 1e-7, np.pi]),
    st.booleans(),
)
def test_the_generated_codes_rotation_error_is_pinocchios(seed: int, angle: float, rounded: bool) -> None:
    """rotation_error_sx (CasADi, for generated code) against rotation_error (Pinocchio's log3) on the branches
    of the log: zero, the series below ε^(1/3), the formula, and within ε^(1/3) of a half-turn; with targets
    rounded to four decimals (not quite rotations, as the target check allows). At a half-turn exactly the axis's
    sign is arbitrary (both logs are the rotation): there the two may differ by it."""
    import casadi as cs

    from armctl.controllers.osc.tasks.rotation import rotation_error_sx

    a, b = cs.SX.sym("a", 3, 3), cs.SX.sym("b", 3, 3)
    log = cs.Function("log", [a, b], [rotation_error_sx(a, b)])
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    rot = Rotation.random(random_state=seed).as_matrix()
    rot_ref = Rotation.from_rotvec(angle * axis).as_matrix() @ rot
    if rounded:
        rot_ref = np.round(rot_ref, 4)
    got, want = np.array(log(rot_ref, rot)).ravel(), rotation_error(rot_ref, rot)
    if angle == np.pi and np.abs(got + want).max() < 1e-9:
        return
    np.testing.assert_allclose(got, want, atol=1e-9)


def test_a_weight_changed_between_steps_takes_effect_for_its_own_controller_only() -> None:
    """A task's weight or gain counts its own changes (``revision``): changed between steps, it changes its
    controller's τ to that of a fresh controller with the new weight, and leaves another controller's alone."""
    from armctl.controllers.osc import OperationalSpaceQP

    dyn = panda_dynamics()

    def tasks() -> list[object]:
        pose = FramePoseTask(kp=400.0)
        target = dyn.frame_pose(Q_HOME)
        target[:3, 3] += [0.05, 0.0, 0.0]
        pose.set_target(target)
        return [pose, PostureTask(7, kp=100.0, weight=1e-3)]

    mine, theirs = tasks(), tasks()
    ctrl, other = OperationalSpaceQP(dyn, mine), OperationalSpaceQP(dyn, theirs)
    ref = armctl.Reference(Q_HOME - 0.1)
    q, qd = Q_HOME + 0.05, np.full(7, 0.1)
    before, other_before = ctrl(0.0, q, qd, ref), other(0.0, q, qd, ref)
    revision = mine[1].revision
    mine[1].weight = 0.5
    mine[0].kd = 10.0
    assert mine[1].revision == revision + 1 and theirs[1].revision == revision
    fresh = tasks()
    fresh[1].weight = 0.5
    fresh[0].kd = 10.0
    after = ctrl(0.0, q, qd, ref)
    np.testing.assert_allclose(after, OperationalSpaceQP(dyn, fresh)(0.0, q, qd, ref), atol=1e-9)
    assert np.abs(after - before).max() > 1e-2
    np.testing.assert_array_equal(other(0.0, q, qd, ref), other_before)


class _Line:
    """A straight-line position target of its own arrays (picklable: a sweep sends it to its workers)."""

    def __init__(self) -> None:
        self.p0, self.v = np.array([0.4, 0.0, 0.5]), np.array([0.0, 0.1, 0.0])

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.p0 + t * self.v, self.v, 0.0 * self.v


def test_an_unpickled_trajectory_takes_the_fast_path(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """After unpickling, the trajectory's arrays have an equal but distinct float64 dtype: the target must still
    take the fast path (no entry-by-entry check, counted: the target module's ``vector`` and ``matrix``) and give
    the original's values."""
    import pickle

    from armctl.controllers.osc.tasks import target as target_module

    calls = []
    for name in ("vector", "matrix"):
        slow = getattr(target_module, name)
        monkeypatch.setattr(target_module, name, lambda *a, _slow=slow, **k: calls.append(1) or _slow(*a, **k))
    original, copy = FramePositionTask(kp=100.0), FramePositionTask(kp=100.0)
    original.set_trajectory(_Line())
    copy.set_trajectory(pickle.loads(pickle.dumps(_Line())))
    for t in np.linspace(0.0, 1.0, 50):
        for got, want in zip(copy.target.at(float(t)), original.target.at(float(t)), strict=True):
            np.testing.assert_array_equal(got, want)
    assert calls == []
