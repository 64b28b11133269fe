"""Helpers of the planning tests: a panda path inside its joint ranges, models with friction."""

from __future__ import annotations

import dataclasses
from functools import cache

import numpy as np

import armctl

PANDA_WAYPOINTS = np.array(
    [
        [0.03, 0.79, -1.03, -0.90, -0.55, 1.72, 0.95],
        [-0.26, 0.09, -1.37, -1.19, 0.11, 1.55, 0.84],
        [-0.57, -0.08, -1.06, -1.72, -0.86, 1.42, 0.73],
        [-0.64, -0.03, 1.39, -0.88, 0.65, 1.95, -0.65],
        [-0.98, 0.83, 0.05, -2.15, 0.36, 2.39, 0.33],
    ]
)

# joint friction of a geared arm: viscous [N·m·s/rad], Coulomb up / down [N·m]
PANDA_VISCOUS = np.array([0.6, 0.6, 0.5, 0.5, 0.2, 0.2, 0.1])
PANDA_COULOMB = np.array([1.5, 1.5, 1.2, 1.2, 0.5, 0.5, 0.3])
PANDA_COULOMB_NEG = 1.2 * PANDA_COULOMB


@cache
def panda(friction: bool = False) -> armctl.Dynamics:
    model = armctl.models.panda()
    if friction:
        model = model.with_friction(viscous=PANDA_VISCOUS, coulomb=PANDA_COULOMB, coulomb_negative=PANDA_COULOMB_NEG)
    return armctl.Dynamics(model)


@cache
def flat_pendulum(viscous: float = 0.0, coulomb: float = 0.0, coulomb_negative: float | None = None) -> armctl.Dynamics:
    """The library's pendulum with gravity switched off and the given friction: M q̈ + friction = τ with a
    constant M (the rod about its end plus the reflected rotor)."""
    model = dataclasses.replace(armctl.models.pendulum(), gravity=np.zeros(3))
    return armctl.Dynamics(model.with_friction(viscous=viscous, coulomb=coulomb, coulomb_negative=coulomb_negative))


# the pendulum's inertia about its axis, from its published data: a 2 kg, 0.5 m rod (m ℓ²/3) and a rotor of
# 5e-5 kg·m² behind a 50:1 gear (k_r² I_m)
PENDULUM_INERTIA = 2.0 * 0.5**2 / 3.0 + 50.0**2 * 5e-5
PENDULUM_GRAVITY = 2.0 * 9.81 * 0.25  # m g ℓ/2: the largest gravity torque [N·m]
