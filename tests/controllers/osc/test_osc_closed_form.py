"""The closed-form operational-space baseline (Λ = (J M⁻¹ Jᵀ)⁻¹, dynamically consistent null space) and how it
compares with the QP near a singular configuration, without simulation: the plant's response is
the forward dynamics of the exact model."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import armctl
from armctl.controllers.osc import ClosedFormOSC, FramePoseTask, OperationalSpaceQP, PostureTask, TorqueLimit
from armctl.errors import SingularityWarning
from tests.controllers.osc.helpers import Q_HOME

#: A pose-singular configuration of the Panda (σ_min of the 6×7 tool Jacobian ≈ 2e-7), found by minimising
#: σ_min over q₄; the singular task direction moves the tool in the x–z plane and turns it about y.
Q_SINGULAR = np.array([0.0, 0.3, 0.0, -0.46700102, 0.0, 1.571, 0.785])


def _pose_task(dyn: armctl.Dynamics, q: np.ndarray, offset: np.ndarray, kp: float = 100.0) -> FramePoseTask:
    task = FramePoseTask(kp=kp)
    target = dyn.frame_pose(q)
    target[:3, 3] += offset[:3]
    target[:3, :3] = Rotation.from_rotvec(offset[3:]).as_matrix() @ target[:3, :3]
    task.set_target(target)
    return task


def test_closed_form_realises_the_task_and_keeps_the_posture_in_the_null_space(panda: armctl.Dynamics) -> None:
    q, qd = Q_HOME + 0.05, np.linspace(0.2, -0.2, 7)
    offset = np.array([0.02, 0.01, -0.03, 0.05, 0.0, -0.04])
    J = panda.jacobian(q)
    h = 1e-7
    drift = (panda.jacobian(q + h * qd) @ qd - panda.jacobian(q - h * qd) @ qd) / (2 * h)
    accs = []
    for kp_posture in (10.0, 400.0):
        task = _pose_task(panda, q, offset)
        ctrl = ClosedFormOSC(panda, task, PostureTask(7, kp=kp_posture))
        tau = ctrl(0.0, q, qd, armctl.Reference(Q_HOME))
        qdd = panda.forward_dynamics(q, qd, tau)
        pose = panda.frame_pose(q)
        target = task.target.at(0.0)[0]
        e = np.r_[target[:3, 3] - pose[:3, 3], Rotation.from_matrix(target[:3, :3] @ pose[:3, :3].T).as_rotvec()]
        np.testing.assert_allclose(J @ qdd + drift, 100.0 * e - 20.0 * (J @ qd), atol=1e-6)
        accs.append(qdd)
    assert np.abs(accs[0] - accs[1]).max() > 1e-2  # the posture does act, only where the task does not see it


def test_near_a_singularity_closed_form_torque_spikes_while_the_qp_stays_within_limits(panda: armctl.Dynamics) -> None:
    """Approaching Q_SINGULAR with a pose error along the singular direction: the closed-form torque grows like
    1/σ_min and leaves the limits far behind; the QP's torque never does, and its task error degrades smoothly
    (the achieved task acceleration stays bounded)."""
    limit = panda.model.effort_limit
    u = np.linalg.svd(panda.jacobian(Q_SINGULAR))[0][:, -1]  # singular task direction
    offset = 0.01 * u / np.linalg.norm(u[:3])  # 1 cm along it
    ratios_cf, ratios_qp, achieved = [], [], []
    for d in (0.3, 0.1, 0.03, 0.01, 0.003):
        q = Q_SINGULAR.copy()
        q[3] += d
        sigma = np.linalg.svd(panda.jacobian(q), compute_uv=False).min()
        cf = ClosedFormOSC(panda, _pose_task(panda, q, offset), PostureTask(7, kp=25.0))
        qp = OperationalSpaceQP(
            panda, [_pose_task(panda, q, offset), PostureTask(7, kp=25.0, priority=1)], limits=[TorqueLimit()]
        )
        ref = armctl.Reference(q)
        ratios_cf.append(np.max(np.abs(cf(0.0, q, np.zeros(7), ref)) / limit))
        tau = qp(0.0, q, np.zeros(7), ref)
        ratios_qp.append(np.max(np.abs(tau) / limit))
        achieved.append(np.linalg.norm(panda.jacobian(q) @ panda.forward_dynamics(q, np.zeros(7), tau)))
        assert sigma < 0.2
    assert ratios_cf[-1] > 3.0 and ratios_cf[-1] > 10 * ratios_cf[0]  # spikes beyond the limits
    assert max(ratios_qp) <= 1.0 + 1e-9  # the QP stays within them
    assert max(achieved) < 10 * max(achieved[0], 1.0)  # bounded: no spike in the QP's motion either


def test_at_a_singular_configuration_lambda_is_damped_to_the_condition_limit(panda: armctl.Dynamics) -> None:
    """At Q_SINGULAR (cond Λ ≈ 4e14) the controller damps Λ: δ² = μ_max/κ − μ_min with μ the eigenvalues of
    J M⁻¹ Jᵀ (computed here with numpy), the torque is that of Khatib's law with Λ = (J M⁻¹ Jᵀ + δ² I)⁻¹, and
    one step further from the singularity (cond Λ ≈ 1e7) nothing is damped."""
    task = _pose_task(panda, Q_SINGULAR, np.array([0.01, 0.0, 0.01, 0.0, 0.02, 0.0]))
    posture = PostureTask(7, kp=25.0)
    ctrl = ClosedFormOSC(panda, task, posture)
    ref = armctl.Reference(Q_HOME)
    qd = np.linspace(-0.1, 0.1, 7)
    tau = ctrl(0.0, Q_SINGULAR, qd, ref)
    M, J = panda.mass_matrix(Q_SINGULAR), panda.jacobian(Q_SINGULAR)
    lam_inv = J @ np.linalg.solve(M, J.T)
    mu = np.linalg.eigvalsh(lam_inv)
    assert mu[-1] / mu[0] > 1e14
    damping = mu[-1] / 1e12 - mu[0]
    assert ctrl.last_log["damping"] == pytest.approx(damping, rel=1e-6)
    state = ctrl.evaluator.evaluate(Q_SINGULAR, qd)
    _, drift, xdd = task.desired_acceleration(state, 0.0, ref)
    qdd0 = posture.desired_acceleration(state, 0.0, ref)[2]
    lam = np.linalg.inv(lam_inv + damping * np.eye(6))
    h = panda.inverse_dynamics(Q_SINGULAR, qd, np.zeros(7))
    expected = J.T @ lam @ (xdd - drift - J @ qdd0) + M @ qdd0 + h
    # Λ's condition number is 1e12 here: its rounding (1e12 × ε ≈ 1e-4 relative) is what the two computations of
    # J M⁻¹ Jᵀ (Cholesky there, LU here) may differ by
    np.testing.assert_allclose(tau, expected, rtol=1e-3, atol=1e-3 * np.abs(expected).max())
    q = Q_SINGULAR.copy()
    q[3] += 0.01
    ctrl(0.0, q, qd, ref)
    assert ctrl.last_log["damping"] == 0.0


def test_on_a_planar_arm_the_rows_it_cannot_move_are_damped_and_the_others_met() -> None:
    """A pose task (six rows) on the planar 3R arm, which moves its tool in the x–z plane only: J M⁻¹ Jᵀ is
    singular outright (a pseudo-inverse would hide it). The controller damps it and its torque still realises
    the task's in-plane acceleration (x, z, turning about y) to 1e-6, from the forward dynamics."""
    dyn = armctl.Dynamics(armctl.models.planar_3r())
    q, qd = np.array([0.4, 0.9, -0.5]), np.array([0.3, -0.2, 0.1])
    task = FramePoseTask(kp=50.0)
    target = dyn.frame_pose(q)
    target[:3, 3] += [0.02, 0.0, -0.01]
    task.set_target(target)
    ctrl = ClosedFormOSC(dyn, task)
    tau = ctrl(0.0, q, qd, armctl.Reference(q))
    assert np.isfinite(tau).all() and ctrl.last_log["damping"] > 0.0
    state = ctrl.evaluator.evaluate(q, qd)
    J, drift, xdd = task.desired_acceleration(state, 0.0, armctl.Reference(q))
    achieved = J @ dyn.forward_dynamics(q, qd, tau) + drift
    plane = [0, 2, 4]
    np.testing.assert_allclose(achieved[plane], xdd[plane], atol=1e-6 * (1 + np.abs(xdd).max()))


def test_damped_steps_are_summarised_once_per_run(panda: armctl.Dynamics) -> None:
    """Steps at the singular configuration and steps away from it: end_run warns once (SingularityWarning) with
    the number of damped steps, then counts afresh; a run without damping ends silently."""
    ctrl = ClosedFormOSC(panda, _pose_task(panda, Q_SINGULAR, np.zeros(6)), PostureTask(7))
    ref = armctl.Reference(Q_HOME)
    for q in (Q_SINGULAR, Q_HOME, Q_SINGULAR, Q_SINGULAR):
        ctrl(0.0, q, np.zeros(7), ref)
    with pytest.warns(SingularityWarning, match=r"over 4 control steps: .* damped on 3 ") as record:
        ctrl.end_run()
    assert len(record) == 1
    ctrl(0.0, Q_HOME, np.zeros(7), ref)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert ctrl.end_run() is None
