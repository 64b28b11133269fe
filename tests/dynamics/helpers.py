"""Helpers of the dynamics tests: a hand-made arm that the built-in ones do not cover."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

import armctl
from armctl.model.parts import Frame, Joint, Link, Motor


def _placement(rpy: tuple[float, float, float], xyz: tuple[float, float, float]) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3] = pin.rpy.rpyToMatrix(*rpy)
    t[:3, 3] = xyz
    return t


def skewed_rpr() -> armctl.RobotModel:
    """Revolute–prismatic–revolute arm with tilted placements, axes along no frame axis, off-axis centres of
    mass, full inertia tensors and armatures."""
    link = [
        Link(1.5, (0.1, -0.05, 0.2), np.array([[0.04, 0.002, -0.001], [0.002, 0.05, 0.003], [-0.001, 0.003, 0.03]])),
        Link(0.8, (0.02, 0.03, -0.1), np.diag([0.01, 0.02, 0.015])),
        Link(0.5, (0.0, 0.08, 0.05), np.array([[0.006, 0.0, 0.001], [0.0, 0.005, 0.0], [0.001, 0.0, 0.004]])),
    ]
    joints = (
        Joint(
            "j1",
            "revolute",
            (0.0, 0.6, 0.8),
            _placement((0.1, -0.2, 0.3), (0.0, 0.0, 0.3)),
            link[0],
            motor=Motor(2e-4, 50.0, gyroscopic=False),
        ),
        Joint("j2", "prismatic", (0.48, 0.6, 0.64), _placement((0.5, 0.0, -0.4), (0.2, 0.1, 0.0)), link[1]),
        Joint(
            "j3",
            "revolute",
            (1.0, 0.0, 0.0),
            _placement((0.0, 0.7, 0.2), (0.0, 0.3, 0.1)),
            link[2],
            motor=Motor(1e-4, 30.0, gyroscopic=False),
        ),
    )
    return armctl.RobotModel(joints, name="skewed_rpr", frames=(Frame("tool", 3, np.eye(4)),), tool_frame="tool")
