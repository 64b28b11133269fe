"""``panda_topp``: the Panda tracking a time-optimal path through six waypoints, against joint friction with
stiction."""

from __future__ import annotations

from functools import cache

import numpy as np

from armctl import models
from armctl.dynamics.base import Dynamics
from armctl.model.robot import RobotModel
from armctl.scenes.base import Scene

WAYPOINTS = np.array(
    [
        [0.0, -0.6, 0.0, -2.2, 0.0, 1.6, 0.8],
        [0.5, -0.3, 0.3, -1.9, 0.2, 1.8, 1.0],
        [0.9, 0.1, 0.4, -1.5, 0.4, 2.0, 0.6],
        [0.4, 0.3, -0.2, -1.2, 0.1, 2.3, 0.2],
        [-0.3, 0.0, -0.4, -1.7, -0.3, 1.9, 0.5],
        [-0.6, -0.4, -0.2, -2.1, -0.1, 1.7, 0.9],
    ]
)


def panda_with_friction() -> RobotModel:
    """The Panda with illustrative joint friction of a plausible magnitude for its geared joints (viscous
    0.1–0.3 N·m·s/rad, Coulomb 0.1–0.5 N·m, breakaway 30 % above Coulomb) — not identified values."""
    return models.panda().with_friction(
        viscous=[0.3, 0.3, 0.3, 0.3, 0.1, 0.1, 0.1],
        coulomb=[0.5, 0.5, 0.5, 0.5, 0.2, 0.2, 0.1],
        static=[0.65, 0.65, 0.65, 0.65, 0.26, 0.26, 0.13],
    )


@cache
def _trajectory(margin: float):
    from armctl.planning import time_optimal

    return time_optimal(
        Dynamics(panda_with_friction()),
        WAYPOINTS,
        vel_limit="model",
        torque_limit="model",
        grid=100,
        torque_margin=margin,
    )


def panda_topp(margin: float = 0.1) -> Scene:
    """Time-optimal (TOPP-RA) path through six waypoints with velocity and torque limits, planned on the exact
    model with ``margin`` of the torque range left for feedback. The plant sticks (breakaway above Coulomb);
    the exact model knows the kinetic friction, the reduced one none.

    Parameters
    ----------
    margin : float, optional
        The share of the torque range left for feedback, in [0, 1).

    Returns
    -------
    Scene
    """
    plant = panda_with_friction()
    traj = _trajectory(margin)
    return Scene(
        "panda_topp",
        "Panda tracking a time-optimal path with stick–slip joint friction",
        plant=plant,
        exact=plant,
        reduced=models.panda(),
        reference=traj,
        duration=float(np.ceil(traj.duration * 1000) / 1000) + 0.2,
        q0=WAYPOINTS[0],
    )
