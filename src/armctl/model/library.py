"""Built-in arms, each with the model it needs and no more (reached as :mod:`armctl.models`).

==================  ==========================================================================================
``pendulum()``      one link in a vertical plane driven through a gear by a motor: rotor inertia, gear ratio,
                    viscous friction (the textbook single-joint example).
``planar_2r()``     two-link elbow arm in a vertical plane with geared motors (Siciliano et al., *Robotics*,
                    §7.3.2 example: a = 1 m, m_l = 50 kg, I_l = 10 kg·m², k_r = 100, I_m = 0.01 kg·m², m_m = 5 kg).
``planar_3r()``     three uniform rods in a vertical plane, no motors.
``puma560()``       Corke's standard Puma 560 parameter set (DH, link inertias, motors, friction; joint side).
``panda()``         Franka Panda from the URDF of the example-robot-data package, fingers locked (7 joints).
``ur5()``           UR5 from the URDF of the example-robot-data package.
==================  ==========================================================================================

The planar arms turn about the world axis −y, so q = 0 points a link along +x and a positive angle lifts it
towards +z; gravity is −z.
"""

from __future__ import annotations

import math
from dataclasses import replace
from functools import cache
from pathlib import Path

import numpy as np

from armctl._checks import FloatArray, boolean
from armctl.errors import ModelLoadError
from armctl.model.dh import DHLink
from armctl.model.parts import Frame, Joint, JointFriction, JointLimits, Link, Motor, transform
from armctl.model.robot import RobotModel

_PLANE_AXIS = (0.0, -1.0, 0.0)


def _poses(**poses: tuple[float, ...]) -> dict[str, FloatArray]:
    """Named poses as the arrays a model holds (checked against the joint limits by the model)."""
    return {name: np.array(q, dtype=float) for name, q in poses.items()}


def _rod(mass: float, length: float) -> Link:
    """A uniform slender rod along +x from the joint: centre at L/2, I = mL²/12 about transverse axes."""
    i = mass * length**2 / 12.0
    return Link(mass, (length / 2, 0.0, 0.0), np.diag([0.0, i, i]))


def pendulum() -> RobotModel:
    """A 0.5 m, 2 kg rod hanging from a horizontal axis (world −y), driven through a 50:1 gear by a motor
    with rotor inertia 5·10⁻⁵ kg·m² (reflected: 0.125 kg·m²), viscous friction 0.05 N·m·s/rad.
    q = 0 hangs straight down; the gravity torque is m g ℓ sin q.

    Returns
    -------
    RobotModel
    """
    length, mass = 0.5, 2.0
    i = mass * length**2 / 12.0
    link = Link(mass, (0.0, 0.0, -length / 2), np.diag([i, i, 0.0]))
    joint = Joint(
        "joint1",
        "revolute",
        _PLANE_AXIS,
        np.eye(4),
        link,
        Motor(5e-5, 50.0),
        JointFriction(viscous=0.05),
        JointLimits(effort=20.0, velocity=10.0),
    )
    tip = Frame("tool", 1, transform(None, (0.0, 0.0, -length)))
    poses = {"ready": (math.pi / 2,), "zero": (0.0,)}
    return RobotModel((joint,), name="pendulum", frames=(tip,), tool_frame="tool", named_poses=poses)


def planar_2r() -> RobotModel:
    """Siciliano's two-link arm (§7.3.2): link 1 is augmented with motor 2 (5 kg at the elbow, rotor
    inertia 0.01 kg·m² about its spin axis); each motor has k_r = 100, I_m = 0.01 kg·m².

    Returns
    -------
    RobotModel
    """
    a, m_l, i_l, m_m, i_m, k_r = 1.0, 50.0, 10.0, 5.0, 0.01, 100.0

    def link() -> Link:  # centre of mass at ℓ = a/2, I_l about the plane normal, a slender body otherwise
        return Link(m_l, (a / 2, 0.0, 0.0), np.diag([0.0, i_l, i_l]))

    motor2_body = Link(m_m, (a, 0.0, 0.0), np.diag([i_m / 2, i_m, i_m / 2]))
    limits = JointLimits(effort=5000.0, velocity=5.0)
    j1 = Joint(
        "joint1", "revolute", _PLANE_AXIS, np.eye(4), link().combined(motor2_body), Motor(i_m, k_r), limits=limits
    )
    j2 = Joint(
        "joint2", "revolute", _PLANE_AXIS, transform(None, (a, 0.0, 0.0)), link(), Motor(i_m, k_r), limits=limits
    )
    return RobotModel(
        (j1, j2),
        name="planar_2r",
        frames=(Frame("tool", 2, transform(None, (a, 0, 0))),),
        tool_frame="tool",
        named_poses={"ready": (math.pi / 4, -math.pi / 2), "zero": (0.0, 0.0)},
    )


