"""Frame kinematics in CasADi SX (for generated code) against Pinocchio's: pose, Jacobian and J̇ q̇."""

from __future__ import annotations

import casadi as cs
import numpy as np
import pytest

import armctl
from armctl.dynamics.operational_space import frame_drift
from armctl.dynamics.symbolic_frames import frame_kinematics
from armctl.model import DHLink

_PRISMATIC = armctl.RobotModel.from_dh(
    [DHLink(a=0.3, mass=1.0), DHLink(d=0.2, alpha=0.4, mass=1.0, kind="prismatic"), DHLink(a=0.2, alpha=0.5, mass=0.5)]
)


@pytest.mark.parametrize("model", [armctl.models.panda(), armctl.models.ur5(), _PRISMATIC], ids=lambda m: m.name)
def test_frame_kinematics_is_pinocchios(model: armctl.RobotModel) -> None:
    """On random states, for the tool frame, every joint's frame, the named frames and the world: position,
    rotation and Jacobian equal ``Dynamics.frame_pose`` / ``jacobian``, and J̇ q̇ Pinocchio's classical
    acceleration at q̈ = 0 (LOCAL_WORLD_ALIGNED), to rounding."""
    dyn = armctl.Dynamics(model)
    n = model.n
    q, qd = cs.SX.sym("q", n), cs.SX.sym("qd", n)
    rng = np.random.default_rng(0)
    states = [(rng.normal(size=n), rng.normal(size=n)) for _ in range(5)]
    for name in [None, *model.frame_names]:
        f = cs.Function("f", [q, qd], list(frame_kinematics(model, q, qd, name)))
        for qv, qdv in states:
            p, rot, jac, drift = (np.array(a) for a in f(qv, qdv))
            pose = dyn.frame_pose(qv, name)
            np.testing.assert_allclose(p.ravel(), pose[:3, 3], atol=1e-12)
            np.testing.assert_allclose(rot, pose[:3, :3], atol=1e-12)
            np.testing.assert_allclose(jac, dyn.jacobian(qv, name), atol=1e-12)
            np.testing.assert_allclose(drift.ravel(), frame_drift(dyn, qv, qdv, name), atol=1e-11)
