"""Bad input to the model's parts and variants raises a named armctl error when the part or variant is made.

* Not a raw TypeError, nor an AttributeError inside Dynamics later; text, booleans and None are not numbers.
* Model parameters that overflow are refused by name: a DH link of 1e308 kg, whose π would hold inf (m·c and the
  inertia about the joint origin overflow); a payload of 1e308 kg, whose weight is inf; a rotor of 1e200 kg·m²
  behind a 1e60 gear, whose reflected inertia is inf."""

from __future__ import annotations

import math
import pathlib
import re
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import armctl
from armctl.errors import ArmctlError, InvalidParameterError, NonFiniteError, ShapeError, UnknownNameError
from armctl.model import DHLink, Frame, Joint, JointFriction, JointLimits, Link, Motor
from armctl.model.consistency import from_pseudo_inertia, is_physical, projection, pseudo_inertia


def _2r() -> armctl.RobotModel:
    return armctl.models.planar_2r()


def _joint(**kwargs: Any) -> Joint:
    args: dict[str, Any] = {
        "name": "j",
        "kind": "revolute",
        "axis": (0, 0, 1),
        "placement": np.eye(4),
        "link": Link(1.0),
    }
    return Joint(**{**args, **kwargs})


# ------------------------------------------------------------------------------------------- friction (1)
@pytest.mark.parametrize("arg", ["viscous", "coulomb", "stribeck_velocity"])
def test_with_friction_refuses_none(arg: str) -> None:
    """viscous=None would give joints viscous=None (NaN in parameters(), a TypeError in friction_torque and
    friction silently dropped by inverse_dynamics); coulomb=None a TypeError inside Dynamics.__init__."""
    with pytest.raises(InvalidParameterError, match=rf"with_friction\(\): {arg} must hold real numbers, got None"):
        _2r().with_friction(**{arg: None})


@pytest.mark.parametrize(
    ("value", "error", "match"),
    [
        (math.nan, NonFiniteError, r"viscous holds NaN or inf: \[nan nan\]"),
        ([0.1, math.inf], NonFiniteError, r"viscous holds NaN or inf: \[0\.1 inf\]"),
        ("0.5", InvalidParameterError, r"viscous must hold real numbers, got '0\.5'"),
        (["0.5", "0.5"], InvalidParameterError, r"viscous must hold real numbers, got \['0\.5', '0\.5'\]"),
        (True, InvalidParameterError, r"viscous must be a real number, not a boolean, got True"),
        (np.array([True, False]), InvalidParameterError, r"viscous must be real numbers, not booleans"),
        ([0.5, -1.0], InvalidParameterError, r"viscous must be >= 0, got \[0\.5, -1\.0\]"),
    ],
)
def test_with_friction_checks_values_when_the_variant_is_made(value: object, error: type, match: str) -> None:
    with pytest.raises(error, match=match):
        _2r().with_friction(viscous=value)


def test_with_friction_valid_input_unchanged() -> None:
    m = _2r().with_friction(viscous=np.float32(0.5), coulomb=[1, 2], coulomb_negative=None, static=[3.0, 4.0])
    assert [j.friction.viscous for j in m.joints] == [0.5, 0.5]
    assert [j.friction.coulomb_neg for j in m.joints] == [1.0, 2.0]
    assert [j.friction.static for j in m.joints] == [3.0, 4.0]
    assert np.isfinite(m.parameters()).all()
    tau = armctl.Dynamics(m).inverse_dynamics(np.zeros(2), np.ones(2), np.zeros(2))
    tau0 = armctl.Dynamics(_2r()).inverse_dynamics(np.zeros(2), np.ones(2), np.zeros(2))
    assert np.allclose(tau - tau0, [1.5, 2.5])  # F_v q̇ + F_c for q̇ = 1


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"viscous": None}, InvalidParameterError, r"friction viscous must be a real number, got None"),
        ({"coulomb": "1"}, InvalidParameterError, r"friction coulomb must be a real number, got '1'"),
        ({"viscous": [1, 2]}, InvalidParameterError, r"friction viscous must be a real number, got \[1, 2\]"),
        ({"static": True}, InvalidParameterError, r"friction static must be a real number, not a boolean, got True"),
        ({"stribeck_velocity": math.nan}, NonFiniteError, r"friction stribeck_velocity must be finite, got nan"),
    ],
)
def test_joint_friction_checks_its_values(kwargs: dict, error: type, match: str) -> None:
    with pytest.raises(error, match=match):
        JointFriction(**kwargs)


