"""Stick–slip on a long chain with many joints stuck at once: the stuck joints stay exactly at rest, and a joint
driven by a torque ramp breaks away in the control period its torque passes its static level (on the generated
and the Python step alike: see this folder's conftest)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import armctl
from armctl.bench.sim_speed import planar_chain
from armctl.sim import simulate
from tests.sim.helpers import OpenLoop, Ramp

N = 20
#: the driven joint, its static level [N·m] and the ramp's rate [N·m/s]
DRIVEN, STATIC, RATE = 9, 2.0, 10.0


def _hanging() -> np.ndarray:
    q0 = np.zeros(N)
    q0[0] = -math.pi / 2  # the chain hangs straight down: no gravity torque at any joint
    return q0


@pytest.mark.parametrize("integrator", ["rk4", "semi-implicit-euler"])
def test_a_ramp_breaks_one_joint_of_twenty_loose_and_the_others_stay_exactly_at_rest(integrator: str) -> None:
    static = np.full(N, 1e3)  # every other joint holds whatever the driven one's motion asks of it
    static[DRIVEN] = STATIC
    model = planar_chain(N).with_friction(viscous=0.1, coulomb=0.8 * static, static=static)
    q0 = _hanging()
    rate = np.zeros(N)
    rate[DRIVEN] = RATE
    res = simulate(model, OpenLoop(Ramp(np.zeros(N), rate)), armctl.Reference.hold(q0), 0.3, integrator=integrator)
    assert not res.diverged
    others = np.delete(np.arange(N), DRIVEN)
    assert (res.q[:, others] == q0[others]).all()  # bit for bit: no creep on nineteen stuck joints
    assert (res.qd[:, others] == 0.0).all()
    assert res.stuck[:, others].all()
    moved = np.flatnonzero(res.q[:, DRIVEN] != q0[DRIVEN])
    assert moved.size, "the driven joint never broke away"
    k = moved[0] - 1  # the control period in which it started moving: the first whose torque passes F_s
    first_above = int(np.flatnonzero(res.tau_applied[:, DRIVEN] > STATIC)[0])
    assert k == first_above
    assert STATIC < res.tau_applied[k, DRIVEN] <= STATIC + 1.001 * RATE * 1e-3  # within one period of the ramp
    assert res.q[-1, DRIVEN] > q0[DRIVEN]


def test_joints_stuck_under_gravity_hold_it_exactly() -> None:
    """A bent chain whose static levels exceed each joint's gravity torque (computed from the model) by 10 %:
    no joint moves, and each friction torque balances its gravity torque."""
    q0 = np.linspace(-1.2, 0.4, N)
    chain = planar_chain(N)
    g = armctl.Dynamics(chain).gravity_torque(q0)
    static = 1.1 * np.abs(g) + 1e-3
    model = chain.with_friction(viscous=0.1, coulomb=0.5 * static, static=static)
    res = simulate(model, OpenLoop(lambda t: np.zeros(N)), armctl.Reference.hold(q0), 0.2)
    assert (res.q == q0).all() and (res.qd == 0.0).all() and res.stuck.all()
    np.testing.assert_allclose(res.tau_friction[-1], -g, rtol=1e-9, atol=1e-9)
