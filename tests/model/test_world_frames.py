"""Frames fixed to the world (parent joint 0) read from a URDF: a base link, the links merged into the world by
locking the first joint. References are Pinocchio's own full models of the same URDF files (parsed here, not
through armctl), evaluated with the locked joints at their lock positions."""

from __future__ import annotations

from functools import cache

import numpy as np
import pinocchio as pin
import pytest

import armctl
from armctl.errors import InvalidParameterError, ModelLoadError

BACKENDS = ("pinocchio", "lagrange")
PANDA = "panda_description/urdf/panda.urdf"
UR5 = "ur_description/urdf/ur5_robot.urdf"
FINGERS = {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0}
Q1 = 0.6  # lock position of panda_joint1


@cache
def _pinocchio(relative: str) -> pin.Model:
    return pin.buildModelFromUrdf(str(armctl.models.robot_description(relative)))


def _reference(relative: str, values: dict[str, float]) -> tuple[pin.Model, pin.Data]:
    """Pinocchio's full model of a URDF with the frame placements at the joint positions ``values``."""
    pm = _pinocchio(relative)
    q = pin.neutral(pm)
    for name, value in values.items():
        q[pm.idx_qs[pm.getJointId(name)]] = value
    data = pm.createData()
    pin.framesForwardKinematics(pm, data, q)
    pin.computeJointJacobians(pm, data, q)
    return pm, data


def _named_frames(pm: pin.Model) -> list[str]:
    """Pinocchio's frames that are not joint frames, the universe or the URDF's link called 'world'."""
    joints = set(pm.names)
    return sorted({f.name for f in pm.frames if f.name not in joints and f.name not in ("universe", "world")})


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("relative", [PANDA, UR5])
def test_every_urdf_frame_is_kept_at_pinocchios_pose(relative: str, backend: str) -> None:
    """Every link and fixed-joint frame of the URDF is a frame of the model, the world-attached ones (the
    Panda's panda_link0, the UR5's base_link and base) included, at Pinocchio's oMf; a world-attached frame
    has joint 0, its constant placement as pose and a zero Jacobian."""
    path = armctl.models.robot_description(relative)
    lock = FINGERS if relative == PANDA else {}
    model = armctl.RobotModel.from_urdf(path, lock=lock)
    dyn = armctl.Dynamics(model, backend=backend)
    pm = _pinocchio(relative)
    fixed = {f.name for f in pm.frames if f.parentJoint == 0} - {"universe", "world"}
    assert fixed >= ({"panda_link0"} if relative == PANDA else {"base_link", "base"})
    names = [*lock, *_named_frames(pm)]  # with the locked fingers' joint frames
    assert set(names) <= set(model.frame_names)
    assert model.frame_names.count("world") == 1
    rng = np.random.default_rng(11)
    for _ in range(3):
        q = rng.uniform(-1.5, 1.5, model.n)
        ref, data = _reference(relative, {**dict(zip(model.joint_names, q, strict=True)), **lock})
        for name in names:
            expected = data.oMf[ref.getFrameId(name)].homogeneous
            assert np.allclose(dyn.frame_pose(q, name), expected, rtol=0, atol=1e-12), name
        for name in fixed:
            assert model.frame(name).joint == 0
            assert np.allclose(dyn.frame_pose(q, name), model.frame(name).placement, rtol=0, atol=0)
            jac = dyn.jacobian(q, name)
            assert jac.shape == (6, model.n) and not jac.any(), name


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("route", ["from_urdf", "reduced"])
def test_locking_the_first_joint_keeps_its_frames(route: str, backend: str) -> None:
    """Panda with panda_joint1 locked at 0.6, by the URDF loader (Pinocchio's buildReducedModel) or by
    RobotModel.reduced: panda_link0, the locked joint's frame and panda_link1 are world-attached frames, and
    every frame's pose and Jacobian equal those of Pinocchio's full model at q1 = 0.6 (the Jacobian's columns
    of the six free joints)."""
    if route == "from_urdf":
        model = armctl.RobotModel.from_urdf(
            armctl.models.robot_description(PANDA), lock={"panda_joint1": Q1, **FINGERS}
        )
    else:
        model = armctl.models.panda().reduced(lock={"panda_joint1": Q1})
    assert model.joint_names == tuple(f"panda_joint{i}" for i in range(2, 8))
    for name in ("panda_link0", "panda_joint1", "panda_link1"):
        assert model.frame(name).joint == 0, name
    dyn = armctl.Dynamics(model, backend=backend)
    pm = _pinocchio(PANDA)
    names = ["panda_joint1", *FINGERS, *_named_frames(pm)]
    rng = np.random.default_rng(12)
    for _ in range(3):
        q = rng.uniform(-1.5, 1.5, model.n)
        ref, data = _reference(PANDA, {"panda_joint1": Q1, **dict(zip(model.joint_names, q, strict=True)), **FINGERS})
        cols = [ref.idx_vs[ref.getJointId(j)] for j in model.joint_names]
        for name in names:
            fid = ref.getFrameId(name)
            assert np.allclose(dyn.frame_pose(q, name), data.oMf[fid].homogeneous, rtol=0, atol=1e-12), name
            expected = pin.getFrameJacobian(ref, data, fid, pin.LOCAL_WORLD_ALIGNED)[:, cols]
            assert np.allclose(dyn.jacobian(q, name), expected, rtol=0, atol=1e-12), name


