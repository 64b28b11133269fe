"""Physical consistency: the pseudo-inertia test against triangle inequalities computed by hand, the
factor parametrisation, and π → RobotModel (model_from_parameters)."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.dynamics.identification import model_from_parameters
from armctl.dynamics.identification.pseudo_inertia import factor_of, is_consistent, parameters_from_factor
from armctl.errors import InvalidParameterError
from tests.helpers.arms import MODEL_NAMES, model


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


def _excited(
    truth: armctl.RobotModel,
    nominal: armctl.RobotModel,
    duration: float,
    rate: float,  # type: ignore[no-untyped-def]
    maxiter: int,
):
    """(Dynamics of ``nominal``, its base parameters, t, q, q̇, q̈, τ): the excitation optimised for ``nominal``
    (6 s period, 3 harmonics, ``maxiter`` iterations) sampled at ``rate`` Hz for ``duration`` s, and the exact
    torques of ``truth`` along it."""
    from armctl.dynamics import identification as ident

    dyn = armctl.Dynamics(nominal)
    base = ident.find_base_parameters(dyn)
    traj = ident.optimize_excitation(dyn, base, period=6.0, harmonics=3, maxiter=maxiter, acceleration_limit=5.0)
    t = np.arange(0.0, duration, 1 / rate)
    q, qd, qdd = traj.trajectory.evaluate(t)
    true_dyn = armctl.Dynamics(truth)
    tau = np.array([true_dyn.inverse_dynamics(*x) for x in zip(q, qd, qdd, strict=True)])
    return dyn, base, t, q, qd, qdd, tau


def _pendulum_problem(mass: float):  # type: ignore[no-untyped-def]
    """A pendulum with viscous and asymmetric Coulomb friction, identified from 12 s of data with 2 % torque
    noise, and the same arm with its mass scaled by ``mass``: the prior the consistent estimate starts from."""
    from armctl.dynamics import identification as ident

    truth = armctl.models.pendulum().with_friction(viscous=0.05, coulomb=0.3, coulomb_negative=0.2)
    nominal = truth.perturbed(seed=2, mass=mass)
    dyn, base, t, q, _, _, tau = _excited(truth, nominal, duration=12.0, rate=500, maxiter=5)
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


def _exact_pendulum(truth: armctl.RobotModel, nominal: armctl.RobotModel, pull: float = 0.0):  # type: ignore[no-untyped-def]
    """The arm of ``nominal`` (the prior) and noise-free data of ``truth`` (exact states, no filter) along the
    best random excitation over one 6 s period at 250 Hz; ``pull`` [N·m] is added to the torque while the joint
    moves down (data no friction can give if it makes F_c⁻ negative)."""
    from armctl.dynamics import identification as ident

    dyn, base, t, q, qd, qdd, tau = _excited(truth, nominal, duration=6.0, rate=250, maxiter=0)
    tau[:, 0] += pull * (qd[:, 0] < 0)
    return dyn, base, ident.IdentificationData(t, q, qd, qdd, tau)


def test_consistent_estimate_clamps_a_negative_coulomb_level_at_zero() -> None:
    """Data whose least squares give F_c⁻ = F_c − δ = −0.2 N·m (F_c⁺ = 0.3, then 0.2 N·m pushing while moving
    down): the constraint F_c ± δ ≥ 0 binds, and the estimate is the least squares with F_c⁻ = 0 (δ = F_c),
    solved by hand with numpy on the problem's regressor — the only constraint the least squares violate."""
    from armctl.dynamics import identification as ident

    truth = armctl.models.pendulum().with_friction(viscous=0.05, coulomb=0.3, coulomb_negative=0.0)
    dyn, base, data = _exact_pendulum(truth, truth.perturbed(seed=2, mass=1.2), pull=0.2)
    result = ident.identify(dyn, data, base=base)
    names = result.problem.names
    fc, offset = names.index("Fc[0]"), names.index("Fc_offset[0]")
    ls = result.estimate.theta
    assert ls[fc] - ls[offset] == pytest.approx(-0.2, abs=1e-9)  # the case is what it should be
    w = np.array(result.problem.regressor)
    w[:, fc] += w[:, offset]  # F_c sgn q̇ + δ |sgn q̇| with δ = F_c
    reduced, *_ = np.linalg.lstsq(np.delete(w, offset, axis=1), result.problem.torque, rcond=None)
    expected = np.insert(reduced, offset, reduced[fc])
    cons = result.consistent
    assert cons.converged, cons.message
    np.testing.assert_allclose(cons.theta, expected, rtol=1e-5, atol=1e-7)
    friction = cons.model.joints[0].friction
    assert friction.coulomb_neg == pytest.approx(0.0, abs=1e-7)
    assert friction.coulomb == pytest.approx(2 * reduced[fc], rel=1e-5)


def test_prior_weight_is_relative_to_the_mean_column_norm() -> None:
    """A prior mass far too low for the data (0.3 × the truth's) makes the prior pull against the fit. The result
    must minimise the documented objective ‖W K π − y‖² + λ · mean_k ‖W_k‖² · ‖N_oᵀ(π − π_0)‖² (OLS, no
    offsets; the compressed matrix R = Qᵀ W has W's column norms), written out here with scipy's null space of
    K: along every curve of bodies through the result — a coordinate of the factor J = U Uᵀ of its pseudo-
    inertia, or of the square roots of its rotor and friction levels — its derivative vanishes (central
    differences), while that of the data term alone does not."""
    import scipy.linalg

    from armctl.dynamics.identification import consistent_estimate, identify

    truth = armctl.models.pendulum().with_friction(viscous=0.05, coulomb=0.3)
    prior = truth.perturbed(seed=2, mass=0.3)
    dyn, base, data = _exact_pendulum(truth, prior)
    problem = identify(dyn, data, base=base, weighted=False, offsets=False, consistent=False).problem
    lam = 1e-2
    cons = consistent_estimate(problem, prior, None, prior_weight=lam)
    assert cons.converged, cons.message
    assert cons.cost_ratio > 2.0  # the prior does cost the fit here

    w, y, kmap = problem.regressor, problem.torque, problem.base.map
    null = scipy.linalg.null_space(kmap)
    weight = lam * float((w**2).sum(axis=0).mean())

    def terms(pi: np.ndarray) -> np.ndarray:  # (data term, prior term)
        e, d = w @ (kmap @ pi) - y, null.T @ (pi - prior.parameters())
        return np.array([e @ e, weight * (d @ d)])

    pi = np.array(cons.pi)
    x = np.r_[factor_of(pi[:10], floor=1e-12), np.sqrt(pi[10:])]

    def body(x: np.ndarray) -> np.ndarray:
        return np.r_[parameters_from_factor(x[:10])[0][0], x[10:] ** 2]

    np.testing.assert_allclose(body(x), pi, atol=1e-10)
    h = 1e-6
    grad = np.array([(terms(body(x + h * e)) - terms(body(x - h * e))) / (2 * h) for e in np.eye(x.size)])
    data_grad = np.linalg.norm(grad[:, 0])
    assert data_grad > 1.0
    assert np.linalg.norm(grad.sum(axis=1)) < 1e-3 * data_grad
