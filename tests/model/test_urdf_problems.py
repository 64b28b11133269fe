"""URDF problems are named, and published data loads.

urdfdom (Pinocchio's URDF parser) reports what it cannot read on stderr only: an ``<inertial>`` it cannot parse
leaves its link massless, a link called ``universe`` is dropped from the frames, a ``<mimic>`` joint loads as an
independent joint, and duplicate names give only "does not contain a valid URDF model". Each raises a
ModelLoadError naming the link or joint. ``physical=False`` loads a published chain whose inertias violate the
triangle inequality (KDL's Motoman SIA10 test chain), checked against KDL's own published values.
"""

from __future__ import annotations

import pathlib

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import armctl
from armctl.errors import InvalidParameterError, ModelLoadError

_ARM = """<robot name="r">
  <link name="{root}"/>
  <link name="upper_arm"><inertial><origin xyz="0 0 0.1"/>{mass}
    <inertia ixx="{ixx}" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <link name="{fore}"><inertial><origin xyz="0 0 0.1"/><mass value="1.0"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="shoulder" type="revolute"><parent link="{root}"/><child link="upper_arm"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/></joint>
  <joint name="{elbow}" type="revolute"><parent link="{parent}"/><child link="{fore}"/><origin xyz="{origin}"/>
    <axis xyz="0 1 0"/>{limit}{mimic}</joint>
</robot>
"""
_GOOD = {
    "root": "base",
    "mass": '<mass value="2.0"/>',
    "ixx": "0.01",
    "fore": "forearm",
    "elbow": "elbow",
    "parent": "upper_arm",
    "origin": "0 0 0.3",
    "limit": '<limit lower="-1" upper="1" effort="10" velocity="1"/>',
    "mimic": "",
}


def _write(tmp_path: pathlib.Path, **changes: str) -> pathlib.Path:
    path = tmp_path / "arm.urdf"
    path.write_text(_ARM.format(**{**_GOOD, **changes}))
    return path


def test_the_well_formed_arm_loads(tmp_path: pathlib.Path) -> None:
    m = armctl.RobotModel.from_urdf(_write(tmp_path))
    assert m.joint_names == ("shoulder", "elbow")
    assert [j.link.mass for j in m.joints] == [2.0, 1.0]
    assert {"base", "upper_arm", "forearm"} <= set(m.frame_names)


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        # urdfdom alone loads the link massless ("Could not parse inertial element", on stderr)
        ({"mass": '<mass value="heavy"/>'}, r"link 'upper_arm': <mass value='heavy'> is not a finite number"),
        ({"mass": '<mass value="nan"/>'}, r"link 'upper_arm': <mass value='nan'> is not a finite number"),
        ({"mass": '<mass value=" 2.0 "/>'}, r"link 'upper_arm': <mass value=' 2.0 '> is not a finite number"),
        ({"mass": ""}, r"link 'upper_arm': its <inertial> has no <mass value=\"...\"/>"),
        ({"ixx": "nan"}, r"link 'upper_arm': <inertia ixx='nan'> is not a finite number"),
        ({"ixx": "1_000"}, r"link 'upper_arm': <inertia ixx='1_000'> is not a finite number"),
        # urdfdom alone drops it from the frames
        ({"root": "universe"}, r"link 'universe': 'universe' is Pinocchio's name for its world frame"),
        ({"fore": "universe"}, r"link 'universe': 'universe' is Pinocchio's name for its world frame"),
        # urdfdom alone says only "does not contain a valid URDF model"
        ({"elbow": "shoulder"}, r"joint name 'shoulder' is used by 2 joints: joint names must be unique"),
        ({"fore": "upper_arm"}, r"link name 'upper_arm' is used by 2 links: link names must be unique"),
        ({"origin": "0 0 abc"}, r"joint 'elbow': <origin xyz='0 0 abc'> is not three finite numbers"),
        ({"origin": "0 0"}, r"joint 'elbow': <origin xyz='0 0'> is not three finite numbers"),
        ({"limit": '<limit effort="10" velocity="fast"/>'}, r"joint 'elbow': <limit velocity='fast'> is not a finite"),
        ({"limit": ""}, r"joint 'elbow': a revolute joint needs <limit effort=\"...\" velocity=\"...\"/>"),
        ({"parent": "shoulder_link"}, r"joint 'elbow': its parent link 'shoulder_link' is not a link of the file"),
    ],
)
def test_urdf_problems_name_the_link_or_joint(tmp_path: pathlib.Path, changes: dict[str, str], match: str) -> None:
    with pytest.raises(ModelLoadError, match=r"^cannot read URDF '.*arm\.urdf': " + match):
        armctl.RobotModel.from_urdf(_write(tmp_path, **changes))


