"""Physical consistency: the pseudo-inertia test against triangle inequalities computed by hand, the
factor parametrisation, and π → RobotModel (model_from_parameters)."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.dynamics.identification import model_from_parameters
from armctl.dynamics.identification.pseudo_inertia import factor_of, is_consistent, parameters_from_factor
from armctl.errors import InvalidParameterError
from tests.conftest import MODEL_NAMES, model


def _params(mass: float, com: np.ndarray, inertia_c: np.ndarray) -> np.ndarray:
    """(m, m c, I_O in π's order) by the parallel-axis theorem."""
    io = inertia_c + mass * (com @ com * np.eye(3) - np.outer(com, com))
    return np.array([mass, *(mass * com), io[0, 0], io[0, 1], io[1, 1], io[0, 2], io[1, 2], io[2, 2]])


def _body_like(rng: np.random.Generator) -> tuple[float, np.ndarray, np.ndarray, bool]:
    """A random mass, com and symmetric I_C, and whether I_C is a body's (PSD, triangle inequalities)."""
    moments = rng.uniform(0.0, 1.0, 3)
    r, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    ic = r @ np.diag(moments) @ r.T
    s = np.sort(moments)
    return float(rng.uniform(0.1, 5.0)), rng.standard_normal(3) * 0.2, ic, bool(s[0] + s[1] >= s[2])


def test_pseudo_inertia_test_is_the_triangle_inequality() -> None:
    rng = np.random.default_rng(0)
    seen = set()
    for _ in range(300):
        m, c, ic, body = _body_like(rng)
        assert is_consistent(_params(m, c, ic)) == body
        seen.add(body)
    assert seen == {True, False}
    assert not is_consistent(_params(1.0, np.zeros(3), np.eye(3)) * np.r_[-1.0, np.ones(9)])  # negative mass


def test_every_factor_is_a_body_and_every_body_has_a_factor() -> None:
    rng = np.random.default_rng(1)
    x = rng.standard_normal((50, 10))
    p, jac = parameters_from_factor(x)
    assert all(is_consistent(row) for row in p)
    # Jacobian against central differences
    h = 1e-6
    for k in range(10):
        e = np.zeros(10)
        e[k] = h
        num = (parameters_from_factor(x + e)[0] - parameters_from_factor(x - e)[0]) / (2 * h)
        np.testing.assert_allclose(jac[:, :, k], num, atol=1e-7)
    for _ in range(20):
        m, c, ic, body = _body_like(rng)
        if body:
            target = _params(m, c, ic)
            np.testing.assert_allclose(parameters_from_factor(factor_of(target, floor=0.0))[0][0], target, atol=1e-9)


@pytest.mark.parametrize("name", MODEL_NAMES)
def test_model_from_its_own_parameters_is_the_same_arm(name: str) -> None:
    m = model(name)
    rebuilt = model_from_parameters(m, m.parameters(), physical=name != "puma560")  # the published Puma is not
    np.testing.assert_allclose(rebuilt.parameters(), m.parameters(), atol=1e-12)
    a, b = armctl.Dynamics(m), armctl.Dynamics(rebuilt)
    rng = np.random.default_rng(2)
    for _ in range(3):
        q, qd, qdd = rng.standard_normal((3, m.n))
        np.testing.assert_allclose(b.inverse_dynamics(q, qd, qdd), a.inverse_dynamics(q, qd, qdd), atol=1e-10)
    assert rebuilt.joint_names == m.joint_names and rebuilt.tool_frame == m.tool_frame


def test_published_puma_is_refused_as_physical() -> None:
    puma = model("puma560")
    with pytest.raises(InvalidParameterError, match="triangle"):
        model_from_parameters(puma, puma.parameters())
    fixed = armctl.models.puma560(physical=True)
    assert model_from_parameters(fixed, fixed.parameters()).n == 6


def test_parameters_of_no_body_are_refused() -> None:
    m = model("planar_2r")
    pi = m.parameters().copy()
    bad_mass = pi.copy()
    bad_mass[13] = -1.0
    with pytest.raises(InvalidParameterError, match="negative"):
        model_from_parameters(m, bad_mass)
    moment_without_mass = pi.copy()
    moment_without_mass[13] = 0.0  # m[1] = 0 but m c of link 2 stays
    with pytest.raises(InvalidParameterError, match="without mass"):
        model_from_parameters(m, moment_without_mass)
    negative_friction = pi.copy()
    negative_friction[11] = -0.1
    with pytest.raises(InvalidParameterError):
        model_from_parameters(m, negative_friction)
    with pytest.raises(InvalidParameterError, match="Coulomb"):
        model_from_parameters(m, pi, coulomb_offset=[1.0, 0.0])  # F_c = 0: F_c − δ < 0


def test_massless_link_and_new_rotor_and_asymmetric_friction() -> None:
    m = model("planar_3r")
    pi = m.parameters().reshape(3, 13).copy()
    pi[0, :4] = 0.0  # link 1 massless (its inertia about the origin stays)
    pi[1, 10] = 0.05  # a rotor where the model has no motor
    pi[2, 12] = 2.0  # mean Coulomb level
    rebuilt = model_from_parameters(m, pi.ravel(), coulomb_offset=[0.0, 0.0, 0.5])
    np.testing.assert_allclose(rebuilt.parameters(), pi.ravel(), atol=1e-12)
    assert rebuilt.joints[0].link.mass == 0.0
    assert rebuilt.joints[1].motor is not None and rebuilt.joints[1].motor.reflected_inertia == pytest.approx(0.05)
    fr = rebuilt.joints[2].friction
    assert (fr.coulomb, fr.coulomb_neg) == (pytest.approx(2.5), pytest.approx(1.5))


def _pendulum_problem(mass: float):  # type: ignore[no-untyped-def]
    """A pendulum with viscous and asymmetric Coulomb friction, identified from 12 s of data with 2 % torque
    noise, and the same arm with its mass scaled by ``mass``: the prior the consistent estimate starts from."""
    from armctl.dynamics import identification as ident

    truth = armctl.models.pendulum().with_friction(viscous=0.05, coulomb=0.3, coulomb_negative=0.2)
    nominal = truth.perturbed(seed=2, mass=mass)
    dyn = armctl.Dynamics(nominal)
    base = ident.find_base_parameters(dyn)
    traj = ident.optimize_excitation(dyn, base, period=6.0, harmonics=3, maxiter=5, acceleration_limit=5.0)
    t = np.arange(0.0, 12.0, 1 / 500)
    q, qd, qdd = traj.trajectory.evaluate(t)
    true_dyn = armctl.Dynamics(truth)
    tau = np.array([true_dyn.inverse_dynamics(*x) for x in zip(q, qd, qdd, strict=True)])
    tau += 0.02 * np.sqrt((tau**2).mean()) * np.random.default_rng(0).standard_normal(tau.shape)
    result = ident.identify(dyn, ident.prepare_data(t, q, tau, cutoff=5.0), base=base, consistent=False)
    return result, nominal


@pytest.mark.parametrize("mass", [0.6, 0.9])
def test_consistent_estimate_leaves_a_wrong_prior_when_the_data_say_so(mass: float) -> None:
    # the truth is physical, so a consistent fit as good as least squares exists; MINPACK's LM alone stopped at
    # the prior (cost ratio 2.5e4 and 1.6e3 for these two) and called that converged
    from armctl.dynamics.identification import consistent_estimate

    result, nominal = _pendulum_problem(mass)
    cons = consistent_estimate(result.problem, nominal, result.estimate)
    assert cons.converged, cons.message
    assert cons.cost_ratio < 1.001
    np.testing.assert_allclose(cons.residual_rms, result.estimate.residual_rms, rtol=1e-3)
    # on smaller budgets, "converged" is said only of a fit as good
    for budget in (1, 3, 10):
        short = consistent_estimate(result.problem, nominal, result.estimate, max_evaluations=budget)
        assert not short.converged or short.cost_ratio < 1.001, (budget, short.cost_ratio)