def planar_3r() -> RobotModel:
    """Three uniform rods (0.5, 0.4, 0.3 m; 4, 3, 2 kg) in a vertical plane, no motors, no friction.

    Returns
    -------
    RobotModel
    """
    lengths, masses = (0.5, 0.4, 0.3), (4.0, 3.0, 2.0)
    joints = []
    offset = 0.0
    for k, (length, mass) in enumerate(zip(lengths, masses, strict=True)):
        joints.append(
            Joint(
                f"joint{k + 1}",
                "revolute",
                _PLANE_AXIS,
                transform(None, (offset, 0.0, 0.0)),
                _rod(mass, length),
                limits=JointLimits(effort=200.0, velocity=5.0),
            )
        )
        offset = length
    tool = Frame("tool", 3, transform(None, (lengths[-1], 0.0, 0.0)))
    poses = {"ready": (math.pi / 4, -math.pi / 2, math.pi / 4), "zero": (0.0, 0.0, 0.0)}
    return RobotModel(tuple(joints), name="planar_3r", frames=(tool,), tool_frame="tool", named_poses=poses)


# Corke's Puma 560 (Robotics Toolbox, mdl_puma560): per link d, a, alpha, m, r (COM in the link frame),
# I = (Ixx, Iyy, Izz, Ixy, Iyz, Ixz) about the COM, Jm, G, B (motor side), Tc = (Tc+, Tc-) (motor side),
# qlim [deg]. Source: Robotics Toolbox for MATLAB, models/mdl_puma560.m (Corke & Armstrong-Helouvry 1994;
# limits after Wang & Chen 1991); no pedestal (the Python toolbox adds 26.45 in to d1).
# As published, links 1 and 3 violate the triangle inequality of principal moments (see puma560()).
# fmt: off
_PUMA = (
    (0.0, 0.0, math.pi / 2, 0.0, (0, 0, 0), (0, 0.35, 0, 0, 0, 0), 200e-6, -62.6111, 1.48e-3,
     (0.395, -0.435), (-160, 160)),
    (0.0, 0.4318, 0.0, 17.4, (-0.3638, 0.006, 0.2275), (0.13, 0.524, 0.539, 0, 0, 0), 200e-6, 107.815,
     0.817e-3, (0.126, -0.071), (-45, 225)),
    (0.15005, 0.0203, -math.pi / 2, 4.8, (-0.0203, -0.0141, 0.070), (0.066, 0.086, 0.0125, 0, 0, 0), 200e-6,
     -53.7063, 1.38e-3, (0.132, -0.105), (-225, 45)),
    (0.4318, 0.0, math.pi / 2, 0.82, (0, 0.019, 0), (1.8e-3, 1.3e-3, 1.8e-3, 0, 0, 0), 33e-6, 76.0364,
     71.2e-6, (11.2e-3, -16.9e-3), (-110, 170)),
    (0.0, 0.0, -math.pi / 2, 0.34, (0, 0, 0), (0.3e-3, 0.4e-3, 0.3e-3, 0, 0, 0), 33e-6, 71.923, 82.6e-6,
     (9.26e-3, -14.5e-3), (-100, 100)),
    (0.0, 0.0, 0.0, 0.09, (0, 0, 0.032), (0.15e-3, 0.15e-3, 0.04e-3, 0, 0, 0), 33e-6, 76.686, 36.7e-6,
     (3.96e-3, -10.5e-3), (-266, 266)),
)
# fmt: on


PUMA_QZ = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)  #: zero angles, L-shaped pose
PUMA_QR = (0.0, math.pi / 2, -math.pi / 2, 0.0, 0.0, 0.0)  #: ready pose, arm up
#: nominal non-singular pose. Corke's toolbox gives q3 = +π, outside joint 3's range [−225°, 45°]; −π is the
#: same pose, inside it (a controller that keeps the limits would throw the arm around from +π)
PUMA_QN = (0.0, math.pi / 4, -math.pi, 0.0, math.pi / 4, 0.0)


