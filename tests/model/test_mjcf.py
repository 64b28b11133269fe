"""MJCF in and out: `RobotModel.from_mjcf` against MuJoCo itself (an engine nobody here wrote: its joint-space
inertia matrix ``mj_fullM`` and its bias force ``qfrc_bias`` at rest), against the numbers written in the XML and
closed-form masses, and the `to_mjcf` → `from_mjcf` round trip."""

from __future__ import annotations

import math
import sys
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import armctl
from armctl.errors import InvalidParameterError, ModelLoadError, OptionalDependencyError, UnknownNameError
from tests.helpers.mjcf_arms import SLIDE_AND_STACKED, SPATIAL_ARM, SPATIAL_JOINTS

pytestmark = pytest.mark.mujoco


@pytest.fixture(scope="module")
def mj():  # type: ignore[no-untyped-def]
    return pytest.importorskip("mujoco")


def mujoco_terms(mj, m, d, q):  # type: ignore[no-untyped-def]
    """(M, g) of MuJoCo at q: mj_fullM, and qfrc_bias with q̇ = 0 (only gravity left in it)."""
    d.qpos[:] = q
    d.qvel[:] = 0.0
    mj.mj_forward(m, d)
    full = np.zeros((m.nv, m.nv))
    mj.mj_fullM(m, d, full)
    return full, d.qfrc_bias.copy()


def positions(n: int) -> st.SearchStrategy[np.ndarray]:
    return st.lists(st.floats(-3.0, 3.0, allow_nan=False), min_size=n, max_size=n).map(np.asarray)


@pytest.mark.parametrize("backend", ["pinocchio", "lagrange"])
@pytest.mark.parametrize("xml", [SPATIAL_ARM, SLIDE_AND_STACKED], ids=["spatial_arm", "slide_and_stacked"])
def test_mass_matrix_and_gravity_equal_mujoco(mj, xml: str, backend: str) -> None:  # type: ignore[no-untyped-def]
    model = armctl.RobotModel.from_mjcf(xml)
    dyn = armctl.Dynamics(model, backend=backend)
    m = mj.MjModel.from_xml_string(xml)
    d = mj.MjData(m)

    @settings(max_examples=40, deadline=None)
    @given(q=positions(model.n))
    def check(q: np.ndarray) -> None:
        full, bias = mujoco_terms(mj, m, d, q)
        assert np.abs(dyn.mass_matrix(q) - full).max() <= 1e-10
        assert np.abs(dyn.gravity_torque(q) - bias).max() <= 1e-10
        for s in range(m.nsite):  # the sites are frames at the same places
            name = mj.mj_id2name(m, mj.mjtObj.mjOBJ_SITE, s)
            pose = dyn.frame_pose(q, name)
            assert np.abs(pose[:3, 3] - d.site_xpos[s]).max() <= 1e-12
            assert np.abs(pose[:3, :3] - d.site_xmat[s].reshape(3, 3)).max() <= 1e-12
        for b in range(1, m.nbody):
            name = mj.mj_id2name(m, mj.mjtObj.mjOBJ_BODY, b)
            if name in model.frame_names and name not in model.joint_names:
                assert np.abs(dyn.frame_pose(q, name)[:3, 3] - d.xpos[b]).max() <= 1e-12

    check()


def test_friction_armature_limits_and_frames_are_read(mj) -> None:  # type: ignore[no-untyped-def]
    model = armctl.RobotModel.from_mjcf(SPATIAL_ARM, tool_frame="tool")
    assert model.joint_names == tuple(SPATIAL_JOINTS)
    for joint, (damping, armature, frictionloss) in zip(model.joints, SPATIAL_JOINTS.values(), strict=True):
        assert joint.kind == "revolute"
        assert joint.friction.viscous == damping and joint.friction.coulomb == frictionloss
        assert joint.motor is not None and not joint.motor.gyroscopic
        assert joint.motor.gear_ratio == 1.0 and joint.motor.reflected_inertia == armature
    assert model.lower.tolist() == [-2.5, -2.0, -math.inf] and model.upper.tolist() == [2.5, 2.0, math.inf]
    # 50 × 1.2 (motor gear × forcerange), 2 × min(30, 25) (asymmetric forcerange), 8 (ctrlrange of a motor)
    assert model.effort_limit.tolist() == [60.0, 50.0, 8.0]
    assert {"base", "upper", "fore", "distal", "hand", "tool"} <= set(model.frame_names)
    assert model.tool_frame == "tool" and model.frame("base").joint == 0
    assert model.gravity.tolist() == [0.0, 0.0, -9.81]
    zero_g = SPATIAL_ARM.replace('gravity="0 0 -9.81"', 'gravity="0.5 0 -3"')
    assert armctl.RobotModel.from_mjcf(zero_g).gravity.tolist() == [0.5, 0.0, -3.0]


def _quat_matrix(w: float, x: float, y: float, z: float) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    return Rotation.from_quat([x, y, z, w]).as_matrix()  # (scipy normalises)