def test_both_lock_routes_give_the_same_frames() -> None:
    """The URDF loader's lock and RobotModel.reduced(lock=...) agree on every frame's joint and placement."""
    a = armctl.RobotModel.from_urdf(armctl.models.robot_description(PANDA), lock={"panda_joint1": Q1, **FINGERS})
    b = armctl.models.panda().reduced(lock={"panda_joint1": Q1})
    assert set(a.frame_names) == set(b.frame_names)
    for name in a.frame_names:
        fa, fb = a.frame(name), b.frame(name)
        assert fa.joint == fb.joint, name
        assert np.allclose(fa.placement, fb.placement, rtol=0, atol=1e-12), name


def test_payload_on_a_world_attached_frame_is_refused() -> None:
    with pytest.raises(InvalidParameterError, match=r"'panda_link0'.*fixed to the world"):
        armctl.models.panda().with_payload(1.0, frame="panda_link0")


_URDF = """<robot name="two">
  <link name="{root}"/>
  <joint name="mount" type="fixed"><parent link="{root}"/><child link="mount"/>
    <origin xyz="0.1 0.2 0.3" rpy="0.1 0.2 0.3"/></joint>
  <link name="mount"/>
  <joint name="j1" type="revolute"><parent link="mount"/><child link="l1"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <link name="l1"><inertial><mass value="1"/><origin xyz="0.1 0 0"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><axis xyz="0 1 0"/>
    <origin xyz="0.3 0 0"/><limit lower="-3" upper="3" effort="10" velocity="2"/></joint>
  <link name="l2"><inertial><mass value="1"/><origin xyz="0.1 0 0"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  {extra}
</robot>
"""


def _write(tmp_path: object, root: str, extra: str = "") -> str:
    import pathlib

    path = pathlib.Path(str(tmp_path)) / f"{root}.urdf"
    path.write_text(_URDF.format(root=root, extra=extra))
    return str(path)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_root_link_called_world_is_the_world_frame(tmp_path: object, backend: str) -> None:
    """A URDF root link named 'world' is the model's world frame; the fixed joint and the link of the same
    name ('mount', world-attached) give one frame, at Pinocchio's pose."""
    path = _write(tmp_path, "world")
    model = armctl.RobotModel.from_urdf(path)
    assert model.frame_names.count("world") == 1
    assert model.frame_names.count("mount") == 1 and model.frame("mount").joint == 0
    pm = pin.buildModelFromUrdf(path)
    data = pm.createData()
    pin.framesForwardKinematics(pm, data, np.array([0.4, -0.7]))
    dyn = armctl.Dynamics(model, backend=backend)
    assert [f.type for f in pm.frames if f.name == "mount"] == [pin.FrameType.FIXED_JOINT, pin.FrameType.BODY]
    for fid, f in enumerate(pm.frames):  # both 'mount' frames (they coincide) and the links
        if f.name in ("mount", "l1", "l2"):
            expected = data.oMf[fid].homogeneous
            assert np.allclose(dyn.frame_pose([0.4, -0.7], f.name), expected, rtol=0, atol=1e-12), f.name
    assert np.array_equal(dyn.frame_pose([0.4, -0.7], "world"), np.eye(4))
    assert not dyn.jacobian([0.4, -0.7], "mount").any()


@pytest.mark.parametrize(
    "extra",
    [
        '<joint name="w" type="fixed"><parent link="base"/><child link="world"/><origin xyz="0 0 1"/></joint>'
        '<link name="world"/>',  # fixed to the world, but not at its origin
        '<joint name="w" type="fixed"><parent link="l2"/><child link="world"/></joint><link name="world"/>',
    ],
)
def test_a_link_called_world_elsewhere_is_refused(tmp_path: object, extra: str) -> None:
    """'world' is the world frame: a link of that name that is not the world's origin is a load error."""
    with pytest.raises(ModelLoadError, match="'world' is reserved"):
        armctl.RobotModel.from_urdf(_write(tmp_path, "base", extra))
