"""Each integrator converges at its order to closed-form or independent solutions, on the paths that only
the simulator takes: time-dependent forcing, stiff joint friction, friction with the Coriolis term."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import armctl
from armctl.sim import Forces, simulate
from tests.sim.helpers import slider, zero_torque


def test_rk4_is_fourth_order_under_a_time_dependent_push() -> None:
    # a free slider pushed by A sin ωt: x(t) = A/(m ω²) (ω t − sin ω t). RK4 must evaluate its last stage at
    # t + h (at t the scheme drops to first order: error 8e-5 at 1 ms, halving with the step)
    m, a, w = 2.0, 10.0, 20.0
    errors = []
    for dt in (1e-3, 5e-4):
        res = simulate(
            slider(m),
            zero_torque,
            armctl.Reference.hold([0.0]),
            1.0,
            dt=dt,
            forces=Forces(disturbance=lambda t: np.array([-a * math.sin(w * t), 0.0, 0.0, 0.0, 0.0, 0.0])),
        )
        exact = a / (m * w * w) * (w * res.t - np.sin(w * res.t))
        errors.append(float(np.abs(res.q[:, 0] - exact).max()))
    assert errors[0] < 1e-9
    assert 10.0 < errors[0] / errors[1] < 22.0  # 2⁴ = 16


def test_implicit_euler_takes_stiff_viscous_friction_in_its_stride() -> None:
    # the pendulum in zero gravity with F_v = 1500 N·m·s/rad: q̇ decays at F_v / J ≈ 5e3 1/s, five times
    # faster than a 1 ms step. Backward Euler with the friction at the new velocity is the recurrence
    # q̇₁ = q̇ / (1 + h F_v / J), stable at any step; with the friction taken at the old velocity it diverges
    model = armctl.models.pendulum()
    flat = armctl.RobotModel(
        model.joints, name="flat", gravity=np.zeros(3), frames=model.frames, tool_frame=model.tool_frame
    ).with_friction(viscous=1500.0)
    inertia = float(armctl.Dynamics(flat).mass_matrix(np.zeros(1))[0, 0])
    res = simulate(
        flat,
        zero_torque,
        armctl.Reference.hold([0.0]),
        0.02,
        qd0=[1.0],
        integrator="implicit-euler",
        forces=Forces(friction="smooth"),
    )
    assert not res.diverged
    factor = 1.0 / (1.0 + 1e-3 * 1500.0 / inertia)
    np.testing.assert_allclose(res.qd[:, 0], factor ** np.arange(len(res.t)), rtol=1e-9, atol=1e-300)


def test_semi_implicit_euler_with_friction_converges_to_the_exact_motion() -> None:
    # planar_2r swinging freely with viscous friction (the non-conservative path of the scheme, which takes
    # C(q, v̄)ᵀ v̄): against scipy's solve_ivp on the forward dynamics at tight tolerance, the error halves with
    # the step (first order). With C v̄ instead of Cᵀ v̄ (a force that does no work, so the energy balance cannot
    # see it) it stayed near 2 rad whatever the step
    model = armctl.models.planar_2r().with_friction(viscous=2.0)
    dyn = armctl.Dynamics(model)
    q0, duration = np.array([0.4, -0.3]), 1.0

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        q, v = x[:2], x[2:]
        return np.concatenate([v, dyn.forward_dynamics(q, v, np.zeros(2))])

    sol = solve_ivp(rhs, (0.0, duration), np.concatenate([q0, [2.0, -1.0]]), rtol=1e-11, atol=1e-11, dense_output=True)
    errors = []
    for dt in (1e-3, 5e-4):
        res = simulate(
            model,
            zero_torque,
            armctl.Reference.hold([0.0, 0.0]),
            duration,
            q0=q0,
            qd0=[2.0, -1.0],
            dt=dt,
            integrator="semi-implicit-euler",
            forces=Forces(friction="smooth"),
        )
        errors.append(float(np.abs(res.q - sol.sol(res.t)[:2].T).max()))
    assert errors[0] < 2e-2
    assert errors[0] / errors[1] == pytest.approx(2.0, rel=0.2)