def test_link_inertias_as_written(mj) -> None:  # type: ignore[no-untyped-def]
    """fullinertia as written (the joint frame is the body's); diaginertia turned by its quat and shifted by the
    joint's pos; the last link's mass from the geoms' volumes × densities (closed forms)."""
    upper, fore, distal = (j.link for j in armctl.RobotModel.from_mjcf(SPATIAL_ARM).joints)
    assert upper.mass == 2.0
    assert np.abs(upper.com - [0.01, 0.02, 0.05]).max() <= 1e-15
    written = np.array([[0.02, 0.001, -0.002], [0.001, 0.025, 0.0015], [-0.002, 0.0015, 0.015]])
    assert np.abs(upper.inertia - written).max() <= 1e-15
    r = _quat_matrix(0.9, 0.1, 0.2, 0.1)
    assert np.abs(fore.com - [0.2, 0.01, -0.02]).max() <= 1e-15  # joint at pos z = 0.02 of its body
    assert np.abs(fore.inertia - r @ np.diag([0.004, 0.03, 0.031]) @ r.T).max() <= 1e-15
    capsule = 900 * (math.pi * 0.025**2 * 0.23 + 4 / 3 * math.pi * 0.025**3)
    box = 2000 * 0.04 * 0.06 * 0.03
    sphere = 1000 * 4 / 3 * math.pi * 0.02**3
    assert distal.mass == pytest.approx(capsule + box + sphere, rel=1e-12)


def test_wrist_ref_is_folded_into_its_placement(mj) -> None:  # type: ignore[no-untyped-def]
    """armctl's q is MuJoCo's qpos: at qpos = qpos0 = ref the arm is where the XML draws it."""
    model = armctl.RobotModel.from_mjcf(SPATIAL_ARM)
    m = mj.MjModel.from_xml_string(SPATIAL_ARM)
    assert m.qpos0.tolist() == [0.0, 0.0, 0.2]
    d = mj.MjData(m)
    mj.mj_forward(m, d)
    tool = armctl.Dynamics(model).frame_pose(m.qpos0, "tool")
    assert np.abs(tool[:3, 3] - d.site_xpos[0]).max() <= 1e-12


@pytest.mark.parametrize(
    "make",
    [
        lambda: armctl.RobotModel.from_mjcf(SPATIAL_ARM, tool_frame="tool"),
        lambda: armctl.RobotModel.from_mjcf(SLIDE_AND_STACKED),
        armctl.models.planar_2r,  # zero principal moments: MuJoCo's bound raises them to 1e-12
        armctl.models.panda,  # meshes of its URDF
        armctl.models.ur5,
        lambda: armctl.models.puma560(physical=True),  # asymmetric Coulomb friction: written as the mean
    ],
    ids=["spatial_arm", "slide_and_stacked", "planar_2r", "panda", "ur5", "puma560"],
)
def test_to_mjcf_round_trip(mj, make) -> None:  # type: ignore[no-untyped-def]
    model = make()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        xml = model.to_mjcf()
    asymmetric = any(j.friction.coulomb != j.friction.coulomb_neg for j in model.joints)
    assert any("one Coulomb level" in str(w.message) for w in caught) == asymmetric
    back = armctl.RobotModel.from_mjcf(xml, tool_frame=model.tool_frame)
    assert back.joint_names == model.joint_names and back.name == model.name
    assert set(model.frame_names) <= set(back.frame_names)
    assert np.array_equal(back.gravity, model.gravity)
    for a, b in zip(model.joints, back.joints, strict=True):
        assert a.kind == b.kind
        assert np.abs(a.axis - b.axis).max() <= 1e-15
        assert np.abs(a.placement - b.placement).max() <= 1e-14
        assert b.link.mass == pytest.approx(a.link.mass, abs=2e-12)
        assert np.abs(a.link.inertia - b.link.inertia).max() <= 1e-11
        if a.link.mass > 1e-9:
            assert np.abs(a.link.com - b.link.com).max() <= 1e-12
        assert b.friction.viscous == a.friction.viscous
        assert b.friction.coulomb == pytest.approx(a.friction.coulomb_mean, rel=1e-15)
        rotor = a.motor.reflected_inertia if a.motor is not None else 0.0
        assert (b.motor.reflected_inertia if b.motor is not None else 0.0) == pytest.approx(rotor, rel=1e-15)
        assert (b.limits.lower, b.limits.upper) == (a.limits.lower, a.limits.upper)
        assert b.limits.effort == a.limits.effort
    for f in model.frames:
        g = back.frame(f.name)
        assert g.joint == f.joint and np.abs(g.placement - f.placement).max() <= 1e-14
    # and MuJoCo's own terms of the exported arm are armctl's
    m = mj.MjModel.from_xml_string(xml)
    d = mj.MjData(m)
    dyn = armctl.Dynamics(model)
    rng = np.random.default_rng(3)
    for _ in range(10):
        q = rng.uniform(-2.0, 2.0, model.n)
        full, bias = mujoco_terms(mj, m, d, q)
        scale = max(1.0, float(np.abs(full).max()))
        assert np.abs(dyn.mass_matrix(q) - full).max() <= 1e-10 * scale
        assert np.abs(dyn.gravity_torque(q) - bias).max() <= 1e-10 * max(1.0, float(np.abs(bias).max()))


