"""Helpers of the operational-space QP tests: the Panda's ready posture and its Dynamics, built once."""

from __future__ import annotations

from functools import cache

import numpy as np

import armctl

#: The Panda's usual "ready" posture.
Q_HOME = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])


@cache
def panda_dynamics(backend: str = "pinocchio", friction: bool = False) -> armctl.Dynamics:
    model = armctl.models.panda()
    if friction:
        model = model.with_friction(
            viscous=[0.5, 0.5, 0.5, 0.5, 0.2, 0.2, 0.2], coulomb=[0.8, 0.8, 0.8, 0.8, 0.3, 0.3, 0.3]
        )
    return armctl.Dynamics(model, backend=backend)
