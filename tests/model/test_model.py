"""RobotModel: builders, variants, parameters, and the errors bad input gets."""

from __future__ import annotations

import ast
import math
import re

import numpy as np
import pytest

import armctl
from armctl.errors import (
    ArmctlError,
    InvalidParameterError,
    ModelLoadError,
    NonFiniteError,
    ShapeError,
    UnknownNameError,
)
from armctl.model import DHLink, Joint, JointFriction, Link, Motor
from armctl.model.consistency import is_physical, project_physical, projection
from tests.helpers.arms import dynamics, model


def test_builtin_sizes_and_tool_frames(model_name: str) -> None:
    m = model(model_name)
    expected = {"pendulum": 1, "planar_2r": 2, "planar_3r": 3, "puma560": 6, "panda": 7, "ur5": 6}[model_name]
    assert m.n == expected
    assert m.parameters().shape == (13 * m.n,)
    assert m.tool_frame in m.frame_names
    assert not m.parameters().flags.writeable


def test_parameters_layout() -> None:
    """π per joint: m, m·c, inertia about the joint origin (parallel axis), k_r² I_m, F_v, F_c."""
    link = Link(2.0, (0.1, 0.2, 0.3), np.diag([0.01, 0.02, 0.03]))
    joint = Joint("j", "revolute", (0, 0, 1), np.eye(4), link, Motor(1e-4, 10.0), JointFriction(0.5, 1.0, 3.0))
    pi = armctl.RobotModel((joint,)).parameters()
    c = np.array([0.1, 0.2, 0.3])
    i_o = np.diag([0.01, 0.02, 0.03]) + 2.0 * (c @ c * np.eye(3) - np.outer(c, c))
    assert pi[0] == 2.0
    assert np.allclose(pi[1:4], 2.0 * c)
    assert np.allclose(pi[4:10], [i_o[0, 0], i_o[0, 1], i_o[1, 1], i_o[0, 2], i_o[1, 2], i_o[2, 2]])
    assert pi[10] == pytest.approx(1e-2)
    assert pi[11] == 0.5
    assert pi[12] == 2.0  # mean of the asymmetric Coulomb levels 1 and 3


def test_standard_and_modified_dh_describe_the_same_arm() -> None:
    """A 3-link arm written in both conventions has the same dynamics and tool pose."""
    std = [
        DHLink(d=0.3, a=0.0, alpha=math.pi / 2, mass=2.0, com=(0, -0.1, 0), inertia=(0.02, 0.01, 0.02)),
        DHLink(a=0.5, mass=1.5, com=(-0.25, 0, 0), inertia=(0.001, 0.03, 0.03)),
        DHLink(a=0.4, mass=1.0, com=(-0.2, 0, 0), inertia=(0.001, 0.015, 0.015)),
    ]
    # modified: row i holds alpha_{i-1}, a_{i-1}, d_i; link bodies are given in frame {i} = joint frame i, which in
    # the standard convention is frame {i-1} · Rz(q): re-express each body there
    mdh = [
        DHLink(d=0.3, mass=2.0, com=(0, 0, 0.1), inertia=(0.02, 0.02, 0.01)),
        DHLink(alpha=math.pi / 2, mass=1.5, com=(0.25, 0, 0), inertia=(0.001, 0.03, 0.03)),
        DHLink(a=0.5, mass=1.0, com=(0.2, 0, 0), inertia=(0.001, 0.015, 0.015)),
    ]
    tool = np.eye(4)
    tool[0, 3] = 0.4
    a = armctl.Dynamics(armctl.RobotModel.from_dh(std, "standard"))
    b = armctl.Dynamics(armctl.RobotModel.from_dh(mdh, "modified", tool=tool))
    rng = np.random.default_rng(0)
    for _ in range(5):
        q, qd, qdd = rng.uniform(-2, 2, (3, 3))
        assert np.allclose(a.frame_pose(q), b.frame_pose(q), atol=1e-12)
        assert np.allclose(a.inverse_dynamics(q, qd, qdd), b.inverse_dynamics(q, qd, qdd), atol=1e-10)