# ------------------------------------------------------------------------------------------- parts (2, 5)
PART_CASES: list[tuple[str, Callable[[], object], type, str]] = [
    ("Link mass list", lambda: Link(mass=[1, 2]), InvalidParameterError, r"link mass \[kg\] .*got \[1, 2\]"),
    ("Link mass None", lambda: Link(None), InvalidParameterError, r"link mass \[kg\] must be a real number, got None"),
    ("Link mass complex", lambda: Link(1j), InvalidParameterError, r"link mass \[kg\] must be a real number, got 1j"),
    ("Link mass text", lambda: Link(mass="1"), InvalidParameterError, r"link mass \[kg\] .*got '1'"),
    ("Link mass bool", lambda: Link(True), InvalidParameterError, r"link mass \[kg\] .*not a boolean, got True"),
    ("Link mass nan", lambda: Link(math.nan), NonFiniteError, r"link mass \[kg\] must be finite, got nan"),
    ("Link com text", lambda: Link(1.0, ["1", "2", "3"]), InvalidParameterError, r"link com .*\['1', '2', '3'\]"),
    (
        "Link com bools",
        lambda: Link(1.0, [True, False, True]),
        InvalidParameterError,
        r"link com must be real numbers, not booleans, got \[True, False, True\]",
    ),
    ("Link inertia text", lambda: Link(1.0, inertia="abc"), InvalidParameterError, r"link inertia .*'abc'"),
    (
        "Link inertia bools",
        lambda: Link(1.0, inertia=[True] * 3),
        InvalidParameterError,
        r"link inertia must be real numbers, not booleans",
    ),
    (
        "Link physical text",
        lambda: Link(1.0, physical="no"),
        InvalidParameterError,
        r"link physical must be True or False, got 'no'",
    ),
    (
        "payload text",
        lambda: _2r().with_payload("2"),
        InvalidParameterError,
        r"payload mass \[kg\] must be a real number, got '2'",
    ),
    ("payload bool", lambda: _2r().with_payload(True), InvalidParameterError, r"payload mass .*got True"),
    (
        "payload com bools",
        lambda: _2r().with_payload(1.0, com=[True] * 3),
        InvalidParameterError,
        r"payload com must be real numbers, not booleans",
    ),
    (
        "payload inertia text",
        lambda: _2r().with_payload(1.0, inertia="abc"),
        InvalidParameterError,
        r"payload inertia must hold real numbers, got 'abc'",
    ),
    ("Motor inertia text", lambda: Motor("1e-4"), InvalidParameterError, r"rotor inertia .*got '1e-4'"),
    (
        "Motor gear None",
        lambda: Motor(1e-4, None),
        InvalidParameterError,
        r"gear ratio must be a real number, got None",
    ),
    (
        "Motor axis bools",
        lambda: Motor(axis=[True, False, False]),
        InvalidParameterError,
        r"motor axis must be real numbers, not booleans",
    ),
    ("JointLimits text", lambda: JointLimits("0", "1"), InvalidParameterError, r"joint lower limit .*got '0'"),
    ("JointLimits None", lambda: JointLimits(None), InvalidParameterError, r"joint lower limit .*got None"),
    ("JointLimits bool", lambda: JointLimits(0.0, True), InvalidParameterError, r"joint upper limit .*got True"),
    ("JointLimits nan", lambda: JointLimits(math.nan), NonFiniteError, r"joint lower limit is NaN"),
    (
        "DHLink motor",
        lambda: DHLink(motor=5),
        InvalidParameterError,
        r"DH link motor must be an armctl.model.Motor or None, got 5 \(int\)",
    ),
    (
        "DHLink limits",
        lambda: DHLink(limits=(0, 1)),
        InvalidParameterError,
        r"DH link limits .*must be an armctl.model.JointLimits, got \(0, 1\) \(tuple\)",
    ),
    (
        "DHLink friction",
        lambda: DHLink(friction=0.5),
        InvalidParameterError,
        r"DH link friction .*must be an armctl.model.JointFriction, got 0.5",
    ),
    ("DHLink d text", lambda: DHLink(d="0.3"), InvalidParameterError, r"DH parameter d .*got '0.3'"),
    ("DHLink a None", lambda: DHLink(a=None), InvalidParameterError, r"DH parameter a .*got None"),
    ("DHLink alpha bool", lambda: DHLink(alpha=True), InvalidParameterError, r"DH parameter alpha .*got True"),
    ("DHLink mass text", lambda: DHLink(mass="1"), InvalidParameterError, r"link mass \[kg\] .*got '1'"),
    ("DHLink com", lambda: DHLink(com=(0, 0)), ShapeError, r"link com must have 3 components"),
    ("DHLink name", lambda: DHLink(name=5), InvalidParameterError, r"DH link name must be a str, got 5"),
    (
        "DH row",
        lambda: armctl.RobotModel.from_dh([5]),
        InvalidParameterError,
        r"DH row 0 must be a DHLink or a dict of its arguments, got 5",
    ),
    ("DH row key", lambda: armctl.RobotModel.from_dh([{"mas": 1.0}]), InvalidParameterError, r"DH row 0: .*'mas'"),
    (
        "DH table text",
        lambda: armctl.RobotModel.from_dh("ab"),
        InvalidParameterError,
        r"a DH table must be a sequence .*got 'ab'",
    ),
    (
        "DH gravity text",
        lambda: armctl.RobotModel.from_dh([DHLink(a=1.0)], gravity=["0", "0", "-9.81"]),
        InvalidParameterError,
        r"gravity .*must hold real numbers, got \['0', '0', '-9.81'\]",
    ),
    (
        "DH tool bools",
        lambda: armctl.RobotModel.from_dh([DHLink(a=1.0)], tool=np.eye(4, dtype=bool)),
        InvalidParameterError,
        r"tool must be real numbers, not booleans",
    ),
    (
        "Joint link",
        lambda: _joint(link=5),
        InvalidParameterError,
        r"joint 'j' link must be an armctl.model.Link, got 5 \(int\)",
    ),
    ("Joint motor", lambda: _joint(motor=5), InvalidParameterError, r"joint 'j' motor must be an armctl.model.Motor"),
    (
        "Joint friction",
        lambda: _joint(friction=None),
        InvalidParameterError,
        r"joint 'j' friction .*must be an armctl.model.JointFriction, got None",
    ),
    (
        "Joint limits",
        lambda: _joint(limits=(0, 1)),
        InvalidParameterError,
        r"joint 'j' limits .*must be an armctl.model.JointLimits, got \(0, 1\)",
    ),
    ("Joint name", lambda: _joint(name=5), InvalidParameterError, r"joint name must be a str, got 5"),
    ("Joint axis text", lambda: _joint(axis=["0", "0", "1"]), InvalidParameterError, r"joint 'j' axis .*'1'\]"),
    (
        "Joint axis bools",
        lambda: _joint(axis=[False, False, True]),
        InvalidParameterError,
        r"joint 'j' axis must be real numbers, not booleans",
    ),
    (
        "Joint placement bools",
        lambda: _joint(placement=np.eye(4, dtype=bool)),
        InvalidParameterError,
        r"joint 'j' placement must be real numbers, not booleans",
    ),
    (
        "Frame joint fraction",
        lambda: Frame("f", 1.5, None),
        InvalidParameterError,
        r"frame 'f' joint index must be a whole number >= 0, got 1.5",
    ),
    ("Frame joint bool", lambda: Frame("f", True, None), InvalidParameterError, r"frame 'f' joint index .*got True"),
    ("Frame name", lambda: Frame(5, 1, None), InvalidParameterError, r"frame name must be a str, got 5"),
    (
        "model frames",
        lambda: armctl.RobotModel(_2r().joints, frames=[5]),
        InvalidParameterError,
        r"frames must be armctl.model.Frame objects, got 5",
    ),
    ("model joints", lambda: armctl.RobotModel(5), InvalidParameterError, r"joints must be a sequence .*got 5"),
    (
        "model name",
        lambda: armctl.RobotModel(_2r().joints, name=5),
        InvalidParameterError,
        r"model name must be a str, got 5",
    ),
    (
        "model gravity bools",
        lambda: armctl.RobotModel(_2r().joints, gravity=[False, False, True]),
        InvalidParameterError,
        r"gravity must be real numbers, not booleans",
    ),
    (
        "perturbed seed -1.0",
        lambda: _2r().perturbed(noise=0.1, seed=-1.0),
        InvalidParameterError,
        r"perturbed\(\): seed must be a whole number >= 0, got -1.0",
    ),
    (
        "perturbed seed 1.5",
        lambda: _2r().perturbed(noise=0.1, seed=1.5),
        InvalidParameterError,
        r"perturbed\(\): seed must be a whole number >= 0, got 1.5",
    ),
    (
        "perturbed factor bool",
        lambda: _2r().perturbed(mass=True),
        InvalidParameterError,
        r"perturbed\(\): mass must be finite and >= 0 .*got True",
    ),
    (
        "reduced rotors text",
        lambda: _2r().reduced(rotors="no"),
        InvalidParameterError,
        r"reduced\(\): rotors must be True or False, got 'no'",
    ),
    (
        "reduced lock bool",
        lambda: _2r().reduced(lock={"joint1": True}),
        InvalidParameterError,
        r"lock position of joint 'joint1' must be a real number, not a boolean, got True",
    ),
    ("reduced lock int", lambda: _2r().reduced(lock=5), InvalidParameterError, r"lock must be a joint name.*got 5"),
    (
        "with_parameters bools",
        lambda: _2r().with_parameters(_2r().parameters() > 0),
        InvalidParameterError,
        r"pi must be real numbers, not booleans",
    ),
    (
        "with_parameters offset bools",
        lambda: _2r().with_parameters(_2r().parameters(), coulomb_offset=[False] * 2),
        InvalidParameterError,
        r"coulomb_offset must be real numbers, not booleans",
    ),
    (
        "with_parameters physical",
        lambda: _2r().with_parameters(_2r().parameters(), physical="yes"),
        InvalidParameterError,
        r"physical must be True or False, got 'yes'",
    ),
    (
        "puma560 physical",
        lambda: armctl.models.puma560(physical="yes"),
        InvalidParameterError,
        r"puma560\(\): physical must be True or False, got 'yes'",
    ),
    (
        "pseudo_inertia bools",
        lambda: pseudo_inertia(np.ones(10, dtype=bool)),
        InvalidParameterError,
        r"link parameters must be real numbers, not booleans",
    ),
    (
        "from_pseudo_inertia text",
        lambda: from_pseudo_inertia([["1"] * 4] * 4),
        InvalidParameterError,
        r"pseudo-inertias must hold real numbers",
    ),
    ("is_physical text", lambda: is_physical(["1"] * 13), InvalidParameterError, r"pi must hold real numbers"),
    (
        "projection bools",
        lambda: projection(np.ones(13, dtype=bool)),
        InvalidParameterError,
        r"pi must be real numbers, not booleans",
    ),
]


