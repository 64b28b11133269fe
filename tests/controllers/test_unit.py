"""Controllers without a simulator: the laws themselves, gains, references and bad input."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import armctl
from armctl.controllers import Adaptive, ComputedTorque, Controller, PassivityBased, PDGravity
from armctl.errors import InvalidParameterError, NonFiniteError, ShapeError
from armctl.model.consistency import is_physical, project_physical, projection
from tests.helpers.arms import dynamics

REF7 = armctl.Reference(np.full(7, 0.1), np.full(7, 0.2), np.full(7, -0.3))


def test_computed_torque_on_the_reference_is_inverse_dynamics() -> None:
    dyn = dynamics("puma560")
    ref = armctl.Reference([0.1, 0.5, -0.3, 0.2, 0.4, 0.0], [0.2, -0.1, 0.3, 0.0, 0.5, -0.2], [1, 0, -1, 2, 0, 1])
    ct = ComputedTorque(dyn, kp=100, kd=20)
    assert np.allclose(ct(0.0, ref.q, ref.qd, ref), dyn.inverse_dynamics(ref.q, ref.qd, ref.qdd))
    # off the reference: M (q̈_d + K_d ė + K_p e) + C q̇ + g + τ_f
    q, qd = ref.q + 0.01, ref.qd - 0.02
    v = ref.qdd + 20 * (ref.qd - qd) + 100 * (ref.q - q)
    expected = (
        dyn.mass_matrix(q) @ v + dyn.coriolis_matrix(q, qd) @ qd + dyn.gravity_torque(q) + dyn.friction_torque(qd)
    )
    assert np.allclose(ct(0.0, q, qd, ref), expected)
    no_friction = ComputedTorque(dyn, kp=100, kd=20, friction=False)
    assert np.allclose(no_friction(0.0, q, qd, ref), expected - dyn.friction_torque(qd))
    feedforward = ComputedTorque(dyn, kp=100, kd=20, friction="reference")
    assert np.allclose(feedforward(0.0, q, qd, ref), expected - dyn.friction_torque(qd) + dyn.friction_torque(ref.qd))
    with pytest.raises(InvalidParameterError, match="friction"):
        ComputedTorque(dyn, 1.0, 1.0, friction="yes")


@pytest.mark.parametrize("gains", ["diagonal", "matrix", "friction", "integral"])
def test_pd_gravity_law(gains: str) -> None:
    # τ = g(q) + K_p e + K_d ė (+ τ_f(q̇)) (+ K_i ∫e), g straight from Pinocchio; puma560 has friction
    import pinocchio as pin

    dyn = dynamics("puma560")
    n = dyn.n
    q, qd = np.linspace(-0.4, 0.5, n), np.linspace(0.3, -0.2, n)
    ref = armctl.Reference(q + 0.05, qd + 0.1)
    kp, kd = np.arange(1.0, n + 1.0) * 50.0, 10.0
    kp_given = np.diag(kp) + (0.5 * np.eye(n)[::-1] + 0.5 * np.eye(n) if gains == "matrix" else 0.0)
    c = PDGravity(
        dyn,
        kp_given if gains == "matrix" else kp,
        kd,
        ki=2.0 if gains == "integral" else None,
        friction=gains == "friction",
    )
    pm = dyn.model.to_pinocchio()
    g = pin.computeGeneralizedGravity(pm, pm.createData(), q)
    expected = g + (kp_given if gains == "matrix" else np.diag(kp)) @ (ref.q - q) + kd * (ref.qd - qd)
    if gains == "friction":
        fr = [j.friction for j in dyn.model.joints]
        expected += np.array(
            [
                f.viscous * v
                + (f.coulomb if v > 0 else -(f.coulomb_negative if f.coulomb_negative is not None else f.coulomb))
                for f, v in zip(fr, qd, strict=True)
            ]
        )
    c(0.0, q, qd, ref)  # the integral starts its clock
    if gains == "integral":
        expected += 2.0 * 0.01 * (ref.q - q)
    np.testing.assert_allclose(c(0.01, q, qd, ref), expected, rtol=1e-12, atol=1e-9)


def test_the_first_call_only_starts_the_integral_clock() -> None:
    """A run whose first call is at t = 0.5 s (not 0): that call adds nothing to ∫e dt (ErrorIntegral's
    docstring), so τ = g(q) + K_p e + K_d ė; the next, 20 ms later, adds K_i e · 0.02. g from Pinocchio."""
    import pinocchio as pin

    dyn = dynamics("planar_2r")
    q, qd = np.array([0.1, 0.2]), np.array([0.3, -0.1])
    ref = armctl.Reference([0.3, -0.1], [0.1, 0.2])
    c = PDGravity(dyn, kp=100.0, kd=10.0, ki=50.0)
    pm = dyn.model.to_pinocchio()
    pd_law = pin.computeGeneralizedGravity(pm, pm.createData(), q) + 100.0 * (ref.q - q) + 10.0 * (ref.qd - qd)
    np.testing.assert_allclose(c(0.5, q, qd, ref), pd_law, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(c(0.52, q, qd, ref), pd_law + 50.0 * 0.02 * (ref.q - q), rtol=1e-12, atol=1e-9)


def _slotine_li(
    dyn: armctl.Dynamics, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference, lam: np.ndarray, kd: float | np.ndarray
) -> np.ndarray:
    """M q̈_r + C(q, q̇) q̇_r + g + F_v q̇_r + F_c±(q̇) − K_D s, friction straight from the model's joints."""
    qd_r, qdd_r = ref.qd - lam @ (q - ref.q), ref.qdd - lam @ (qd - ref.qd)
    fr = [j.friction for j in dyn.model.joints]
    fv = np.array([f.viscous for f in fr])
    fc = np.array(
        [
            f.coulomb if v > 0 else -(f.coulomb if f.coulomb_negative is None else f.coulomb_negative)
            for f, v in zip(fr, qd, strict=True)
        ]
    )
    kd_s = kd @ (qd - qd_r) if np.ndim(kd) == 2 else kd * (qd - qd_r)
    return (
        dyn.mass_matrix(q) @ qdd_r + dyn.coriolis_matrix(q, qd) @ qd_r + dyn.gravity_torque(q) + fv * qd_r + fc - kd_s
    )