def test_every_problem_is_listed(tmp_path: pathlib.Path) -> None:
    path = _write(tmp_path, mass='<mass value="heavy"/>', elbow="shoulder")
    with pytest.raises(ModelLoadError) as info:
        armctl.RobotModel.from_urdf(path)
    assert "<mass value='heavy'> is not a finite number" in str(info.value)
    assert "joint name 'shoulder' is used by 2 joints" in str(info.value)


def test_xml_that_is_not_well_formed_is_named(tmp_path: pathlib.Path) -> None:
    path = tmp_path / "arm.urdf"
    path.write_text("<robot><link name='a'></robot>")
    with pytest.raises(
        ModelLoadError, match=r"^cannot read URDF '.*arm\.urdf': not well-formed XML \(mismatched tag: line 1"
    ):
        armctl.RobotModel.from_urdf(path)


def test_a_mimic_joint_is_refused_unless_locked(tmp_path: pathlib.Path) -> None:
    """A <mimic> joint would load as an independent joint: q_elbow free while the file says
    q_elbow = 2 q_shoulder. Refused by name; locked, it is held fixed and the model loads."""
    path = _write(tmp_path, mimic='<mimic joint="shoulder" multiplier="2" offset="0"/>')
    with pytest.raises(
        ModelLoadError,
        match=r"<mimic> joints are not supported \('elbow' follows 'shoulder'\).*Lock them \(lock=\['elbow'\]\)",
    ):
        armctl.RobotModel.from_urdf(path)
    m = armctl.RobotModel.from_urdf(path, lock={"elbow": 0.2})
    assert m.joint_names == ("shoulder",)


def test_the_panda_with_its_mimicking_finger_locked_loads() -> None:
    """panda.urdf's second finger mimics the first: locking both fingers (as the branch needs anyway) loads."""
    path = armctl.models.robot_description("panda_description/urdf/panda.urdf")
    with pytest.raises(ModelLoadError, match="only serial chains"):  # the fingers branch off the hand
        armctl.RobotModel.from_urdf(path)
    with pytest.raises(ModelLoadError, match=r"'panda_finger_joint2' follows 'panda_finger_joint1'"):
        armctl.RobotModel.from_urdf(path, lock=["panda_finger_joint1"])
    m = armctl.RobotModel.from_urdf(path, lock=["panda_finger_joint1", "panda_finger_joint2"])
    assert m.n == 7


# ---------------------------------------------------------------------------- KDL's Motoman SIA10 test chain
# orocos_kinematics_dynamics, orocos_kdl/tests/solvertest.cpp, chain "motomansia10dyn": seven RotZ segments with
# f_tip = Frame::DH(0, alpha, d, 0) and RigidBodyInertia(mass, com, RotationalInertia(Ixx, Iyy, Izz)) in the
# segment's tip frame, then a fixed segment to the tool (0, 0, 0.155); joint (motor) inertias 5, 5, 3, 3, 1, 1, 1.
_H = np.pi / 2
_SIA10_DH = [(_H, 0.36), (-_H, 0.0), (_H, 0.36), (-_H, 0.0), (_H, 0.36), (-_H, 0.0), (0.0, 0.0)]
_SIA10_BODIES = [
    (15.0, (0.0, -0.02, 0.0), (0.1, 0.05, 0.1)),
    (5.0, (0.0, -0.02, -0.1), (0.01, 0.1, 0.1)),
    (5.0, (0.0, -0.05, 0.02), (0.05, 0.01, 0.05)),
    (3.0, (0.0, 0.02, -0.15), (0.1, 0.1, 0.01)),
    (3.0, (0.0, -0.05, 0.01), (0.02, 0.01, 0.02)),
    (3.0, (0.0, -0.01, -0.1), (0.1, 0.1, 0.01)),
    (1.0, (0.0, 0.0, 0.05), (0.01, 0.01, 0.1)),  # 0.01 + 0.01 < 0.1: no rigid body has these moments
]
_SIA10_ARMATURE = np.diag([5.0, 5.0, 3.0, 3.0, 1.0, 1.0, 1.0])
# FdSolverDevelopmentTest: the state and KDL's values (3 decimals; H to 4)
_Q = np.array([0.2, 0.6, 1.0, 0.5, -1.4, 0.3, -0.8])
_QD = np.array([1.0, -2.0, 3.0, -4.0, 5.0, -6.0, 7.0])
_TOOL = [-0.547, -0.301, 0.924]
_GRAVITY = [0.000, -36.672, 4.315, -11.205, 0.757, 1.780, 0.000]
_CORIOLIS = [-15.523, 24.250, -6.862, 6.303, 0.110, -4.898, -0.249]
_H_KDL = [
    [6.8687, -0.4333, 0.4599, 0.6892, 0.0638, -0.0054, 0.0381],
    [-0.4333, 8.8324, -0.5922, 0.7905, 0.0003, -0.0242, 0.0265],
    [0.4599, -0.5922, 3.3496, -0.0253, 0.1150, -0.0243, 0.0814],
    [0.6892, 0.7905, -0.0253, 3.9623, -0.0201, 0.0087, -0.0291],
    [0.0638, 0.0003, 0.1150, -0.0201, 1.1234, 0.0029, 0.0955],
    [-0.0054, -0.0242, -0.0243, 0.0087, 0.0029, 1.1425, 0.0],
    [0.0381, 0.0265, 0.0814, -0.0291, 0.0955, 0.0, 1.1000],
]