@pytest.mark.parametrize(("make", "error", "match"), [c[1:] for c in PART_CASES], ids=[c[0] for c in PART_CASES])
def test_bad_parts_raise_named_errors_when_made(make: Callable[[], object], error: type, match: str) -> None:
    with pytest.raises(error, match=match) as info:
        make()
    assert isinstance(info.value, ArmctlError)


def test_valid_parts_unchanged() -> None:
    """Numbers of any real type are taken and stored as floats (ints for a frame's joint); ±inf is no limit."""
    assert Link(np.float32(2.0)).mass == 2.0 and type(Link(2).mass) is float
    assert Frame("f", 1.0, None).joint == 1 and type(Frame("f", np.int64(2), None).joint) is int
    lim = JointLimits(-np.inf, np.float64(1.0))
    assert lim.lower == -math.inf and lim.velocity == math.inf and lim.upper == 1.0
    row = DHLink(d=1, mass=np.int64(2), com=[0, 0, 0.1], inertia=(0.1, 0.1, 0.1), physical=np.bool_(True))
    assert row.d == 1.0 and row.mass == 2.0 and row.com.shape == (3,) and row.inertia.shape == (3, 3)
    assert row.physical is True
    caller = np.array([0.0, 0.0, 0.1])
    Link(1.0, caller)
    assert caller.flags.writeable  # the part's read-only copy is its own
    m = _2r()
    assert np.array_equal(
        m.perturbed(noise=0.1, seed=np.int64(3)).parameters(), m.perturbed(noise=0.1, seed=3.0).parameters()
    )
    assert m.reduced(lock=None).n == 2 and m.reduced(rotors=np.bool_(False)).has_motors is False