def _off_reference(name: str) -> tuple[armctl.Dynamics, int, np.ndarray, np.ndarray, armctl.Reference]:
    """(dyn, n, q, q̇, ref): a state off the reference, joints moving both ways."""
    dyn = dynamics(name)
    n = dyn.n
    ref = armctl.Reference(np.full(n, 0.1), np.full(n, 0.2), np.full(n, -0.3))
    return dyn, n, np.full(n, 0.15), np.linspace(-0.3, 0.4, n), ref


# panda: no friction; puma560: rotors, viscous and asymmetric Coulomb friction
@pytest.mark.parametrize("name", ["panda", "puma560"])
def test_passivity_based_law(name: str) -> None:
    dyn, n, q, qd, ref = _off_reference(name)
    lam = np.diag(np.arange(1.0, n + 1.0))
    expected = _slotine_li(dyn, q, qd, ref, lam, 5.0)
    assert np.allclose(PassivityBased(dyn, lam, 5.0)(0.0, q, qd, ref), expected, rtol=1e-12, atol=1e-10)


def _spd(n: int, seed: int, scale: float) -> np.ndarray:
    """A symmetric positive definite gain that is not diagonal."""
    b = np.random.default_rng(seed).uniform(-1.0, 1.0, (n, n))
    return scale * (np.eye(n) + 0.1 * (b @ b.T))


