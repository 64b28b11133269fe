"""Helpers of the operational-space QP tests: the Panda's ready posture and its Dynamics, built once; the independent
solver (quadprog) the tests check optima against."""

from __future__ import annotations

from functools import cache
from types import ModuleType

import numpy as np
import pytest

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


def rotation_zyx(rx: float, ry: float, rz: float) -> np.ndarray:
    """R_z R_y R_x, written out (not from the code under test)."""
    cx, sx, cy, sy, cz, sz = np.cos(rx), np.sin(rx), np.cos(ry), np.sin(ry), np.cos(rz), np.sin(rz)
    rot_x = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    rot_y = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rot_z = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rot_z @ rot_y @ rot_x


def quadprog_solvers() -> ModuleType:
    """qpsolvers, where it has quadprog (the independent solver of the optimality tests); else the calling test, or
    the module that calls it at import, is skipped."""
    qpsolvers = pytest.importorskip("qpsolvers")
    if "quadprog" not in qpsolvers.available_solvers:  # pragma: no cover - the test extra installs it
        pytest.skip("quadprog (the test extra) is not installed", allow_module_level=True)
    return qpsolvers
