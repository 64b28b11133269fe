"""`RobotModel.from_mjcf(..., lock=)`: joints held at given positions, as `from_urdf` does. A two-finger hand on a
small arm (the fingers are two branches, each with a slide joint) is refused without it and read with it; the
result is checked against MuJoCo itself on the full model with the held joints at their positions: the inertia
matrix of the free joints is the block of ``mj_fullM`` (held joints do not move), gravity the matching entries of
``qfrc_bias`` at rest, and a fingertip site is where MuJoCo puts it."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.errors import ModelLoadError, UnknownNameError

pytestmark = pytest.mark.mujoco

# a 3-joint arm carrying a hand with two fingers; the wrist hinge sits off its body's origin and has a ref, and
# the right finger's slide has a ref too, so that holding a joint at a position means the motion from qpos0
HAND = """
<mujoco model="two_finger_hand">
  <compiler angle="radian"/>
  <worldbody>
    <body name="upper" pos="0 0 0.3">
      <joint name="shoulder" type="hinge" axis="0 0 1" damping="0.2"/>
      <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.04" mass="2.0"/>
      <body name="fore" pos="0.4 0 0">
        <joint name="elbow" type="hinge" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1.2"/>
        <body name="hand" pos="0.3 0 0" quat="0.9238795 0 0.3826834 0">
          <joint name="wrist" type="hinge" axis="1 0 0" pos="0.02 0 0" ref="0.3"/>
          <geom type="box" size="0.03 0.06 0.02" pos="0.03 0 0" mass="0.5"/>
          <body name="finger_left" pos="0.07 0.02 0">
            <joint name="finger_left" type="slide" axis="0 1 0" range="0 0.04"/>
            <geom type="box" size="0.02 0.005 0.01" pos="0.02 0 0" mass="0.08"/>
            <site name="tip_left" pos="0.04 0 0"/>
          </body>
          <body name="finger_right" pos="0.07 -0.02 0">
            <joint name="finger_right" type="slide" axis="0 -1 0" range="0 0.04" ref="0.01"/>
            <geom type="box" size="0.02 0.005 0.01" pos="0.02 0 0" mass="0.08"/>
            <site name="tip_right" pos="0.04 0 0"/>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <!-- as in MuJoCo Menagerie's Panda: the fingers coupled by an equality, driven through a tendon -->
  <tendon>
    <fixed name="split">
      <joint joint="finger_left" coef="0.5"/>
      <joint joint="finger_right" coef="0.5"/>
    </fixed>
  </tendon>
  <equality>
    <joint joint1="finger_left" joint2="finger_right" polycoef="0 1 0 0 0"/>
  </equality>
  <actuator>
    <motor joint="shoulder" ctrllimited="true" ctrlrange="-30 30"/>
    <general tendon="split" forcerange="-100 100" ctrlrange="0 255" gainprm="0.01568" biasprm="0 -100 -10"/>
  </actuator>
</mujoco>
"""


@pytest.fixture(scope="module")
def mj():  # type: ignore[no-untyped-def]
    return pytest.importorskip("mujoco")


def _mujoco_at(mj, qpos: np.ndarray):  # type: ignore[no-untyped-def]
    """MuJoCo's full model at ``qpos`` (at rest): (M, bias, data)."""
    m = mj.MjModel.from_xml_string(HAND)
    d = mj.MjData(m)
    d.qpos[:] = qpos
    mj.mj_forward(m, d)
    full = np.zeros((m.nv, m.nv))
    mj.mj_fullM(m, d, full)
    return full, d.qfrc_bias.copy(), d, m


def test_a_hand_with_two_fingers_is_refused_without_lock_and_says_how(mj) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ModelLoadError, match=r"several bodies with joints .*lock="):
        armctl.RobotModel.from_mjcf(HAND)


@pytest.mark.parametrize("backend", ["pinocchio", "lagrange"])
def test_fingers_held_open_equal_mujoco(mj, backend: str) -> None:  # type: ignore[no-untyped-def]
    lock = {"finger_left": 0.03, "finger_right": 0.015}
    model = armctl.RobotModel.from_mjcf(HAND, lock=lock)
    assert model.joint_names == ("shoulder", "elbow", "wrist") and model.joints[0].friction.viscous == 0.2
    assert model.joints[0].limits.effort == 30.0  # the motor's, while the fingers' tendon actuator is left out
    dyn = armctl.Dynamics(model, backend=backend)
    rng = np.random.default_rng(5)
    for _ in range(5):
        q = rng.uniform(-2.0, 2.0, 3)
        full, bias, d, m = _mujoco_at(mj, np.concatenate([q, [lock["finger_left"], lock["finger_right"]]]))
        assert np.abs(dyn.mass_matrix(q) - full[:3, :3]).max() <= 1e-10
        assert np.abs(dyn.gravity_torque(q) - bias[:3]).max() <= 1e-10
        for site in ("tip_left", "tip_right"):
            s = mj.mj_name2id(m, mj.mjtObj.mjOBJ_SITE, site)
            pose = dyn.frame_pose(q, site)
            assert np.abs(pose[:3, 3] - d.site_xpos[s]).max() <= 1e-12
            assert np.abs(pose[:3, :3] - d.site_xmat[s].reshape(3, 3)).max() <= 1e-12


def test_a_hinge_held_off_its_ref_and_fingers_named_only(mj) -> None:  # type: ignore[no-untyped-def]
    """The wrist (a hinge off its body's origin, with a ref) held at 0.7 rad and the fingers given by name only
    (held at 0): two joints left, equal to MuJoCo's at that posture."""
    model = armctl.RobotModel.from_mjcf(HAND, lock={"wrist": 0.7, "finger_left": 0.0, "finger_right": 0.0})
    by_name = armctl.RobotModel.from_mjcf(HAND, lock=("finger_left", "finger_right"))
    assert model.joint_names == ("shoulder", "elbow") and by_name.n == 3
    dyn = armctl.Dynamics(model)
    q = np.array([0.4, -1.1])
    full, bias, d, m = _mujoco_at(mj, np.array([0.4, -1.1, 0.7, 0.0, 0.0]))
    assert np.abs(dyn.mass_matrix(q) - full[:2, :2]).max() <= 1e-10
    assert np.abs(dyn.gravity_torque(q) - bias[:2]).max() <= 1e-10
    s = mj.mj_name2id(m, mj.mjtObj.mjOBJ_SITE, "tip_right")
    assert np.abs(dyn.frame_pose(q, "tip_right")[:3, 3] - d.site_xpos[s]).max() <= 1e-12


def test_a_lock_naming_no_joint_is_refused_with_the_names(mj) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(UnknownNameError, match=r"finger_middle.*finger_left"):
        armctl.RobotModel.from_mjcf(HAND, lock={"finger_middle": 0.0})
