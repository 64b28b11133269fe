"""Named poses: every built-in arm has "ready" and "zero" within its joint limits, the variants keep them, and a
pose outside the limits or of the wrong size is refused by name."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.errors import InvalidParameterError, ShapeError
from armctl.model.robot import RobotModel

ARMS = ("pendulum", "planar_2r", "planar_3r", "puma560", "panda", "ur5")


@pytest.mark.parametrize("arm", ARMS)
def test_every_built_in_arm_has_ready_and_zero_within_its_limits(arm: str) -> None:
    model = getattr(armctl.models, arm)()
    poses = model.named_poses
    assert {"ready", "zero"} <= set(poses)
    for name, q in poses.items():
        assert q.shape == (model.n,) and not q.flags.writeable, name
        assert np.all(q >= model.lower) and np.all(q <= model.upper), name
    assert not np.allclose(poses["ready"], poses["zero"])


def test_the_panda_s_zero_stops_joint_4_at_its_limit_and_ready_points_the_hand_down() -> None:
    model = armctl.models.panda()
    zero = model.named_poses["zero"]
    assert zero[3] == model.upper[3] < 0.0 and not np.delete(zero, 3).any()
    for arm in (model, armctl.models.ur5()):
        pose = armctl.Dynamics(arm).frame_pose(arm.named_poses["ready"])
        np.testing.assert_allclose(pose[:3, 2], (0.0, 0.0, -1.0), atol=1e-6)  # the tool's z axis points down


def test_the_puma_s_poses_are_corke_s() -> None:
    poses = armctl.models.puma560().named_poses
    np.testing.assert_array_equal(poses["ready"], [0.0, np.pi / 2, -np.pi / 2, 0.0, 0.0, 0.0])
    np.testing.assert_array_equal(poses["nominal"], [0.0, np.pi / 4, -np.pi, 0.0, np.pi / 4, 0.0])


def test_variants_keep_the_poses_and_a_locked_joint_leaves_them() -> None:
    model = armctl.models.panda()
    heavy = model.with_payload(1.0, (0.0, 0.0, 0.05), np.eye(3) * 1e-3).with_friction(viscous=0.1)
    np.testing.assert_array_equal(heavy.named_poses["ready"], model.named_poses["ready"])
    locked = model.reduced(lock={"panda_joint7": 0.785})
    np.testing.assert_array_equal(locked.named_poses["ready"], model.named_poses["ready"][:6])


def test_a_model_of_one_s_own_gets_zero_and_bad_poses_are_named() -> None:
    joints = armctl.models.planar_2r().joints
    limited = tuple(
        j.__class__(**{**j.__dict__, "limits": armctl.model.JointLimits(-1.0, 1.0, effort=100.0, velocity=2.0)})
        for j in joints
    )
    own = RobotModel(limited, name="own")
    np.testing.assert_array_equal(own.named_poses["zero"], [0.0, 0.0])
    with pytest.raises(InvalidParameterError, match=r"named pose 'up' puts joint2 at 1\.5, outside its range"):
        RobotModel(limited, named_poses={"up": (0.0, 1.5)})
    with pytest.raises(ShapeError, match="named pose 'up' must have shape"):
        RobotModel(limited, named_poses={"up": (0.0, 0.5, 0.0)})
    with pytest.raises(InvalidParameterError, match="named_poses must be a mapping"):
        RobotModel(limited, named_poses=[(0.0, 0.5)])  # type: ignore[arg-type]


def test_poses_carried_to_narrower_limits_are_clipped_into_them() -> None:
    import dataclasses

    model = armctl.models.pendulum()  # ready: π/2, the joint has no range
    joint = model.joints[0]
    narrow = dataclasses.replace(joint, limits=dataclasses.replace(joint.limits, lower=-1.0, upper=1.0))
    clipped = dataclasses.replace(model, joints=(narrow,))
    np.testing.assert_array_equal(clipped.named_poses["ready"], [1.0])
    np.testing.assert_array_equal(clipped.named_poses["zero"], [0.0])
