"""Limits of the operational-space QP: bounds on q̈ or τ, one row per joint."""

from armctl.controllers.osc.limits.acceleration import AccelerationLimit
from armctl.controllers.osc.limits.base import Limit
from armctl.controllers.osc.limits.position import JointPositionLimit
from armctl.controllers.osc.limits.torque import TorqueLimit
from armctl.controllers.osc.limits.velocity import JointVelocityLimit

__all__ = ["AccelerationLimit", "JointPositionLimit", "JointVelocityLimit", "Limit", "TorqueLimit"]