@pytest.mark.parametrize(
    "moments", [(1.0, 1.0, 3.0), (0.1, 0.2, 0.45), (0.5, 1.0, 1.6), (1.0, 2.0, 3.0), (2.0, 2.0, 3.0)]
)
def test_link_takes_the_moments_of_some_mass_distribution_only(moments: tuple[float, float, float]) -> None:
    """Principal moments a mass distribution can have: Σ = ½ tr(I) 1 − I = ∫ r rᵀ dm positive semi-definite
    (computed here; I₁ + I₂ ≥ I₃, a flat plate (1, 2, 3) on the edge). Link (a rotated, full tensor) refuses
    the others by the triangle inequality; physical=False takes them."""
    r = Rotation.from_rotvec([0.4, -0.9, 0.3]).as_matrix()
    inertia = r @ np.diag(moments) @ r.T
    sigma = 0.5 * np.trace(inertia) * np.eye(3) - inertia
    if np.linalg.eigvalsh(sigma).min() >= -1e-12:
        np.testing.assert_allclose(Link(1.0, inertia=inertia).inertia, inertia, rtol=0, atol=1e-15)
    else:
        with pytest.raises(InvalidParameterError, match="triangle inequality"):
            Link(1.0, inertia=inertia)
        assert Link(1.0, inertia=inertia, physical=False).physical is False