def test_full_gain_matrices_in_every_joint_space_law() -> None:
    """Non-diagonal K_p, K_d, Λ, K_D: each law against its formula written out with the matrices."""
    dyn, n, q, qd, ref = _off_reference("puma560")
    kp, kd, lam, kd_pb = _spd(n, 1, 100.0), _spd(n, 2, 20.0), _spd(n, 3, 2.0), _spd(n, 4, 5.0)
    e, ed = ref.q - q, ref.qd - qd
    ct = ComputedTorque(dyn, kp, kd)
    expected = (
        dyn.mass_matrix(q) @ (ref.qdd + kd @ ed + kp @ e)
        + dyn.coriolis_matrix(q, qd) @ qd
        + dyn.gravity_torque(q)
        + dyn.friction_torque(qd)
    )
    np.testing.assert_allclose(ct(0.0, q, qd, ref), expected, rtol=1e-12, atol=1e-9)
    pd = PDGravity(dyn, kp, kd)
    np.testing.assert_allclose(pd(0.0, q, qd, ref), dyn.gravity_torque(q) + kp @ e + kd @ ed, rtol=1e-12, atol=1e-9)
    expected = _slotine_li(dyn, q, qd, ref, lam, kd_pb)
    np.testing.assert_allclose(PassivityBased(dyn, lam, kd_pb)(0.0, q, qd, ref), expected, rtol=1e-12, atol=1e-9)
    # the exact parameters (puma560's asymmetric Coulomb friction included, through Y's Coulomb column)
    ad = Adaptive(dyn, lam, kd_pb, gamma=1e-9)
    np.testing.assert_allclose(ad(0.0, q, qd, ref), expected, rtol=1e-12, atol=1e-9)
    s = qd - (ref.qd - lam @ (q - ref.q))
    np.testing.assert_allclose(ad.last_log["s"], s, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("name", ["panda", "puma560"])
def test_adaptive_with_exact_parameters_is_passivity_based(name: str) -> None:
    dyn, n, q, qd, ref = _off_reference(name)
    ad = Adaptive(dyn, 3.0, 5.0, gamma=0.0 + 1e-9)
    assert np.allclose(ad(0.0, q, qd, ref), _slotine_li(dyn, q, qd, ref, 3.0 * np.eye(n), 5.0), rtol=1e-12, atol=1e-10)
    assert np.allclose(ad.last_log["theta"], dyn.model.parameters())


def _full_gain(p: int) -> np.ndarray:
    b = np.random.default_rng(4).uniform(-1.0, 1.0, (p, p))
    return 0.5 * np.eye(p) + 0.01 * (b @ b.T)  # symmetric positive definite, not diagonal


@pytest.mark.parametrize("gamma", [0.5, np.linspace(0.1, 1.0, 26), _full_gain(26)], ids=["scalar", "diagonal", "full"])
def test_adaptive_update_is_the_gradient_law(gamma: object) -> None:
    """θ̂(t+dt) = θ̂ − dt Γ Yᵀ s, step after step, with a jittering dt (a loop that measures its time)."""
    dyn = dynamics("planar_2r")
    ref = armctl.Reference([0.3, -0.2], [0.1, 0.0], [0.0, 0.5])
    ad = Adaptive(dyn, 2.0, 10.0, gamma=gamma, theta0=np.zeros(26))
    g = np.diag(np.broadcast_to(gamma, 26)) if np.ndim(gamma) < 2 else np.asarray(gamma)
    rng = np.random.default_rng(9)
    t, theta, logs = 0.0, np.zeros(26), []
    for k in range(6):
        q, qd = np.array([0.35, -0.1]) + 0.01 * k, np.array([0.0, 0.2]) - 0.02 * k
        ad(t, q, qd, ref)
        logs.append((ad.last_log["theta"], ad.last_log["theta"].copy()))
        s = ad.last_log["s"]
        y = dyn.passivity_regressor(q, qd, ref.qd - 2.0 * (q - ref.q), ref.qdd - 2.0 * (qd - ref.qd))
        dt = 0.01 * (1.0 + 1e-6 * rng.standard_normal())
        t += dt
        theta = theta - dt * g @ (y.T @ s)  # the law, for the next step's θ̂ (at t + dt, on this state's s)
        ad(t, q, qd, ref)
        assert np.allclose(ad.last_log["theta"], theta, rtol=1e-8, atol=1e-12)
        ad.theta = theta.copy()  # a new array: assigned, not changed in place
    for logged, kept in logs:  # θ̂ is replaced each step, so a kept log never changes
        assert np.array_equal(logged, kept)
    ad.reset()
    assert np.allclose(ad.theta, 0)


def test_adaptive_update_with_sigma_and_composite_terms_is_the_written_law() -> None:
    """θ̂⁺ = (I + κ dt Γ W_fᵀW_f)⁻¹ [θ̂ − dt Γ (Yᵀs + σ(θ̂ − θ₀) − κ W_fᵀτ_f)], written out here with a full
    solve (the controller uses Woodbury), and the first-order filters x_f ← x_f + (1 − e^{−ω dt})(x − x_f) of
    W = Y(q, q̇, Δq̇/dt) and of the previous call's torque, started at their first values."""
    dyn = dynamics("planar_2r")
    ref = armctl.Reference([0.3, -0.2], [0.1, 0.0], [0.0, 0.5])
    lam, kd, gamma, sigma, kappa, omega, dt = 2.0, 10.0, 0.5, 0.3, 4.0, 20.0, 0.01
    theta0 = dyn.parameters() * 0.8
    ad = Adaptive(dyn, lam, kd, gamma=gamma, theta0=theta0, sigma=sigma, composite=kappa, filter_bandwidth=omega)
    theta, w_f, tau_f, qd_prev, tau_prev = theta0.copy(), None, None, None, None
    a = 1.0 - math.exp(-omega * dt)
    for k in range(6):
        t = k * dt
        q, qd = np.array([0.35, -0.1]) + 0.01 * k, np.array([0.0, 0.2]) - 0.03 * k
        qd_r = ref.qd - lam * (q - ref.q)
        s = qd - qd_r
        y = dyn.passivity_regressor(q, qd, qd_r, ref.qdd - lam * (qd - ref.qd))
        if k > 0:
            w = dyn.regressor(q, qd, (qd - qd_prev) / dt)
            w_f = w if w_f is None else w_f + a * (w - w_f)
            tau_f = tau_prev.copy() if tau_f is None else tau_f + a * (tau_prev - tau_f)
            grad = y.T @ s + sigma * (theta - theta0) - kappa * w_f.T @ tau_f
            lhs = np.eye(26) + kappa * dt * gamma * w_f.T @ w_f
            theta = np.linalg.solve(lhs, theta - dt * gamma * grad)
        tau = ad(t, q, qd, ref)
        np.testing.assert_allclose(ad.theta, theta, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(tau, y @ theta - kd * s, rtol=1e-9, atol=1e-9)
        qd_prev, tau_prev = qd, tau
    assert np.abs(theta - theta0).max() > 1e-3  # the terms moved θ̂: the comparison is not of two θ₀


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-5, 5), min_size=26, max_size=26))
def test_projection_is_physical_and_idempotent(values: list[float]) -> None:
    p = project_physical(np.array(values))
    assert is_physical(p)
    assert np.allclose(project_physical(p), p, atol=1e-9)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-5, 5), min_size=26, max_size=26))