@pytest.mark.parametrize("convention", ["standard", "modified"])
def test_dh_motor_axis_is_in_the_dh_frame_of_the_link_it_rides_on(convention: str) -> None:
    """A motor's explicit axis is read in DH frame {i−1} (the base frame {0} for joint 1). Joint i's axis
    there is z in the standard convention and Rx(α)z in the modified one (row i's α, Craig's α_{i−1}; z of
    {i−1} is joint i − 1's axis): given so, the model is the default-axis one, rotor coupling included. An x
    axis is rotated from {i−1} into joint i − 1's frame by row i − 1's Rz(θ_off)Rx(α) (standard) or not at
    all (modified: joint frame = {i−1})."""
    alphas, offsets = (math.pi / 2, -0.7, 0.0), (0.2, -0.4, 0.0)

    def rows(axes: list[tuple[float, ...] | None]) -> list[DHLink]:
        bodies = [
            dict(d=0.3, mass=2.0, com=(0, -0.1, 0), inertia=(0.02, 0.01, 0.02)),
            dict(a=0.5, mass=1.5, com=(-0.25, 0, 0), inertia=(0.001, 0.03, 0.03)),
            dict(a=0.4, mass=1.0, com=(-0.2, 0, 0), inertia=(0.001, 0.015, 0.015)),
        ]
        return [
            DHLink(alpha=al, offset=off, motor=Motor(inertia=2e-4, gear_ratio=-60.0, axis=ax), **body)
            for al, off, ax, body in zip(alphas, offsets, axes, bodies, strict=True)
        ]

    def rz_rx(theta: float, alpha: float) -> np.ndarray:
        c, s_, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
        return np.array([[c, -s_ * ca, s_ * sa], [s_, c * ca, -c * sa], [0.0, sa, ca]])

    base = np.eye(4)
    base[:3, :3] = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])  # a rotated base
    joint_axes = [(0.0, 0.0, 1.0) if convention == "standard" else tuple(rz_rx(0.0, al)[:, 2]) for al in alphas]
    default = armctl.RobotModel.from_dh(rows([None] * 3), convention, base=base)
    given = armctl.RobotModel.from_dh(rows(joint_axes), convention, base=base)
    for a, b in zip(default.joints, given.joints, strict=True):
        np.testing.assert_allclose(b.motor_axis, a.motor_axis, atol=1e-15)
    lag_a, lag_b = (armctl.Dynamics(m, backend="lagrange") for m in (default, given))
    q, qd, qdd = np.array([0.3, -0.8, 1.1]), np.array([1.0, -2.0, 0.5]), np.array([0.2, 0.1, -0.3])
    np.testing.assert_allclose(lag_b.inverse_dynamics(q, qd, qdd), lag_a.inverse_dynamics(q, qd, qdd), rtol=1e-13)
    x_axis = armctl.RobotModel.from_dh(rows([(1.0, 0.0, 0.0)] * 3), convention, base=base)
    np.testing.assert_allclose(x_axis.joints[0].motor_axis, base[:3, :3] @ [1.0, 0.0, 0.0], atol=1e-15)
    for i in (1, 2):  # rotor i + 1 rides on link i
        expected = rz_rx(offsets[i - 1], alphas[i - 1])[:, 0] if convention == "standard" else [1.0, 0.0, 0.0]
        np.testing.assert_allclose(x_axis.joints[i].motor_axis, expected, atol=1e-15)


def test_payload_adds_its_weight_through_the_jacobian() -> None:
    """A point payload of mass m at the tool adds J_vᵀ(−m g₀) to the gravity torque."""
    base = model("panda")
    heavy = base.with_payload(1.5)
    q = np.array([0.2, -0.4, 0.1, -1.8, 0.3, 1.6, 0.5])
    d0, d1 = dynamics("panda"), armctl.Dynamics(heavy)
    expected = d0.gravity_torque(q) + d0.jacobian(q)[:3].T @ (-1.5 * base.gravity)
    assert np.allclose(d1.gravity_torque(q), expected, atol=1e-10)
    assert base.parameters()[-13] != heavy.parameters()[-13]  # the model itself is unchanged
    assert heavy.n == base.n