def puma560(physical: bool = False) -> RobotModel:
    """Corke's standard Puma 560: standard DH, link masses/COMs/inertias, motors (J_m, G) and motor-side
    viscous B and asymmetric Coulomb T_c, referred to the joint side as the toolbox does: reflected inertia G²J_m,
    F_v = G²B, F_c⁺ = |G|·T_c⁺, F_c⁻ = |G|·|T_c⁻|. Joint 1's link has no mass (the toolbox gives only its inertia
    about the vertical axis, I_yy = 0.35 kg·m² in link frame 1). Named poses: :data:`PUMA_QZ`, :data:`PUMA_QR`,
    :data:`PUMA_QN`.

    Parameters
    ----------
    physical : bool, optional
        As published, two inertia tensors are not those of a rigid body: link 1's (0, 0.35, 0) and link 3's
        (0.066, 0.086, 0.0125), whose principal moments violate the triangle inequality. False (the default) keeps
        the published numbers (links marked ``physical=False``), so results compare with the toolbox's; True makes
        the smallest change that fixes them: link 1 I_xx = I_zz = 0.175 (no torque depends on them, link 1 only
        turns about y1) and link 3 I_zz = 0.020 (from 0.0125).

    Returns
    -------
    RobotModel
    """
    physical = boolean(physical, "puma560(): physical")
    rows: list[DHLink] = []
    for d, a, alpha, m, r, inert, jm, g, b, tc, qlim in _PUMA:
        ixx, iyy, izz, ixy, iyz, ixz = inert
        k = len(rows)
        if physical and k == 0:
            ixx = izz = 0.175
        if physical and k == 2:
            izz = 0.020
        tensor = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]], dtype=float)
        rows.append(
            DHLink(
                d=d,
                a=a,
                alpha=alpha,
                mass=m,
                com=r,
                inertia=tensor,
                motor=Motor(jm, g),
                friction=JointFriction(viscous=b * g * g, coulomb=abs(g) * tc[0], coulomb_negative=abs(g) * abs(tc[1])),
                limits=JointLimits(math.radians(qlim[0]), math.radians(qlim[1])),
                name=f"joint{k + 1}",
                physical=physical or k not in (0, 2),
            )
        )
    model = RobotModel.from_dh(rows, convention="standard", name="puma560")
    return replace(model, named_poses=_poses(ready=PUMA_QR, zero=PUMA_QZ, nominal=PUMA_QN))


@cache
def _robots_dir() -> Path:
    from importlib.metadata import PackageNotFoundError, distribution

    try:
        dist = distribution("example-robot-data")
    except PackageNotFoundError:
        raise ModelLoadError(
            "the example-robot-data package is not installed: pip install example-robot-data",
            value="example-robot-data",
        ) from None
    for rel in ("cmeel.prefix/share/example-robot-data/robots", "share/example-robot-data/robots"):
        path = Path(str(dist.locate_file(rel)))
        if path.is_dir():
            return path
    raise ModelLoadError(
        "example-robot-data is installed but its robots folder was not found", value=str(dist.locate_file(""))
    )


def robot_description(relative: str) -> Path:
    """Path of a file shipped by the example-robot-data package.

    Parameters
    ----------
    relative : str
        Its path in the package's ``robots`` folder, e.g. ``'panda_description/urdf/panda.urdf'``.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ModelLoadError
        The package or the file is not there.
    """
    path = _robots_dir() / relative
    if not path.is_file():
        raise ModelLoadError(f"{relative!r} is not in example-robot-data ({_robots_dir()})", value=relative)
    return path


#: the Panda's ready pose (Franka's own "ready"): hand pointing down in front of the base
PANDA_QR = (0.0, -math.pi / 4, 0.0, -3 * math.pi / 4, 0.0, math.pi / 2, math.pi / 4)
#: the UR5's ready pose: elbow up, tool pointing down in front of the base
UR5_QR = (0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0)
#: the UR5 straight up (a singular configuration: wrist and shoulder aligned)
UR5_QU = (0.0, -math.pi / 2, 0.0, -math.pi / 2, 0.0, 0.0)


def panda() -> RobotModel:
    """Franka Emika Panda (URDF of example-robot-data), fingers locked closed: 7 joints; tool frame
    ``panda_hand_tcp``; URDF effort/velocity/position limits; no motors and no friction.

    The URDF's ``damping="0.003"`` is a simulator hint, not an identified friction, so it is dropped; add a
    friction model with :meth:`RobotModel.with_friction` where a scene needs one.

    Returns
    -------
    RobotModel
    """
    path = robot_description("panda_description/urdf/panda.urdf")
    model = RobotModel.from_urdf(path, lock=("panda_finger_joint1", "panda_finger_joint2"), name="panda")
    tool = "panda_hand_tcp" if "panda_hand_tcp" in model.frame_names else "panda_hand"
    return RobotModel(
        model.joints,
        name="panda",
        gravity=model.gravity,
        frames=model.frames,
        tool_frame=tool,
        source=model.source,
        named_poses={"ready": PANDA_QR},
    ).reduced(friction=False)


def ur5() -> RobotModel:
    """Universal Robots UR5 (URDF of example-robot-data): 6 joints, tool frame ``tool0``.

    Returns
    -------
    RobotModel
    """
    path = robot_description("ur_description/urdf/ur5_robot.urdf")
    model = RobotModel.from_urdf(path, tool_frame="tool0", name="ur5")
    return replace(model, named_poses=_poses(ready=UR5_QR, zero=(0.0,) * 6, up=UR5_QU))
