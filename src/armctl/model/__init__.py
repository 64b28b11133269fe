"""Robot descriptions: :class:`RobotModel` and its parts, DH and URDF loaders."""

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
