"""The parts of a robot description: :class:`RobotModel` and what it is made of (``Link``, ``Joint``,
``Motor``, ``JointFriction``, ``JointLimits``, ``Frame``, ``DHLink``), with the DH, URDF and MJCF loaders
(``RobotModel.from_dh``, ``from_urdf``, ``from_mjcf``).

The built-in arms (``pendulum()``, ``planar_2r()``, ``panda()``, ...) are reached as :mod:`armctl.models`
(plural); they are defined here, in :mod:`armctl.model.library`."""

from armctl.model.dh import DHLink
from armctl.model.parts import Frame, Joint, JointFriction, JointLimits, Link, Motor
from armctl.model.robot import PARAMETER_NAMES, PARAMS_PER_JOINT, RobotModel

__all__ = [
    "PARAMETER_NAMES",
    "PARAMS_PER_JOINT",
    "DHLink",
    "Frame",
    "Joint",
    "JointFriction",
    "JointLimits",
    "Link",
    "Motor",
    "RobotModel",
]