def test_projection_is_the_nearest_psd_pseudo_inertia(values: list[float]) -> None:
    """The optimality conditions of the Frobenius-nearest PSD matrix P to J, checked link by link: P ⪰ 0,
    P − J ⪰ 0 (only negative eigen-directions of J are removed) and P (P − J) = 0 (complementarity)."""
    from armctl.model.consistency import pseudo_inertia

    pi = np.array(values)
    for k in range(2):
        j = pseudo_inertia(pi[13 * k : 13 * k + 10])
        proj = pseudo_inertia(project_physical(pi)[13 * k : 13 * k + 10])
        scale = 1.0 + np.abs(j).max()
        assert np.linalg.eigvalsh(proj).min() >= -1e-9 * scale
        assert np.linalg.eigvalsh(proj - j).min() >= -1e-9 * scale
        assert np.abs(proj @ (proj - j)).max() <= 1e-9 * scale**2
    assert (project_physical(pi).reshape(2, 13)[:, 10:] >= 0).all()
    # the two ways in (a Cholesky test first, or the eigendecomposition straight away) agree to rounding (on
    # the boundary of the set one may accept what the other moves by ~1e-15), and each says whether it changed π
    (a, changed_a), (b, changed_b) = projection(pi), projection(pi, likely_inside=False)
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * scale)
    assert changed_a == (not np.array_equal(a, pi)) and changed_b == (not np.array_equal(b, pi))


