"""The algebraic identities of the Lagrange model, on random states (hypothesis), on both backends.

M symmetric positive definite; Ṁ − 2C skew-symmetric (Ṁ by central differences); Y π = τ; the passivity
regressor identity; and the energy balance dE/dt = q̇ᵀ(τ − τ_f) along the model's own forward dynamics, with
dE/dt by central differences of T + U.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import armctl
from tests.helpers.arms import dynamics

CASES = [
    ("planar_2r", "pinocchio"),
    ("planar_2r", "lagrange"),
    ("puma560", "pinocchio"),
    ("puma560", "lagrange"),
    ("panda", "pinocchio"),
    ("ur5", "pinocchio"),
    ("planar_3r", "lagrange"),
]
SETTINGS = settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


def states(n: int, k: int = 3) -> st.SearchStrategy[np.ndarray]:
    return st.lists(st.floats(-3.0, 3.0, allow_nan=False), min_size=k * n, max_size=k * n).map(
        lambda v: np.asarray(v).reshape(k, n)
    )


@pytest.mark.parametrize(("name", "backend"), CASES)
@SETTINGS
@given(data=st.data())
def test_mass_matrix_symmetric_positive_definite(name: str, backend: str, data: st.DataObject) -> None:
    dyn = dynamics(name, backend)
    q = data.draw(states(dyn.n, 1))[0]
    m = dyn.mass_matrix(q)
    assert np.allclose(m, m.T, rtol=0, atol=1e-12 * np.abs(m).max())
    assert np.linalg.eigvalsh(m).min() > 0


@pytest.mark.parametrize(("name", "backend"), CASES)
@SETTINGS
@given(data=st.data())
def test_mdot_minus_2c_is_skew_symmetric(name: str, backend: str, data: st.DataObject) -> None:
    dyn = dynamics(name, backend)
    q, qd, _ = data.draw(states(dyn.n))
    h = 1e-6
    mdot = (dyn.mass_matrix(q + h * qd) - dyn.mass_matrix(q - h * qd)) / (2 * h)
    n = mdot - 2 * dyn.coriolis_matrix(q, qd)
    # central differences: truncation O(h²) and round-off ~ ε|M|/h; N itself is O(|M| |q̇|)
    tol = 1e-7 * np.abs(dyn.mass_matrix(q)).max() * (1 + np.abs(qd).max())
    assert np.abs(n + n.T).max() <= tol
    assert abs(qd @ n @ qd) <= tol * (qd @ qd + 1)


@pytest.mark.parametrize(("name", "backend"), CASES)
@SETTINGS
@given(data=st.data())
def test_regressor_times_parameters_is_inverse_dynamics(name: str, backend: str, data: st.DataObject) -> None:
    dyn = dynamics(name, backend)
    q, qd, qdd = data.draw(states(dyn.n))
    tau = dyn.inverse_dynamics(q, qd, qdd)
    y = dyn.regressor(q, qd, qdd)
    assert y.shape == (dyn.n, 13 * dyn.n)
    # exact for puma560's asymmetric Coulomb friction too (its Coulomb column is F_c⁺/F̄_c or −F_c⁻/F̄_c)
    assert np.allclose(y @ dyn.model.parameters(), tau, rtol=1e-10, atol=1e-10 * np.abs(tau).max())


def _slotine_li_form(
    dyn: armctl.Dynamics, q: np.ndarray, qd: np.ndarray, qd_r: np.ndarray, qdd_r: np.ndarray
) -> np.ndarray:
    """M q̈_r + C(q, q̇) q̇_r + g + F_v q̇_r + τ_c(q̇), the Coulomb levels F_c⁺, −F_c⁻ read from the joints."""
    fr = [j.friction for j in dyn.model.joints]
    fv = np.array([f.viscous for f in fr])
    coulomb = np.where(qd > 0, [f.coulomb for f in fr], 0.0) - np.where(qd < 0, [f.coulomb_neg for f in fr], 0.0)
    return dyn.mass_matrix(q) @ qdd_r + dyn.coriolis_matrix(q, qd) @ qd_r + dyn.gravity_torque(q) + fv * qd_r + coulomb


@pytest.mark.parametrize(("name", "backend"), CASES)
@SETTINGS
@given(data=st.data())
def test_passivity_regressor_identity(name: str, backend: str, data: st.DataObject) -> None:
    dyn = dynamics(name, backend)
    q, qd, qd_r = data.draw(states(dyn.n))
    qdd_r = data.draw(states(dyn.n, 1))[0]
    expected = _slotine_li_form(dyn, q, qd, qd_r, qdd_r)
    y = dyn.passivity_regressor(q, qd, qd_r, qdd_r)
    got = y @ dyn.model.parameters()
    assert np.allclose(got, expected, rtol=1e-9, atol=1e-9 * max(np.abs(expected).max(), 1.0))
    # with q̇_r = q̇ and q̈_r = q̈ it is the ordinary regressor
    assert np.allclose(dyn.passivity_regressor(q, qd, qd, qdd_r), dyn.regressor(q, qd, qdd_r), atol=1e-9)


@pytest.mark.parametrize(("name", "backend"), CASES)
@SETTINGS
@given(data=st.data())
def test_passivity_torque_is_the_slotine_li_form(name: str, backend: str, data: st.DataObject) -> None:
    """passivity_torque (two inverse-dynamics evaluations: the base class's polarisation on the Lagrange
    backend, a gravity-free twin on Pinocchio's) against M q̈_r + C(q, q̇) q̇_r + g + F_v q̇_r + τ_c(q̇) formed
    from the backend's M, C and g and the joints' friction."""
    dyn = dynamics(name, backend)
    q, qd, qd_r = data.draw(states(dyn.n))
    qdd_r = data.draw(states(dyn.n, 1))[0]
    expected = _slotine_li_form(dyn, q, qd, qd_r, qdd_r)
    got = dyn.passivity_torque(q, qd, qd_r, qdd_r)
    assert np.allclose(got, expected, rtol=1e-9, atol=1e-9 * max(np.abs(expected).max(), 1.0))


@pytest.mark.parametrize(("name", "backend"), CASES)
@SETTINGS
@given(data=st.data())
def test_energy_balance_along_forward_dynamics(name: str, backend: str, data: st.DataObject) -> None:
    """dE/dt = q̇ᵀ(τ − τ_f): the power of the actuators minus what friction dissipates."""
    dyn = dynamics(name, backend)
    q, qd, tau = data.draw(states(dyn.n))
    tau = tau * 10
    qdd = dyn.forward_dynamics(q, qd, tau)

    def energy(qq: np.ndarray, vv: np.ndarray) -> float:
        return dyn.kinetic_energy(qq, vv) + dyn.potential_energy(qq)

    h = 1e-6
    de_dt = (energy(q + h * qd, qd + h * qdd) - energy(q - h * qd, qd - h * qdd)) / (2 * h)
    power = qd @ (tau - dyn.friction_torque(qd))
    roundoff = 1e-6 * (abs(energy(q, qd)) + 1)  # ~ ε|E|/h with margin
    assert de_dt == pytest.approx(power, rel=1e-5, abs=1e-5 * np.abs(tau).max() + roundoff)


@pytest.mark.parametrize(("name", "backend"), CASES)
def test_forward_dynamics_inverts_inverse_dynamics(name: str, backend: str) -> None:
    dyn = dynamics(name, backend)
    rng = np.random.default_rng(7)
    for _ in range(5):
        q, qd, qdd = rng.uniform(-2, 2, (3, dyn.n))
        wrench = rng.normal(size=6)
        tau = dyn.inverse_dynamics(q, qd, qdd, wrench=wrench)
        assert np.allclose(dyn.forward_dynamics(q, qd, tau, wrench=wrench), qdd, atol=1e-8)


@pytest.mark.parametrize("backend", ["pinocchio", "lagrange"])
def test_coulomb_column_gives_each_level(backend: str) -> None:
    """F̄_c κ(q̇) is F_c⁺ moving forwards, −F_c⁻ backwards and 0 at rest, for one-sided (F_c⁻ = 0), asymmetric
    and absent Coulomb friction; Y π = τ then holds exactly, while identification's regressor keeps
    sgn q̇ (it estimates the asymmetry as an unknown of its own)."""
    from armctl.dynamics.identification.base_parameters import identification_regressor

    pos, neg = np.array([2.0, 1.5, 0.0]), np.array([0.0, 0.5, 0.0])  # one-sided, asymmetric, none
    model = armctl.models.planar_3r().with_friction(viscous=0.1, coulomb=pos, coulomb_negative=neg)
    dyn = armctl.Dynamics(model, backend=backend)
    pi = model.parameters()
    for qd in (np.array([0.3, -0.2, 1e-9]), np.array([-1e-12, 2.0, -0.4]), np.array([0.0, 0.0, 0.0])):
        level = np.where(qd > 0, pos, 0.0) - np.where(qd < 0, neg, 0.0)  # from the levels themselves
        np.testing.assert_allclose(pi[12::13] * dyn.coulomb_column(qd), level, rtol=1e-15, atol=0)
        q, qdd = np.array([0.2, -0.4, 0.9]), np.array([0.5, -1.0, 0.3])
        y = dyn.regressor(q, qd, qdd)
        np.testing.assert_allclose(y[np.arange(3), 13 * np.arange(3) + 12], dyn.coulomb_column(qd), rtol=0)
        tau = dyn.inverse_dynamics(q, qd, qdd)
        np.testing.assert_allclose(y @ pi, tau, rtol=1e-12, atol=1e-12)
        y_id = identification_regressor(dyn, q, qd, qdd)
        np.testing.assert_array_equal(y_id[np.arange(3), 13 * np.arange(3) + 12], np.sign(qd))
        np.testing.assert_allclose(y_id @ pi + dyn.coulomb_offset(qd), tau, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("scale", [0.1, 0.5, 2.0])
def test_a_model_built_from_parameters_is_what_the_regressor_predicts(scale: float) -> None:
    """with_parameters(θ) keeps the model's ratio of the two Coulomb levels, as the regressor's Coulomb column
    does: Y(x) θ is the new model's τ, for θ with every Coulomb entry scaled (puma560, asymmetric), and the
    levels are F_c± scaled alike (read from the new model's joints)."""
    model = armctl.models.puma560()
    theta = model.parameters().copy()
    theta[12::13] *= scale
    new = model.with_parameters(theta, physical=False)
    for old_j, new_j in zip(model.joints, new.joints, strict=True):
        assert new_j.friction.coulomb == pytest.approx(scale * old_j.friction.coulomb, rel=1e-12)
        assert new_j.friction.coulomb_neg == pytest.approx(scale * old_j.friction.coulomb_neg, rel=1e-12)
    y_of, tau_of = armctl.Dynamics(model), armctl.Dynamics(new)
    rng = np.random.default_rng(1)
    for q, qd, qdd in rng.uniform(-1.5, 1.5, (5, 3, 6)):
        np.testing.assert_allclose(
            y_of.regressor(q, qd, qdd) @ theta, tau_of.inverse_dynamics(q, qd, qdd), rtol=1e-12, atol=1e-12
        )


@pytest.mark.parametrize("backend", ["pinocchio", "lagrange"])
def test_a_rotor_given_to_a_joint_without_a_motor_is_an_armature(backend: str) -> None:
    """planar_3r has no motors: a θ with rotor inertias gives its joints armatures (reflected inertia, no
    gyroscopic coupling), so Y(x) θ of the motorless arm is the new model's τ on the Lagrange backend too, which
    with a coupled k_r = 1 motor was off by up to 0.78 N·m."""
    model = armctl.models.planar_3r()
    theta = model.parameters().reshape(3, 13).copy()
    theta[:, 10] = [0.5, 0.3, 0.2]
    theta = theta.reshape(-1)
    new = model.with_parameters(theta)
    assert all(j.motor is not None and not j.motor.gyroscopic for j in new.joints)
    y_of, tau_of = armctl.Dynamics(model, backend=backend), armctl.Dynamics(new, backend=backend)
    rng = np.random.default_rng(2)
    for q, qd, qdd in rng.uniform(-1.5, 1.5, (5, 3, 3)):
        np.testing.assert_allclose(
            y_of.regressor(q, qd, qdd) @ theta, tau_of.inverse_dynamics(q, qd, qdd), rtol=1e-12, atol=1e-12
        )
