"""armctl: model-based control and planning of robot manipulators.

The spine is the Lagrange model M(q)q̈ + C(q,q̇)q̇ + g(q) = τ − F_v q̇ − F_c sgn(q̇) − J(q)ᵀh_e:
:class:`RobotModel` describes an arm, :class:`Dynamics` evaluates it.
"""

from armctl import controllers, errors, models, planning
from armctl.dynamics import Dynamics
from armctl.errors import ArmctlError
from armctl.model import RobotModel
from armctl.reference import Reference
from armctl.sim import SimResult, simulate

__version__ = "0.1.0"
__all__ = ["ArmctlError", "Dynamics", "Reference", "RobotModel", "SimResult", "controllers", "errors", "models",
           "planning", "simulate"]
