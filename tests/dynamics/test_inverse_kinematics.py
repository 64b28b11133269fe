"""Inverse kinematics: round trips on random reachable poses of the Panda and the UR5 (targets from the library's
forward kinematics, answers checked with Pinocchio's own ``framesForwardKinematics``), position targets on the
planar arms, and the named error of an unreachable target."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import armctl
from armctl.errors import InfeasibleError, InvalidParameterError, InverseKinematicsError, ShapeError, UnknownNameError


def _pinocchio_pose(model: armctl.RobotModel, q: np.ndarray) -> pin.SE3:
    """The tool frame's pose by Pinocchio's own forward kinematics (the reference of these tests)."""
    pm = model.to_pinocchio()
    pd = pm.createData()
    pin.framesForwardKinematics(pm, pd, q)
    return pd.oMf[pm.getFrameId(model.tool_frame)]


@pytest.mark.parametrize("arm", ["panda", "ur5"])
def test_two_hundred_random_reachable_poses_round_trip(arm: str) -> None:
    model = getattr(armctl.models, arm)()
    dyn = armctl.Dynamics(model)
    pm = model.to_pinocchio()
    pd = pm.createData()
    fid = pm.getFrameId(model.tool_frame)
    rng = np.random.default_rng(7)
    worst_p = worst_r = 0.0
    for _ in range(200):
        q_true = rng.uniform(model.lower, model.upper)
        target = dyn.frame_pose(q_true)  # the library's forward kinematics: the input only
        q = dyn.inverse_kinematics(target)
        assert np.all(q >= model.lower) and np.all(q <= model.upper)
        pin.framesForwardKinematics(pm, pd, q)
        reached = pd.oMf[fid]
        worst_p = max(worst_p, float(np.linalg.norm(target[:3, 3] - reached.translation)))
        worst_r = max(worst_r, float(np.linalg.norm(pin.log3(target[:3, :3] @ reached.rotation.T))))
    assert worst_p < 1e-6 and worst_r < 1e-6


@pytest.mark.parametrize("arm", ["pendulum", "planar_2r", "planar_3r", "puma560"])
def test_position_targets_of_the_smaller_arms(arm: str) -> None:
    """A 4×4 target on an arm of fewer than 6 joints is solved for its position (the rotation left free); a
    position target is solved for the position on any arm."""
    model = getattr(armctl.models, arm)()
    dyn = armctl.Dynamics(model)
    rng = np.random.default_rng(3)
    lo, hi = np.maximum(model.lower, -np.pi), np.minimum(model.upper, np.pi)
    for _ in range(20):
        target = dyn.frame_pose(rng.uniform(lo, hi))
        q = dyn.inverse_kinematics(target if model.n < 6 else target[:3, 3])
        assert np.all(q >= model.lower) and np.all(q <= model.upper)
        reached = _pinocchio_pose(model, q).translation
        assert np.linalg.norm(target[:3, 3] - reached) < 1e-6


def test_a_planar_arm_reaches_a_pose_of_its_plane_when_asked_for_the_pose() -> None:
    model = armctl.models.planar_3r()
    dyn = armctl.Dynamics(model)
    target = dyn.frame_pose([0.3, -0.9, 0.4])
    q = dyn.inverse_kinematics(target, rows="pose", q0=[0.0, 0.0, 0.0])
    reached = _pinocchio_pose(model, q)
    assert np.linalg.norm(target[:3, 3] - reached.translation) < 1e-6
    assert np.linalg.norm(pin.log3(target[:3, :3] @ reached.rotation.T)) < 1e-6


def test_an_unreachable_target_raises_naming_the_residual() -> None:
    dyn = armctl.Dynamics(armctl.models.panda())
    far = np.eye(4)
    far[:3, 3] = (3.0, 0.0, 0.5)  # the Panda reaches about 0.9 m from its shoulder
    with pytest.raises(InverseKinematicsError, match=r"misses it by 2\.\d+ m in position") as caught:
        dyn.inverse_kinematics(far, restarts=2)
    err = caught.value
    assert isinstance(err, InfeasibleError) and err.residual.shape == (6,)
    assert 1.9 < np.linalg.norm(err.residual[:3]) < 2.6
    model = dyn.model
    assert np.all(err.q >= model.lower) and np.all(err.q <= model.upper)
    # the residual is the target's distance from what the returned q reaches
    reached = _pinocchio_pose(model, err.q).translation
    np.testing.assert_allclose(err.residual[:3], far[:3, 3] - reached, atol=1e-12)


def test_the_start_picks_the_solution_and_bad_input_is_named() -> None:
    model = armctl.models.ur5()
    dyn = armctl.Dynamics(model)
    q_true = np.array([0.4, -1.2, 1.1, -1.4, -1.5, 0.3])
    q = dyn.inverse_kinematics(dyn.frame_pose(q_true), q0=q_true + 0.05)
    np.testing.assert_allclose(q, q_true, atol=1e-8)
    with pytest.raises(ShapeError, match="4×4 pose or a position"):
        dyn.inverse_kinematics(np.zeros(6))
    with pytest.raises(UnknownNameError, match="unknown frame 'nosuch'"):
        dyn.inverse_kinematics(np.zeros(3), frame="nosuch")
    with pytest.raises(InvalidParameterError, match="rows='pose' needs a 4×4 target_pose"):
        dyn.inverse_kinematics(np.zeros(3), rows="pose")
    with pytest.raises(UnknownNameError, match=r"valid rows values: .pose., .position."):
        dyn.inverse_kinematics(np.eye(4), rows="orientation")
    bent = np.eye(4)
    bent[0, 0] = 2.0
    with pytest.raises(InvalidParameterError, match="homogeneous pose"):
        dyn.inverse_kinematics(bent)
    with pytest.raises(InvalidParameterError, match="tolerance"):
        dyn.inverse_kinematics(np.eye(4), tolerance=0.0)