# ------------------------------------------------------------------------------------------------- URDF (3)
def _ur5() -> pathlib.Path:
    return armctl.models.robot_description("ur_description/urdf/ur5_robot.urdf")


def test_urdf_lock_takes_one_name() -> None:
    """lock="shoulder_pan_joint" is one name, not letters to iterate ("unknown joint 's'")."""
    m = armctl.RobotModel.from_urdf(_ur5(), lock="shoulder_pan_joint")
    assert m.joint_names == ("shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint")
    assert "shoulder_pan_joint" in m.frame_names


@pytest.mark.parametrize(
    ("value", "error", "match"),
    [
        (math.nan, NonFiniteError, r"lock position of joint 'shoulder_pan_joint' must be finite, got nan"),
        ("0.5", InvalidParameterError, r"lock position of joint 'shoulder_pan_joint' must be a real number, got '0.5'"),
        (True, InvalidParameterError, r"lock position of joint 'shoulder_pan_joint' .*not a boolean, got True"),
    ],
)
def test_urdf_lock_positions_are_checked(value: object, error: type, match: str) -> None:
    with pytest.raises(error, match=match):
        armctl.RobotModel.from_urdf(_ur5(), lock={"shoulder_pan_joint": value})


def test_urdf_lock_unknown_name_and_path_type() -> None:
    with pytest.raises(UnknownNameError, match=r"unknown joint 'elbow'; valid joints: 'shoulder_pan_joint'"):
        armctl.RobotModel.from_urdf(_ur5(), lock="elbow")
    with pytest.raises(InvalidParameterError, match=r"URDF path must be a str or a path, got 5"):
        armctl.RobotModel.from_urdf(5)  # type: ignore[arg-type]


_URDF = """<robot name="r">
  <link name="base"/>
  <link name="upper_arm"><inertial><origin xyz="0 0 0.1"/><mass value="{mass}"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <link name="forearm"><inertial><origin xyz="0 0 0.1"/><mass value="1.0"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper_arm"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/></joint>
  <joint name="elbow" type="revolute"><parent link="upper_arm"/><child link="forearm"/><origin xyz="0 0 0.3"/>
    <axis xyz="0 1 0"/><limit lower="{lower}" upper="{upper}" effort="10" velocity="1"/></joint>
</robot>
"""


@pytest.mark.parametrize(
    ("values", "match"),
    [
        (
            {"mass": -1.0, "lower": -1, "upper": 1},
            r"joint 'shoulder' \(link 'upper_arm'\): link mass \[kg\] must be >= 0",
        ),
        (
            {"mass": 1.0, "lower": 1, "upper": -1},
            r"joint 'elbow' \(link 'forearm'\): joint lower limit 1.0 is above upper",
        ),
    ],
)
def test_urdf_errors_name_the_joint_and_link(tmp_path: pathlib.Path, values: dict, match: str) -> None:
    path = tmp_path / "arm.urdf"
    path.write_text(_URDF.format(**values))
    with pytest.raises(InvalidParameterError, match=r"arm\.urdf: " + match):
        armctl.RobotModel.from_urdf(path)
    ok = tmp_path / "ok.urdf"
    ok.write_text(_URDF.format(mass=1.0, lower=-1, upper=1))
    assert armctl.RobotModel.from_urdf(ok).joint_names == ("shoulder", "elbow")


