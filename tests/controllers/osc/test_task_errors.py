"""What the operational-space controllers log of their frame tasks: target − actual by Pinocchio's own forward
kinematics, NaN on rows of weight 0, nothing for other tasks or with ``log_task_errors = False``."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

import armctl
from armctl.controllers.osc import (
    ClosedFormOSC,
    FrameOrientationTask,
    FramePoseTask,
    FramePositionTask,
    OperationalSpaceQP,
    PostureTask,
)

Q = np.array([0.1, -0.6, 0.2, -2.2, 0.1, 1.8, 0.6])


def _reference_pose(model: armctl.RobotModel, q: np.ndarray, frame: str) -> pin.SE3:
    pm = model.to_pinocchio()
    pd = pm.createData()
    pin.framesForwardKinematics(pm, pd, q)
    return pd.oMf[pm.getFrameId(frame)]


def test_each_frame_task_logs_its_errors_against_pinocchio_s_pose() -> None:
    model = armctl.models.panda()
    dyn = armctl.Dynamics(model)
    target = dyn.frame_pose(model.named_poses["ready"])
    pose = FramePoseTask(kp=100.0, weight=[1, 1, 0, 1, 1, 1])
    pose.set_target(target)
    hand = FramePositionTask("panda_link7", kp=50.0)
    hand.set_target((0.3, 0.0, 0.6))
    wrist = FrameOrientationTask("panda_link5", kp=50.0, weight=0.5)
    wrist.set_target(np.eye(3))
    ctrl = OperationalSpaceQP(dyn, [pose, hand, wrist, PostureTask(7, kp=10.0, priority=1)])
    ctrl(0.0, Q, np.zeros(7), armctl.Reference(Q))
    log = ctrl.last_log
    tool = _reference_pose(model, Q, model.tool_frame)
    e = log["position_error[pose[tool]]"]
    np.testing.assert_allclose(e[:2], (target[:3, 3] - tool.translation)[:2], atol=1e-12)
    assert np.isnan(e[2])  # weight 0: free
    np.testing.assert_allclose(
        log["orientation_error[pose[tool]]"], pin.log3(target[:3, :3] @ tool.rotation.T), atol=1e-12
    )
    link7 = _reference_pose(model, Q, "panda_link7")
    np.testing.assert_allclose(log["position_error[position[panda_link7]]"], (0.3, 0.0, 0.6) - link7.translation)
    link5 = _reference_pose(model, Q, "panda_link5")
    np.testing.assert_allclose(log["orientation_error[orientation[panda_link5]]"], pin.log3(link5.rotation.T))
    assert not any("posture" in k for k in log)
    assert (
        "orientation_error[position[panda_link7]]" not in log and "position_error[orientation[panda_link5]]" not in log
    )


def test_logging_can_be_turned_off_and_the_closed_form_logs_too() -> None:
    model = armctl.models.panda()
    dyn = armctl.Dynamics(model)
    pose = FramePoseTask(kp=100.0)
    pose.set_target(dyn.frame_pose(Q))
    ctrl = OperationalSpaceQP(dyn, [pose])
    ctrl.log_task_errors = False
    ctrl(0.0, Q, np.zeros(7), armctl.Reference(Q))
    assert not any(k.endswith("[pose[tool]]") for k in ctrl.last_log)
    closed = ClosedFormOSC(dyn, pose, PostureTask(7, kp=10.0))
    closed(0.0, Q, np.zeros(7), armctl.Reference(Q))
    np.testing.assert_allclose(closed.last_log["position_error[pose[tool]]"], 0.0, atol=1e-12)


def test_the_logger_reads_any_backend_s_frames() -> None:
    """Without Pinocchio's workspace (the Lagrange backend) the frame poses come from the kernel's own forward
    kinematics; the errors are the same."""
    from armctl.controllers.osc.task_errors import FrameTaskErrors

    model = armctl.models.planar_3r()
    q = np.array([0.3, -0.7, 0.4])
    task = FramePoseTask(kp=10.0, weight=[1, 0, 1, 0, 1, 0])  # the plane's rows
    target = armctl.Dynamics(model).frame_pose([0.1, 0.2, -0.3])
    task.set_target(target)
    ref = _reference_pose(model, q, model.tool_frame)
    for backend in ("pinocchio", "lagrange"):
        log = FrameTaskErrors([task])(armctl.Dynamics(model, backend=backend).kernel, q, 0.0)
        e_pos, e_rot = log["position_error[pose[tool]]"], log["orientation_error[pose[tool]]"]
        np.testing.assert_allclose(e_pos[[0, 2]], (target[:3, 3] - ref.translation)[[0, 2]], atol=1e-12)
        np.testing.assert_allclose(e_rot[1], pin.log3(target[:3, :3] @ ref.rotation.T)[1], atol=1e-12)
        assert np.isnan(e_pos[1]) and np.isnan(e_rot[[0, 2]]).all()
