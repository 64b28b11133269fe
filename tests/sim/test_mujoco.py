"""Simulated trajectories against MuJoCo (an engine nobody here wrote): the Panda loaded from the same URDF
(meshes stripped, fingers fixed, no damping, armature, limits or contact), the same open-loop torque profile
held over each 1 ms period, both integrating with RK4 at 1 ms."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

import armctl
from armctl.sim import simulate
from tests.sim.helpers import OpenLoop

pytestmark = pytest.mark.mujoco


class Profile:
    """τ(t) = g(q0) + a ∘ sin(2π f t + φ): a gravity-balancing offset plus a different sine on every joint."""

    def __init__(self, dyn: armctl.Dynamics, q0: np.ndarray) -> None:
        self.offset = dyn.gravity_torque(q0)
        self.amp = 0.08 * dyn.model.effort_limit
        self.freq = np.linspace(0.7, 2.3, dyn.n)
        self.phase = np.linspace(0.0, 2.0, dyn.n)

    def __call__(self, t: float) -> np.ndarray:
        return self.offset + self.amp * np.sin(2 * math.pi * self.freq * t + self.phase)


@pytest.mark.parametrize("q0", [[0.0, -0.4, 0.0, -2.0, 0.0, 1.6, 0.8], [0.5, 0.3, -0.4, -1.2, 0.7, 2.2, -0.3]])
# its run goes beyond a velocity limit on the way, as expected
@pytest.mark.filterwarnings("ignore:the run went beyond the plant's limits:armctl.errors.SimulationWarning")
def test_panda_open_loop_trajectory_matches_mujoco_rk4(q0: list[float]) -> None:
    from tests.helpers.mujoco_models import panda_mujoco

    q0 = np.array(q0)
    qd0 = np.linspace(-0.3, 0.3, 7)
    dyn = armctl.Dynamics(armctl.models.panda())
    profile = Profile(dyn, q0)
    res = simulate(dyn, OpenLoop(profile), armctl.Reference.hold(q0), 1.0, qd0=qd0, integrator="rk4", saturate=False)

    m, d = panda_mujoco()
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    m.opt.timestep = 1e-3
    d.qpos[:] = q0
    d.qvel[:] = qd0
    q_mj = [d.qpos.copy()]
    for k in range(1000):
        d.qfrc_applied[:] = profile(k * 1e-3)
        mujoco.mj_step(m, d)
        q_mj.append(d.qpos.copy())
    q_mj = np.array(q_mj)
    assert np.ptp(q_mj, axis=0).max() > 0.2  # the arm moved
    assert np.abs(res.q - q_mj).max() <= 1e-4, np.abs(res.q - q_mj).max()