@pytest.mark.parametrize("likely_inside", [True, False])
def test_projection_clips_negative_rotor_and_friction_alone(likely_inside: bool) -> None:
    """project_physical's docstring: rotor inertia and friction are clipped at 0. Links that are physical
    already keep their ten parameters (to rounding: the eigendecomposition is taken apart and put back), so
    the result is π with just the negative terms set to 0 (by hand), and projection() reports a change."""
    pi = model("planar_2r").parameters()
    assert is_physical(pi)
    bad, want = pi.copy(), pi.copy()
    bad[[11, 12, 23]] = -0.5, -0.2, -1e-3  # joint 1's F_v and F_c, joint 2's rotor inertia
    want[[11, 12, 23]] = 0.0
    assert not is_physical(bad)
    projected, changed = projection(bad, likely_inside=likely_inside)
    assert changed
    np.testing.assert_allclose(projected, want, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(project_physical(bad), want, rtol=1e-12, atol=1e-12)


def test_locked_joint_gives_the_submodel() -> None:
    """Locking joint 3 at 0.7: M, g of the reduced arm are the full model's with q3 = 0.7, q̇3 = 0."""
    full = model("puma560").reduced(friction=False)
    red = full.reduced(lock={"joint3": 0.7})
    assert red.n == 5 and "joint3" not in red.joint_names
    df, dr = armctl.Dynamics(full), armctl.Dynamics(red)
    keep = [0, 1, 3, 4, 5]
    rng = np.random.default_rng(1)
    for _ in range(3):
        qr, qdr, qddr = rng.uniform(-2, 2, (3, 5))
        q, qd, qdd = (np.insert(x, 2, v) for x, v in ((qr, 0.7), (qdr, 0.0), (qddr, 0.0)))
        assert np.allclose(dr.mass_matrix(qr), df.mass_matrix(q)[np.ix_(keep, keep)], atol=1e-10)
        assert np.allclose(dr.inverse_dynamics(qr, qdr, qddr), df.inverse_dynamics(q, qd, qdd)[keep], atol=1e-10)


def test_reduced_drops_rotors_and_friction_and_perturbed_scales() -> None:
    p = model("puma560")
    assert p.has_motors and p.has_friction
    r = p.reduced(rotors=False, friction=False)
    assert not r.has_motors and not r.has_friction
    pert = p.perturbed(mass=1.2, friction=0.5)
    assert np.allclose(pert.parameters()[0::13], p.parameters()[0::13] * 1.2)  # every link's mass
    assert pert.joints[0].friction.viscous == pytest.approx(0.5 * p.joints[0].friction.viscous)
    noisy = p.perturbed(noise=0.2, seed=3)
    assert np.array_equal(noisy.parameters(), p.perturbed(noise=0.2, seed=3).parameters())
    assert not np.allclose(noisy.parameters(), p.parameters())


def test_puma560_physical_variant() -> None:
    assert not model("puma560").joints[2].link.physical
    fixed = armctl.models.puma560(physical=True)
    assert all(j.link.physical for j in fixed.joints)
    # link 1's fix changes no torque
    q = np.array([0.3, 0.2, -0.5, 0.1, 0.4, 0.2])
    only1 = [j if i != 0 else fixed.joints[0] for i, j in enumerate(model("puma560").joints)]
    a = armctl.Dynamics(armctl.RobotModel(tuple(only1)))
    b = armctl.Dynamics(armctl.RobotModel(model("puma560").joints))
    assert np.allclose(a.inverse_dynamics(q, q, q), b.inverse_dynamics(q, q, q))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"mass": -1.0}, "mass"),
        ({"mass": 1.0, "inertia": (1.0, 1.0, -0.1)}, "positive semi-definite"),
        ({"mass": 1.0, "inertia": (0.1, 0.1, 0.5)}, "triangle inequality"),
        ({"mass": 1.0, "inertia": np.ones((2, 2))}, "3×3"),
        ({"mass": 1.0, "com": (0, 0)}, "3 components"),
    ],
)
def test_bad_link_raises_named_errors(kwargs: dict, match: str) -> None:
    with pytest.raises(ArmctlError, match=match):
        Link(**kwargs)


