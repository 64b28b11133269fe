"""What the operational-space controllers log of their frame tasks (targets and weights, under keys that name
the task and its frame), and the errors a run's result derives from them: target − actual by Pinocchio's own
forward kinematics, NaN on free rows and on samples without a target."""

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
from armctl.sim.tracking import task_errors

Q = np.array([0.1, -0.6, 0.2, -2.2, 0.1, 1.8, 0.6])


def _reference_pose(model: armctl.RobotModel, q: np.ndarray, frame: str) -> pin.SE3:
    pm = model.to_pinocchio()
    pd = pm.createData()
    pin.framesForwardKinematics(pm, pd, q)
    return pd.oMf[pm.getFrameId(frame)]


def test_each_frame_task_logs_its_target_and_weights() -> None:
    model = armctl.models.panda()
    dyn = armctl.Dynamics(model)
    target = dyn.frame_pose(model.named_poses["ready"])
    pose = FramePoseTask(kp=100.0, weight=[1, 1, 0, 1, 1, 1])
    pose.set_target(target)
    hand = FramePositionTask("panda_link7", kp=50.0)
    hand.set_target((0.3, 0.0, 0.6))
    wrist = FrameOrientationTask("panda_link5", kp=50.0, weight=0.5)
    wrist.set_trajectory(lambda t: (pin.rpy.rpyToMatrix(0.0, 0.0, t), None, None))
    ctrl = OperationalSpaceQP(dyn, [pose, hand, wrist, PostureTask(7, kp=10.0, priority=1)])
    ctrl(0.25, Q, np.zeros(7), armctl.Reference(Q))
    log = ctrl.last_log
    np.testing.assert_array_equal(log["pose_target[pose[tool]|]"], target)
    np.testing.assert_array_equal(log["task_weight[pose[tool]]"], [1, 1, 0, 1, 1, 1])
    np.testing.assert_array_equal(log["position_target[position[panda_link7]|panda_link7]"], [0.3, 0.0, 0.6])
    np.testing.assert_allclose(
        log["orientation_target[orientation[panda_link5]|panda_link5]"], pin.rpy.rpyToMatrix(0.0, 0.0, 0.25)
    )
    assert not any("posture" in k for k in log)
    closed = ClosedFormOSC(dyn, pose, PostureTask(7, kp=10.0))
    closed(0.0, Q, np.zeros(7), armctl.Reference(Q))
    np.testing.assert_array_equal(closed.last_log["pose_target[pose[tool]|]"], target)


def test_the_errors_are_target_minus_pinocchio_s_pose_with_free_rows_and_missing_samples_nan() -> None:
    model = armctl.models.panda()
    rng = np.random.default_rng(2)
    q = model.named_poses["ready"] + rng.normal(0.0, 0.2, (6, 7))
    target = armctl.Dynamics(model).frame_pose(model.named_poses["ready"])
    logs = {
        "pose_target[press|]": np.repeat(target[None], 4, axis=0),
        "pose_target[press|]:sample": np.array([1, 2, 3, 5]),  # no target at samples 0 and 4
        "task_weight[press]": np.array([[1, 1, 0, 1, 1, 1]] * 3 + [[1.0] * 6]),
        "task_weight[press]:sample": np.array([1, 2, 3, 5]),
        "position_target[hand|panda_link7]": np.tile([0.3, 0.0, 0.6], (6, 1)),
        "position_target[elsewhere|no_such_frame]": np.zeros((6, 3)),  # not a frame of the plant: skipped
    }
    errors = task_errors(logs, model, q)
    assert set(errors) == {"position_error[press]", "orientation_error[press]", "position_error[hand]"}
    pos, rot = errors["position_error[press]"], errors["orientation_error[press]"]
    assert np.isnan(pos[[0, 4]]).all() and np.isnan(rot[[0, 4]]).all()
    for k in (1, 2, 3, 5):
        ref = _reference_pose(model, q[k], model.tool_frame)
        want = target[:3, 3] - ref.translation
        if k < 5:
            want[2] = np.nan  # free while its weight is 0
        np.testing.assert_allclose(pos[k], want, atol=1e-12)
        np.testing.assert_allclose(rot[k], pin.log3(target[:3, :3] @ ref.rotation.T), atol=1e-12)
    link7 = _reference_pose(model, q[3], "panda_link7")
    np.testing.assert_allclose(errors["position_error[hand]"][3], (0.3, 0.0, 0.6) - link7.translation, atol=1e-12)
    assert task_errors(logs) == {}  # without the plant: only errors the logs hold
