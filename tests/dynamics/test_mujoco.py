"""Forward dynamics of the Panda against MuJoCo loading the same URDF (an engine nobody here wrote)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.helpers.arms import dynamics

pytestmark = pytest.mark.mujoco


@pytest.mark.parametrize("backend", ["pinocchio", "lagrange"])
def test_panda_forward_dynamics_matches_mujoco(backend: str) -> None:
    from tests.helpers.mujoco_models import mujoco_forward, panda_mujoco

    m, d = panda_mujoco()
    dyn = dynamics("panda", backend)
    rng = np.random.default_rng(4)
    for _ in range(20):
        q = rng.uniform(dyn.model.lower, dyn.model.upper)
        qd = rng.uniform(-2, 2, 7)
        tau = rng.uniform(-1, 1, 7) * dyn.model.effort_limit
        expected = mujoco_forward(m, d, q, qd, tau)
        got = dyn.forward_dynamics(q, qd, tau)
        assert np.abs(got - expected).max() <= 1e-6 * np.abs(expected).max()