def test_projection_refuses_non_finite_parameters() -> None:
    pi = dynamics("panda").model.parameters().copy()
    pi[3] = np.nan
    with pytest.raises(NonFiniteError, match="NaN or inf"):
        project_physical(pi)
    pi[3] = np.inf
    assert not is_physical(pi)


def test_projection_on_the_boundary_agrees_both_ways() -> None:
    """A point mass (rank-1 pseudo-inertia, on the boundary of the set): the Cholesky shortcut and the
    eigendecomposition may disagree on 'changed' by rounding, not on the result."""
    from armctl.model.consistency import from_pseudo_inertia, pseudo_inertia

    v = np.array([0.1, 0.2, 0.3, 1.0])
    pi = np.concatenate([from_pseudo_inertia(1.3 * np.outer(v, v)), [0.0, 0.0, 0.0]])
    a, b = projection(pi)[0], projection(pi, likely_inside=False)[0]
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-14)
    assert is_physical(a) and is_physical(b)
    with pytest.raises(ShapeError, match="10 entries"):
        pseudo_inertia(np.ones(13))
    with pytest.raises(ShapeError, match="4×4"):
        from_pseudo_inertia(np.ones(16))


def test_projection_leaves_physical_parameters_alone() -> None:
    pi = dynamics("panda").model.parameters()
    assert is_physical(pi) and np.allclose(project_physical(pi), pi)
    assert not is_physical(armctl.models.puma560().parameters())  # Corke's published links 1 and 3