# ------------------------------------------------------------------------------------- rotor_coupling (4)
@pytest.mark.parametrize("value", ["False", 0, 1, None, [True]])
def test_rotor_coupling_must_be_a_real_boolean(value: object) -> None:
    """rotor_coupling="False" must not turn the coupling on (bool("False") is True)."""
    m = armctl.models.pendulum()
    shown = re.escape(repr(value))
    with pytest.raises(InvalidParameterError, match=f"rotor_coupling must be True or False, got {shown}"):
        armctl.Dynamics(m, backend="lagrange", rotor_coupling=value)
    with pytest.raises(InvalidParameterError, match="rotor_coupling must be True or False"):
        armctl.dynamics.lagrange.LagrangeDynamics.is_compiled_cached(m, rotor_coupling=value)


def test_rotor_coupling_takes_numpy_booleans() -> None:
    d = armctl.Dynamics(armctl.models.pendulum(), backend="lagrange", rotor_coupling=np.bool_(False))
    assert d.rotor_coupling is False and d.options["rotor_coupling"] is False


@pytest.mark.parametrize("value", ["False", 0, None])
def test_compile_must_be_a_real_boolean(value: object) -> None:
    """compile="False" must not compile (bool("False") is True); refused before the symbolic build."""
    with pytest.raises(InvalidParameterError, match=rf"compile must be True .*'auto'.*, got {re.escape(repr(value))}"):
        armctl.Dynamics(armctl.models.pendulum(), backend="lagrange", compile=value)


def test_a_dh_link_whose_parameters_overflow_is_refused() -> None:
    links = [DHLink(a=0.5, mass=1.0), DHLink(a=2.0, mass=1e308, name="forearm")]
    with pytest.raises(
        InvalidParameterError,
        match=r"^DH row 1 \(forearm\), its body in the joint frame: link mass 1e\+308 kg with com \[2\.0, 0\.0, 0\.0\]"
        r" m overflows its parameters \(first moment m·c = \[inf",
    ):
        armctl.RobotModel.from_dh(links)


def test_a_link_whose_moments_overflow_is_refused() -> None:
    """m·c = 1e260 is finite, the inertia about the joint origin m|c|² = 1e320 is not."""
    with pytest.raises(
        InvalidParameterError, match=r"^link mass 1e\+200 kg with com \[1e\+60, 0\.0, 0\.0\] m overflows its parameters"
    ):
        Link(1e200, com=(1e60, 0.0, 0.0))


def test_a_rotor_whose_reflected_inertia_overflows_is_refused() -> None:
    with pytest.raises(InvalidParameterError, match=r"^rotor inertia 1e\+200 kg·m² and gear ratio 1e\+60 overflow"):
        Motor(1e200, 1e60)


def test_a_model_whose_weight_overflows_is_refused() -> None:
    """π of a 1e308 kg payload is finite, but the payload's weight is not: every gravity torque would be inf."""
    arm = armctl.models.planar_2r()
    assert np.isfinite(arm.parameters()).all()
    with pytest.raises(
        InvalidParameterError,
        match=r"^joint 'joint2': its link \(1e\+308 kg, centre of mass up to .* m from the joint axes\) overflows the "
        r"dynamics: gravity torques up to inf N·m",
    ):
        arm.with_payload(1e308)


def test_large_finite_models_still_build_and_evaluate() -> None:
    """The bounds refuse only what overflows: a 1e150 kg link builds, and its dynamics are finite and match the
    closed form of a point mass on a rod, M = m a² (about z, gravity along −z: no weight torque)."""
    m = armctl.RobotModel.from_dh([DHLink(a=2.0, mass=1e150)])
    assert np.isfinite(m.parameters()).all()
    dyn = armctl.Dynamics(m)
    np.testing.assert_allclose(dyn.mass_matrix([0.3]), [[1e150 * 2.0**2]], rtol=1e-12)
    assert Link(1e300, com=(1.0, 0.0, 0.0)).mass == 1e300