def _sia10_urdf() -> str:
    """The chain as a URDF: link i's frame is segment i's frame after its joint; its body sits in the segment's
    tip frame f_tip = Tz(d) Rx(alpha), which the <inertial> origin expresses."""
    lines = ['<robot name="sia10">', '<link name="base"/>']
    parent, origin = "base", ("0 0 0", "0 0 0")
    for i, ((alpha, d), (mass, com, (ixx, iyy, izz))) in enumerate(zip(_SIA10_DH, _SIA10_BODIES, strict=True), 1):
        c = np.array([0.0, 0.0, d]) + Rotation.from_euler("x", alpha).as_matrix() @ np.array(com)
        lines.append(
            f'<link name="link{i}"><inertial><origin xyz="{" ".join(map(repr, c.tolist()))}" rpy="{alpha!r} 0 0"/>'
            f'<mass value="{mass}"/><inertia ixx="{ixx}" ixy="0" ixz="0" iyy="{iyy}" iyz="0" izz="{izz}"/>'
            "</inertial></link>"
        )
        lines.append(
            f'<joint name="joint{i}" type="revolute"><parent link="{parent}"/><child link="link{i}"/>'
            f'<origin xyz="{origin[0]}" rpy="{origin[1]}"/><axis xyz="0 0 1"/>'
            '<limit lower="-3.1" upper="3.1" effort="100" velocity="2"/></joint>'
        )
        parent, origin = f"link{i}", (f"0 0 {d!r}", f"{alpha!r} 0 0")
    lines += [
        '<link name="tool"/>',
        '<joint name="tool_joint" type="fixed"><parent link="link7"/><child link="tool"/>'
        '<origin xyz="0 0 0.155"/></joint>',
        "</robot>",
    ]
    return "\n".join(lines)


@pytest.fixture
def sia10(tmp_path: pathlib.Path) -> pathlib.Path:
    path = tmp_path / "sia10.urdf"
    path.write_text(_sia10_urdf())
    return path


def test_a_published_chain_outside_the_triangle_inequality_needs_physical_false(sia10: pathlib.Path) -> None:
    with pytest.raises(
        InvalidParameterError,
        match=r"joint 'joint7' \(links 'link7', 'tool'\): link inertia violates the triangle inequality .*"
        r"0\.01 \+ 0\.01 < 0\.1.*physical=False takes them",
    ):
        armctl.RobotModel.from_urdf(sia10)
    m = armctl.RobotModel.from_urdf(sia10, tool_frame="tool", physical=False)
    assert m.n == 7 and m.joints[6].link.physical is False and m.joints[0].link.physical is False
    with pytest.raises(InvalidParameterError, match="physical must be True or False"):
        armctl.RobotModel.from_urdf(sia10, physical="False")  # type: ignore[arg-type]


@pytest.mark.parametrize("backend", ["pinocchio", "lagrange"])
def test_the_sia10_chain_matches_kdls_published_dynamics(sia10: pathlib.Path, backend: str) -> None:
    """KDL's own values for this chain (its solver tests): tool position, gravity torques, Coriolis torques
    C(q, q̇) q̇ and the joint-space inertia H, which includes the joint (motor) inertias as an armature."""
    dyn = armctl.Dynamics(armctl.RobotModel.from_urdf(sia10, tool_frame="tool", physical=False), backend=backend)
    np.testing.assert_allclose(dyn.frame_pose(_Q, "tool")[:3, 3], _TOOL, rtol=0, atol=1e-3)
    np.testing.assert_allclose(dyn.gravity_torque(_Q), _GRAVITY, rtol=0, atol=1e-3)
    np.testing.assert_allclose(dyn.coriolis_matrix(_Q, _QD) @ _QD, _CORIOLIS, rtol=0, atol=1e-3)
    np.testing.assert_allclose(dyn.mass_matrix(_Q) + _SIA10_ARMATURE, _H_KDL, rtol=0, atol=1e-4)


def test_physical_false_reaches_a_locked_load(sia10: pathlib.Path) -> None:
    m = armctl.RobotModel.from_urdf(sia10, lock=["joint1"], physical=False)
    assert m.n == 6 and m.joints[-1].link.physical is False