def test_bad_input_errors() -> None:
    dyn = dynamics("panda")
    with pytest.raises(ShapeError, match=r"qd must have shape \(7,\)"):
        dyn.inverse_dynamics(np.zeros(7), np.zeros(6), np.zeros(7))
    with pytest.raises(NonFiniteError, match="qdd"):
        dyn.inverse_dynamics(np.zeros(7), np.zeros(7), [0, 0, np.nan, 0, 0, 0, 0])
    with pytest.raises(NonFiniteError, match="q holds"):
        dyn.mass_matrix([np.inf] + [0.0] * 6)
    with pytest.raises(NonFiniteError, match="q holds"):
        dyn.mass_matrix([np.nan] + [0.0] * 6)  # M does not depend on q1: checked anyway
    with pytest.raises(UnknownNameError, match="panda_hand_tcp") as info:
        dyn.jacobian(np.zeros(7), frame="gripper")
    assert "gripper" in str(info.value) and isinstance(info.value, KeyError)
    with pytest.raises(ValueError, match="'lagrange'") as info:  # a bad argument value is a ValueError too
        armctl.Dynamics(model("panda"), backend="featherstone")
    assert isinstance(info.value, UnknownNameError) and isinstance(info.value, KeyError)
    assert str(info.value) == "unknown backend 'featherstone'; valid backends: 'pinocchio', 'lagrange'"
    with pytest.raises(ModelLoadError, match="not found"):
        armctl.RobotModel.from_urdf("/nonexistent/robot.urdf")
    with pytest.raises(ShapeError, match="wrench"):
        dyn.inverse_dynamics(np.zeros(7), np.zeros(7), np.zeros(7), wrench=np.zeros(3))
    with pytest.raises(InvalidParameterError, match="convention"):
        armctl.RobotModel.from_dh([DHLink(a=1.0, mass=1.0)], convention="craig")


def test_unreadable_urdf(tmp_path: object) -> None:
    import pathlib

    bad = pathlib.Path(str(tmp_path)) / "bad.urdf"
    bad.write_text("<robot name='x'><link name='a'/><joint name='j' type='revolute'>")
    with pytest.raises(ModelLoadError, match="cannot read URDF"):
        armctl.RobotModel.from_urdf(bad)


def test_urdf_lock_and_tool_frame_errors() -> None:
    path = armctl.models.robot_description("panda_description/urdf/panda.urdf")
    with pytest.raises(UnknownNameError, match="panda_joint1"):
        armctl.RobotModel.from_urdf(path, lock=("finger",))
    with pytest.raises(UnknownNameError, match="unknown frame"):
        armctl.RobotModel.from_urdf(path, tool_frame="nope", lock=("panda_finger_joint1", "panda_finger_joint2"))
    with pytest.raises(ModelLoadError, match="serial chains") as info:
        armctl.RobotModel.from_urdf(path)  # the two fingers branch off the hand
    # the message says what to lock, and doing so loads the 7-joint arm
    suggested = re.search(r"lock=(\[.*?\])", str(info.value))
    assert suggested is not None and suggested[1] == "['panda_finger_joint1', 'panda_finger_joint2']"
    assert armctl.RobotModel.from_urdf(path, lock=ast.literal_eval(suggested[1])).n == 7


def test_dynamics_pickles_by_rebuilding() -> None:
    import pickle

    for backend in ("pinocchio", "lagrange"):
        d = dynamics("planar_2r", backend)
        d2 = pickle.loads(pickle.dumps(d))
        q = np.array([0.3, -0.2])
        assert np.allclose(d2.mass_matrix(q), d.mass_matrix(q)) and d2.backend == backend


def test_repr_is_a_summary() -> None:
    text = repr(armctl.models.puma560())
    assert text.startswith("RobotModel('puma560': 6 joints RRRRRR, ") and "motors=True, friction=True" in text
    assert len(text) < 200  # not every array of every joint
    masses = sum(j.link.mass for j in armctl.models.planar_2r().joints)
    assert f"{masses:.4g} kg of links" in repr(armctl.models.planar_2r())