class Zero(Controller):
    def compute(self, t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        return np.zeros(self.n)


def test_bad_input() -> None:
    dyn = dynamics("panda")
    for bad, err in [
        ((-1.0,), InvalidParameterError),
        ((np.ones(6),), ShapeError),
        ((np.nan,), NonFiniteError),
        ((np.array([[1.0, 2.0], [0.0, 1.0]]),), ShapeError),
    ]:
        with pytest.raises(err):
            PDGravity(dyn, *bad, 1.0)
    with pytest.raises(InvalidParameterError, match="positive definite"):
        ComputedTorque(dyn, np.diag([1, 1, 1, 1, 1, 1, -1.0]), 1.0)
    with pytest.raises(InvalidParameterError, match="symmetric"):
        PassivityBased(dyn, np.triu(np.ones((7, 7))), 1.0)
    ct = ComputedTorque(dyn, 1.0, 1.0)
    with pytest.raises(ShapeError, match="reference has 2 joints"):
        ct(0.0, np.zeros(7), np.zeros(7), armctl.Reference([0.0, 0.0]))
    with pytest.raises(NonFiniteError, match="qd"):
        ct(0.0, np.zeros(7), [np.nan] * 7, REF7)
    with pytest.raises(InvalidParameterError, match="Reference"):
        ct(0.0, np.zeros(7), np.zeros(7), np.zeros(7))  # type: ignore[arg-type]
    with pytest.raises(ShapeError, match="theta0"):
        Adaptive(dyn, 1.0, 1.0, 1.0, theta0=np.zeros(5))
    with pytest.raises(InvalidParameterError, match="projection must be True or False, got 'False'"):
        Adaptive(dyn, 1.0, 1.0, 1.0, projection="False")  # bool("False") is True
    ad = Adaptive(dyn, 1.0, 1.0, 1.0, projection=True)
    with pytest.raises(InvalidParameterError, match="projection must be True or False"):
        ad.projection = 1
    assert pickle.loads(pickle.dumps(ad)).projection is True
    with pytest.raises(InvalidParameterError, match="needs n"):
        Zero(None)
    assert np.array_equal(Zero(n=3)(0.0, np.zeros(3), np.zeros(3), armctl.Reference(np.zeros(3))), np.zeros(3))


def test_the_physical_projection_is_not_the_lyapunov_metrics() -> None:
    """A limit shown, not hidden: ``project_physical`` is the nearest consistent point in the Frobenius norm of
    each link's pseudo-inertia J, while the adaptive law's V = ½sᵀMs + ½θ̃ᵀΓ⁻¹θ̃ measures θ̃ in Γ⁻¹ (Euclidean
    for a scalar Γ). A projection can move θ̂ towards the true π in the first and away from it in the second,
    so V may rise at a projection (the docstring of ``Adaptive`` says so). Here the distances are computed
    from J built independently of the module's own map, by the definition J = ∫ [r; 1][r; 1]ᵀ dm."""
    from armctl.model.consistency import is_physical, project_physical

    pi = dynamics("planar_2r").parameters()
    theta = pi + np.random.default_rng(0).normal(0.0, 5.0, (2, 26))[1]
    projected = project_physical(theta)
    assert not is_physical(theta) and is_physical(projected) and is_physical(pi)

    def pseudo(link: np.ndarray) -> np.ndarray:  # from (m, m c, I about the frame origin: xx, xy, yy, xz, yz, zz)
        m, h = link[0], link[1:4]
        ixx, ixy, iyy, ixz, iyz, izz = link[4:10]
        inertia = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
        sigma = 0.5 * np.trace(inertia) * np.eye(3) - inertia  # ∫ r rᵀ dm
        return np.block([[sigma, h[:, None]], [h[None, :], np.array([[m]])]])

    def j_distance(x: np.ndarray) -> float:
        d = (x - pi).reshape(2, 13)
        return float(np.sqrt(sum(np.linalg.norm(pseudo(v[:10])) ** 2 + v[10:] @ v[10:] for v in d)))

    assert j_distance(projected) < j_distance(theta)  # nearer in the projection's own metric
    assert np.linalg.norm(projected - pi) > np.linalg.norm(theta - pi)  # farther in V's (Γ scalar)


@pytest.mark.parametrize("gamma", ["scalar", "diagonal", "full"])
def test_adaptive_logs_the_lyapunov_function_of_its_plant(gamma: str) -> None:
    """V = ½ sᵀM s + ½ θ̃ᵀΓ⁻¹θ̃ with a plant the controller's model differs from (a payload): M and π are the
    plant's (given as a RobotModel), Γ⁻¹ formed here by inverting Γ (scalar, diagonal or full)."""
    ctrl_dyn = dynamics("planar_2r")
    plant = ctrl_dyn.model.with_payload(0.7, (0.05, 0.0, 0.0))
    rng = np.random.default_rng(4)
    g = {
        "scalar": 3.0,
        "diagonal": rng.uniform(0.5, 4.0, 26),
        "full": (lambda a: a @ a.T + np.eye(26))(rng.standard_normal((26, 26))),
    }[gamma]
    g_inv = np.linalg.inv(np.diag(np.broadcast_to(g, 26)) if np.ndim(g) < 2 else g)
    ad = Adaptive(ctrl_dyn, 2.0, 10.0, g, plant=plant)
    pi = plant.parameters()
    assert not np.allclose(pi, ctrl_dyn.parameters())
    ref = armctl.Reference([0.3, -0.2], [0.1, 0.0], [0.0, 0.5])
    for k, t in enumerate((0.0, 0.01, 0.02)):
        q, qd = np.array([0.35, -0.1]) + 0.01 * k, np.array([0.0, 0.2])
        ad(t, q, qd, ref)
        s, err = ad.last_log["s"], ad.last_log["theta"] - pi
        m = armctl.Dynamics(plant).mass_matrix(q)
        assert ad.last_log["V"] == pytest.approx(0.5 * s @ m @ s + 0.5 * err @ g_inv @ err, rel=1e-9)
    plain = Adaptive(ctrl_dyn, 2.0, 10.0, 3.0)
    plain(0.0, q, qd, ref)
    assert "V" not in plain.last_log


def test_adaptive_plant_checks() -> None:
    ctrl_dyn = dynamics("planar_2r")
    with pytest.raises(ShapeError, match="plant has 3 joints, the controller 2"):
        Adaptive(ctrl_dyn, 2.0, 10.0, 1.0, plant=armctl.models.planar_3r())
    with pytest.raises(InvalidParameterError, match=r"plant must be an armctl\.Dynamics"):
        Adaptive(ctrl_dyn, 2.0, 10.0, 1.0, plant="planar_2r")
    with pytest.raises(InvalidParameterError, match="set plant="):
        Adaptive(ctrl_dyn, 2.0, 10.0, 1.0).lyapunov([0.1, 0.2], [0.0, 0.0])