def test_to_mjcf_meshes(mj) -> None:  # type: ignore[no-untyped-def]
    """The Panda's collision meshes (STL) come along from its URDF, each on the link of its name; without a mesh
    source the links are capsules."""
    import xml.etree.ElementTree as ET

    panda = armctl.models.panda()
    root = ET.fromstring(panda.to_mjcf())
    files = [el.get("file") for el in root.iter("mesh")]
    assert len(files) >= 9 and all(f.endswith(".stl") for f in files)
    m = mj.MjModel.from_xml_string(panda.to_mjcf())
    assert m.nmesh == len(files)
    hand = [m.geom_bodyid[g] for g in range(m.ngeom) if m.geom_type[g] == mj.mjtGeom.mjGEOM_MESH]
    assert m.body("panda_joint7").id in hand  # hand and fingers ride on the last joint
    plain = ET.fromstring(panda.to_mjcf(meshes=False))
    assert not list(plain.iter("mesh")) and len(list(plain.iter("geom"))) == panda.n
    assert all(g.get("contype") == "1" and g.get("conaffinity") == "0" for g in plain.iter("geom"))


@pytest.mark.parametrize(
    ("xml", "error", "words"),
    [
        ('<body name="b"><freejoint name="root"/><geom size="0.1"/></body>', ModelLoadError, "'root' is a free joint"),
        ('<body name="b"><joint name="ball" type="ball"/><geom size="0.1"/></body>', ModelLoadError, "ball joint"),
        (
            '<body name="b"><joint name="s" stiffness="3"/><geom size="0.1"/></body>',
            ModelLoadError,
            "spring (stiffness=3)",
        ),
        (
            '<body name="a"><joint name="j1"/><geom size="0.1"/><body name="l"><joint name="j2"/><geom size="0.1"/>'
            '</body><body name="r"><joint name="j3"/><geom size="0.1"/></body></body>',
            ModelLoadError,
            "carries several bodies with joints ('l', 'r')",
        ),
        (
            '<body name="a"><joint name="j1"/><geom size="0.1"/></body><body name="c"><joint name="j2"/>'
            '<geom size="0.1"/></body>',
            ModelLoadError,
            "give base=",
        ),
        ('<body name="a"><geom size="0.1"/></body>', ModelLoadError, "no hinge or slide joint"),
    ],
    ids=["free", "ball", "spring", "branches", "two_arms", "no_joint"],
)
def test_what_a_robot_model_cannot_hold_is_refused_by_name(mj, xml: str, error: type, words: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(error, match=re_escape(words)):
        armctl.RobotModel.from_mjcf(f"<mujoco><worldbody>{xml}</worldbody></mujoco>")


def re_escape(text: str) -> str:
    import re

    return re.escape(text)


def test_base_selects_one_arm_of_a_scene(mj) -> None:  # type: ignore[no-untyped-def]
    two = (
        '<mujoco><worldbody><body name="a"><joint name="j1"/><geom size="0.1"/></body>'
        '<body name="c" pos="1 0 0"><freejoint name="box"/><geom size="0.1"/></body></worldbody></mujoco>'
    )
    model = armctl.RobotModel.from_mjcf(two, base="a")
    assert model.joint_names == ("j1",)
    with pytest.raises(UnknownNameError, match="unknown body 'nope'"):
        armctl.RobotModel.from_mjcf(two, base="nope")
    with pytest.raises(ModelLoadError, match="carried by the joints of body 'upper'"):
        armctl.RobotModel.from_mjcf(SPATIAL_ARM, base="fore")


def test_bad_sources(mj, tmp_path) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ModelLoadError, match="MJCF file not found"):
        armctl.RobotModel.from_mjcf(tmp_path / "none.xml")
    with pytest.raises(ModelLoadError, match="cannot read the MJCF text"):
        armctl.RobotModel.from_mjcf("<mujoco><worldbody><body></mujoco>")
    with pytest.raises(InvalidParameterError, match="got int"):
        armctl.RobotModel.from_mjcf(5)
    path = tmp_path / "arm.xml"
    path.write_text(SPATIAL_ARM)
    model = armctl.RobotModel.from_mjcf(path)
    assert model.source == str(path) and model.name == "spatial3"
    assert armctl.RobotModel.from_mjcf(mj.MjSpec.from_string(SPATIAL_ARM)).n == 3


def test_non_rigid_inertia_is_refused_by_to_mjcf() -> None:
    with pytest.raises(InvalidParameterError, match=r"link of joint 'joint1'.*puma560\(physical=True\)"):
        armctl.models.puma560().to_mjcf()


def test_missing_mujoco_is_a_clear_error(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "mujoco", None)  # `import mujoco` now raises ImportError
    with pytest.raises(OptionalDependencyError, match=re_escape('pip install "armctl[mujoco]"')) as info:
        armctl.RobotModel.from_mjcf(SPATIAL_ARM)
    assert isinstance(info.value, ImportError) and "RobotModel.from_mjcf needs MuJoCo" in str(info.value)
    assert "<mujoco" in armctl.models.planar_3r().to_mjcf()  # writing MJCF needs no MuJoCo
