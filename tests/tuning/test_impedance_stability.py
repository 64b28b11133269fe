"""The sampled-data model of Cartesian impedance on a compliant environment: its transition matrix against an
independent hybrid simulation (SciPy's integrator between held samples), its default damping against the closed
form, the controller's Λ, K and D it reads, its border against closed loops of the Panda pressing on a table
(within 15 % at every impedance stiffness of the bench's map), and bad input."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import armctl
from armctl.bench.interaction_borders import Q_READY, impedance_outcome, predicted_environment_stiffness
from armctl.controllers import CartesianImpedance
from armctl.errors import InvalidParameterError
from armctl.tuning.force_stability import normal_inertia
from armctl.tuning.impedance_stability import (
    critical_environment_stiffness,
    impedance_loop_matrix,
    impedance_model,
)


def _spd(rng: np.random.Generator, m: int, scale: float) -> np.ndarray:
    a = rng.normal(size=(m, m))
    return scale * (a @ a.T + m * np.eye(m)) / m


def test_the_transition_matrix_is_the_held_delayed_loop_on_six_coupled_axes() -> None:
    rng = np.random.default_rng(1)
    m, period, k_e, d_e = 6, 1e-3, 2e5, 30.0
    lam, k, d = _spd(rng, m, 3.0), _spd(rng, m, 500.0), _spd(rng, m, 60.0)
    n = np.array([0.3, -0.2, 0.9, 0.0, 0.0, 0.0])
    n /= np.linalg.norm(n)
    big = impedance_loop_matrix(k_e, k, lam, period, delay=1, damping=d_e, impedance_damping=d, normal=n[:3])
    z = rng.normal(size=4 * m)  # (x_k, ẋ_k, x_{k−1}, ẋ_{k−1})
    force = -k @ z[2 * m : 3 * m] - d @ z[3 * m :]  # from the sample one period old, held
    contact = np.outer(n, n)

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        x, v = y[:m], y[m:]
        return np.concatenate([v, np.linalg.solve(lam, force - k_e * contact @ x - d_e * contact @ v)])

    sol = solve_ivp(rhs, (0.0, period), z[: 2 * m], method="DOP853", rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose((big @ z)[: 2 * m], sol.y[:, -1], rtol=1e-8, atol=1e-11)
    np.testing.assert_array_equal((big @ z)[2 * m :], z[: 2 * m])


def test_the_default_damping_is_critical_and_decoupled_axes_give_the_one_axis_border() -> None:
    lam, k_d, zeta = 4.0, 1000.0, 0.7
    one_axis = {"inertia": lam, "period": 1e-3, "delay": 1}
    np.testing.assert_allclose(
        impedance_loop_matrix(3e6, k_d, zeta=zeta, **one_axis),
        impedance_loop_matrix(3e6, k_d, impedance_damping=2.0 * zeta * np.sqrt(k_d * lam), **one_axis),
    )
    k_star = critical_environment_stiffness(k_d, **one_axis)
    # three axes, diagonal Λ and K, the contact along z: the other axes do not couple
    three = critical_environment_stiffness([300.0, 50.0, k_d], inertia=[2.0, 9.0, lam], period=1e-3, delay=1)
    np.testing.assert_allclose(three, k_star, rtol=1e-3)
    assert critical_environment_stiffness(k_d, inertia=lam, period=1e-3, delay=2) < k_star


def test_the_model_reads_the_controllers_inertia_and_damping() -> None:
    dyn = armctl.Dynamics(armctl.models.panda())
    c = CartesianImpedance(dyn, [3000.0, 3000.0, 3000.0, 50.0, 50.0, 50.0], compile=False)
    c.set_target(dyn.frame_pose(Q_READY))
    model = impedance_model(c, Q_READY)
    qd = np.random.default_rng(2).normal(size=7)
    c(0.0, Q_READY, qd, armctl.Reference(Q_READY))
    # at the target, the controller's force is the damping's: F = D ė = −D J q̇
    np.testing.assert_allclose(c.last_log["force"], -model["impedance_damping"] @ dyn.jacobian(Q_READY) @ qd,
                               rtol=1e-9, atol=1e-9)  # fmt: skip
    # the normal's mobility nᵀ Λ⁻¹ n is the arm's 1/Λ_n = (J_v M⁻¹ J_vᵀ)_zz
    np.testing.assert_allclose(1.0 / np.linalg.inv(model["inertia"])[2, 2], normal_inertia(dyn, Q_READY), rtol=1e-9)
    np.testing.assert_array_equal(model["impedance_stiffness"], c.stiffness)


@pytest.mark.parametrize("k_d", [100.0, 3000.0])
def test_impedance_on_the_panda_chatters_within_15_percent_of_the_predicted_environment_stiffness(k_d: float) -> None:
    k_star = predicted_environment_stiffness(k_d)
    assert impedance_outcome(k_d, 0.85 * k_star) == "stable"
    assert impedance_outcome(k_d, 1.15 * k_star) == "chatter"


def test_bad_input_is_named() -> None:
    with pytest.raises(InvalidParameterError, match="no stability border"):
        critical_environment_stiffness(100.0, inertia=4.0, period=1e-3, damping=1e9)
    with pytest.raises(InvalidParameterError, match="inertia"):
        impedance_loop_matrix(1e4, 100.0, inertia=0.0, period=1e-3)
    with pytest.raises(InvalidParameterError, match="impedance_damping"):
        impedance_loop_matrix(1e4, 100.0, inertia=4.0, period=1e-3, impedance_damping=-1.0)
    with pytest.raises(InvalidParameterError, match="normal"):
        impedance_loop_matrix(1e4, 100.0, inertia=np.eye(3), period=1e-3, normal=[0.0, 0.0, 0.0])
    with pytest.raises(InvalidParameterError, match="CartesianImpedance"):
        impedance_model(object(), Q_READY)
    dyn = armctl.Dynamics(armctl.models.panda())
    shaped = CartesianImpedance(dyn, [500.0] * 3, inertia=[2.0] * 3, compile=False)
    with pytest.raises(InvalidParameterError, match="inertia"):
        impedance_model(shaped, Q_READY)
