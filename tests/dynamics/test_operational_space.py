"""The operational-space model and the dynamic manipulability ellipsoid against independent references:
the Robotics Toolbox's published Λ of the Puma 560, the joint-space dynamics on random states (the frame's
acceleration by finite differences of its velocity along the motion), and the planar two-link arm's closed form
(Siciliano et al., *Robotics: Modelling, Planning and Control*, 2009, §7.3.2 and §7.9)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import armctl
from armctl.dynamics.operational_space import frame_drift, task_rows
from armctl.errors import InvalidParameterError, SingularConfigurationError
from armctl.model import Joint, Link
from tests.conftest import dynamics, model

# Λ of the Puma 560 at qn = (0, π/4, π, 0, π/4, 0) from Peter Corke's Robotics Toolbox for Python,
# tests/test_DHRobot.py, TestDHRobot.test_inertia_x (`puma.inertia_x(puma.qn, representation=None)`, the
# geometric Jacobian), https://github.com/petercorke/robotics-toolbox-python
RTB_PUMA_INERTIA_X = [
    [17.2954, -2.7542, -9.6233, -0.0000, 0.2795, 0.0000],
    [-2.7542, 12.1909, 1.2459, -0.3254, -0.0703, -0.9652],
    [-9.6233, 1.2459, 13.3348, -0.0000, 0.2767, -0.0000],
    [-0.0000, -0.3254, -0.0000, 0.1941, 0.0000, 0.1941],
    [0.2795, -0.0703, 0.2767, 0.0000, 0.1713, 0.0000],
    [0.0000, -0.9652, -0.0000, 0.1941, 0.0000, 0.5791],
]


@pytest.mark.parametrize("q3", [math.pi, -math.pi])  # the toolbox's qn, and the library's PUMA_QN (same pose)
def test_puma_lambda_equals_the_robotics_toolbox(q3: float) -> None:
    q = np.array([0.0, math.pi / 4, q3, 0.0, math.pi / 4, 0.0])
    osm = dynamics("puma560").operational_space_model(q, np.zeros(6))
    np.testing.assert_allclose(osm.Lambda, RTB_PUMA_INERTIA_X, atol=0.6e-4)


def _frame_acceleration(dyn: armctl.Dynamics, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, frame: str | None):
    """d/dt (J q̇) along q(t) = q + t q̇ + ½ t² q̈, by a central difference of step 1e-6 s."""
    h = 1e-6

    def velocity(t: float) -> np.ndarray:
        return dyn.jacobian(q + t * qd + 0.5 * t * t * qdd, frame) @ (qd + t * qdd)

    return (velocity(h) - velocity(-h)) / (2 * h)


@pytest.mark.parametrize(
    ("name", "backend"), [("panda", "pinocchio"), ("puma560", "pinocchio"), ("puma560", "lagrange")]
)
@settings(max_examples=8, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_the_model_reproduces_the_joint_space_dynamics(name: str, backend: str, seed: int) -> None:
    """Λ ẍ + μ + p = J̄ᵀ τ for any torque τ (null-space torques of the redundant Panda included), with ẍ the
    frame's acceleration under the joint-space forward dynamics; and J J̄ = I, Λ symmetric positive definite."""
    m = model(name).reduced(friction=False)
    dyn = armctl.Dynamics(m, backend=backend)
    rng = np.random.default_rng(seed)
    lo, hi = np.maximum(m.lower, -2.5), np.minimum(m.upper, 2.5)
    q = lo + (hi - lo) * rng.random(m.n)
    qd = rng.uniform(-1.5, 1.5, m.n)
    tau = rng.uniform(-10, 10, m.n)
    try:
        osm = dyn.operational_space_model(q, qd)
    except SingularConfigurationError:  # a random pose near a wrist singularity: nothing to compare
        return
    qdd = dyn.forward_dynamics(q, qd, tau)
    xdd = _frame_acceleration(dyn, q, qd, qdd, None)
    lhs = osm.Lambda @ xdd + osm.mu + osm.p
    rhs = osm.Jbar.T @ tau
    scale = np.abs(osm.Lambda).max() * (np.abs(xdd).max() + 1) + np.abs(rhs).max()
    assert np.abs(lhs - rhs).max() <= 1e-6 * scale
    # J J̄ = J M⁻¹ Jᵀ Λ = I to rounding, which grows with Λ's condition number near a singularity
    np.testing.assert_allclose(osm.jacobian @ osm.Jbar, np.eye(6), atol=max(1e-8, 1e-14 * np.linalg.cond(osm.Lambda)))
    np.testing.assert_allclose(osm.Lambda, osm.Lambda.T, atol=0)
    assert np.linalg.eigvalsh(osm.Lambda).min() > 0
    assert np.allclose(osm.acceleration(osm.Jbar.T @ tau), xdd, rtol=1e-5, atol=1e-6 * np.abs(xdd).max())


def test_position_rows_and_the_drift() -> None:
    """rows="position": a 3×3 model of the frame origin; J̇ q̇ is the derivative of J along q̇ (central differences
    of the Jacobian, step 1e-6)."""
    dyn = dynamics("panda")
    q = np.array([0.1, -0.3, 0.2, -1.8, 0.1, 1.4, 0.5])
    qd = np.array([0.4, -0.2, 0.3, 0.5, -0.6, 0.2, 0.9])
    full = dyn.operational_space_model(q, qd)
    pos = dyn.operational_space_model(q, qd, rows="position")
    assert pos.Lambda.shape == (3, 3) and pos.Jbar.shape == (7, 3) and pos.rows == (0, 1, 2)
    j = dyn.jacobian(q)
    np.testing.assert_allclose(np.linalg.inv(pos.Lambda), j[:3] @ np.linalg.solve(dyn.mass_matrix(q), j[:3].T))
    s = 1e-6
    drift = (dyn.jacobian(q + s * qd) - dyn.jacobian(q - s * qd)) @ qd / (2 * s)
    np.testing.assert_allclose(frame_drift(dyn, q, qd), drift, atol=1e-7)
    np.testing.assert_allclose(full.drift, drift, atol=1e-7)
    # another frame, on the Lagrange backend (its own Pinocchio model for the drift)
    lag = dynamics("planar_3r", "lagrange")
    q3, qd3 = np.array([0.2, 0.7, -0.4]), np.array([1.0, -0.5, 0.8])
    d3 = (lag.jacobian(q3 + s * qd3, "joint3") - lag.jacobian(q3 - s * qd3, "joint3")) @ qd3 / (2 * s)
    np.testing.assert_allclose(frame_drift(lag, q3, qd3, "joint3"), d3, atol=1e-7)


# ------------------------------------------------------------------------------------ the planar 2R arm
A1 = A2 = 1.0


def siciliano_2r(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(J, B) of Siciliano's two-link arm: the tip's (x, z) Jacobian and the closed-form inertia matrix (§7.3.2;
    a = 1 m, ℓ = 0.5 m, m_l = 50 kg, I_l = 10 kg·m², k_r = 100, I_m = 0.01 kg·m², m_m = 5 kg)."""
    a, ell, ml, il, kr, im, mm = 1.0, 0.5, 50.0, 10.0, 100.0, 0.01, 5.0
    s1, c1, s12, c12, c2 = np.sin(q[0]), np.cos(q[0]), np.sin(q[0] + q[1]), np.cos(q[0] + q[1]), np.cos(q[1])
    jac = np.array([[-A1 * s1 - A2 * s12, -A2 * s12], [A1 * c1 + A2 * c12, A2 * c12]])
    b11 = il + ml * ell**2 + kr**2 * im + il + ml * (a**2 + ell**2 + 2 * a * ell * c2) + im + mm * a**2
    b12 = il + ml * (ell**2 + a * ell * c2) + kr * im
    b22 = il + ml * ell**2 + kr**2 * im
    return jac, np.array([[b11, b12], [b12, b22]])


@pytest.mark.parametrize("q", [[0.3, 1.0], [-1.2, 2.4], [2.0, -0.7]])
def test_two_link_ellipsoid_matches_the_closed_form(q: list[float]) -> None:
    """Axes and lengths of the ellipsoid {J B⁻¹ τ : ‖τ‖ ≤ 1}: the eigenvectors and the square roots of the
    eigenvalues of A Aᵀ, A = J B⁻¹, for the 2×2 closed form ((t ± √(t² − 4 det²))/2, t = tr A Aᵀ); the measure
    |det J| / det B; and Λ = (J B⁻¹ Jᵀ)⁻¹ = J⁻ᵀ B J⁻¹ (J square)."""
    dyn = dynamics("planar_2r", "lagrange")  # with the rotor coupling of the textbook's model
    qv = np.array(q)
    jac, b = siciliano_2r(qv)
    a = jac @ np.linalg.inv(b)
    aat = a @ a.T
    t, det = np.trace(aat), np.linalg.det(a)
    root = math.sqrt(t * t - 4 * det * det)
    lengths = np.sqrt([(t + root) / 2, (t - root) / 2])
    major = np.array([aat[0, 1], lengths[0] ** 2 - aat[0, 0]])  # (A Aᵀ − σ₁² I) v = 0
    major /= np.linalg.norm(major)
    ell = dyn.dynamic_manipulability(qv, rows="xz")
    np.testing.assert_allclose(ell.lengths, lengths, rtol=1e-10)
    assert abs(abs(ell.axes[:, 0] @ major) - 1) < 1e-10
    assert abs(ell.axes[:, 0] @ ell.axes[:, 1]) < 1e-12
    assert ell.measure == pytest.approx(abs(np.linalg.det(jac)) / np.linalg.det(b), rel=1e-10)
    assert ell.isotropy == pytest.approx(lengths[1] / lengths[0])
    osm = dyn.operational_space_model(qv, np.zeros(2), rows="xz")
    j_inv = np.linalg.inv(jac)
    np.testing.assert_allclose(osm.Lambda, j_inv.T @ b @ j_inv, rtol=1e-10)


def test_torque_scale() -> None:
    """With torque scales s the ellipsoid is the image of diag(s) times the unit ball."""
    dyn = dynamics("planar_3r")
    q = np.array([0.4, -0.9, 1.3])
    s = np.array([200.0, 120.0, 40.0])
    scaled = dyn.dynamic_manipulability(q, rows=("x", "z"), torque_scale=s)
    a = dyn.jacobian(q)[[0, 2]] @ np.linalg.solve(dyn.mass_matrix(q), np.diag(s))
    np.testing.assert_allclose(scaled.lengths, np.linalg.svd(a, compute_uv=False), rtol=1e-12)
    limits = dyn.dynamic_manipulability(q, rows="xz", torque_scale="limits")  # 200 N·m on every joint
    unit = dyn.dynamic_manipulability(q, rows="xz")
    np.testing.assert_allclose(limits.lengths, 200.0 * unit.lengths, rtol=1e-12)
    with pytest.raises(InvalidParameterError, match="torque_scale"):
        dyn.dynamic_manipulability(q, torque_scale=[1.0, 0.0, 1.0])
    free = armctl.RobotModel(
        (Joint("turn", "revolute", (0.0, 0.0, 1.0), np.eye(4), Link(1.0, (0.3, 0, 0), np.eye(3) * 0.01)),),
        name="no effort limit",
    )
    with pytest.raises(InvalidParameterError, match="effort limits"):
        armctl.Dynamics(free).dynamic_manipulability([0.0], rows="x", torque_scale="limits")


def test_singular_configurations_are_named() -> None:
    dyn = dynamics("planar_2r")
    with pytest.raises(SingularConfigurationError, match="singular") as info:
        dyn.operational_space_model([0.3, 0.0], [0.0, 0.0], rows="xz")  # stretched
    assert info.value.sigma_min < 1e-12 and "rows" in str(info.value)
    assert isinstance(info.value, ValueError)
    with pytest.raises(SingularConfigurationError, match="rank 2 of 6"):
        dyn.operational_space_model([0.3, 1.0], [0.0, 0.0])  # six rows on a planar arm
    ok = dyn.operational_space_model([0.3, 1e-3], [0.0, 0.0], rows="xz", singular_tolerance=1e-9)
    assert np.linalg.eigvalsh(ok.Lambda).max() > 1e5  # near the singularity Λ grows as 1/σ²


def test_rows() -> None:
    assert task_rows("pose") == (0, 1, 2, 3, 4, 5)
    assert task_rows("xz") == (0, 2)
    assert task_rows(("x", "wz")) == (0, 5)
    assert task_rows([1, 4]) == (1, 4)
    for bad in ("xx", "pos", [0, 0], [6], [True], []):
        with pytest.raises(InvalidParameterError):
            task_rows(bad)  # type: ignore[arg-type]


def test_plot_along_a_path() -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Ellipse

    from armctl.dynamics.manipulability_plot import plot_dynamic_manipulability

    dyn = dynamics("planar_2r")
    path = np.column_stack([np.linspace(-0.3, 1.2, 6), np.linspace(2.2, 0.4, 6)])
    ax = plot_dynamic_manipulability(dyn, path)
    ellipses = [p for p in ax.patches if isinstance(p, Ellipse)]
    assert len(ellipses) == 6
    tip = dyn.frame_pose(path[0])[:3, 3]
    assert ellipses[0].center == pytest.approx((tip[0], tip[2]))
    plt.close(ax.figure)
    with pytest.raises(InvalidParameterError, match="two position rows"):
        plot_dynamic_manipulability(dyn, path, rows="pose")


def test_the_damped_terms_are_the_inverse_of_the_shifted_task_space_inverse_inertia() -> None:
    """operational_space_terms with damping δ²: Λ = (J M⁻¹ Jᵀ + δ² I)⁻¹ (numpy), J̄ = M⁻¹ Jᵀ Λ, J J̄ = I − δ² Λ,
    μ and p from them; δ² = 0 gives the exact terms."""
    from armctl.dynamics.operational_space import operational_space_terms

    dyn = dynamics("panda")
    rng = np.random.default_rng(2)
    q, qd = rng.uniform(-1.0, 1.0, 7), rng.normal(size=7)
    mass, jac = dyn.mass_matrix(q), dyn.jacobian(q)
    drift, cq, g = frame_drift(dyn, q, qd), dyn.coriolis_matrix(q, qd) @ qd, dyn.gravity_torque(q)
    lam_inv = jac @ np.linalg.solve(mass, jac.T)
    for damping in (0.0, 1e-3, 0.5):
        lam, jbar, mu, p = operational_space_terms(mass, jac, drift, cq, g, damping)
        ref = np.linalg.inv(lam_inv + damping * np.eye(6))
        np.testing.assert_allclose(lam, ref, rtol=1e-9, atol=1e-12 * np.abs(ref).max())
        np.testing.assert_allclose(jbar, np.linalg.solve(mass, jac.T) @ ref, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(jac @ jbar, np.eye(6) - damping * ref, atol=1e-9)
        np.testing.assert_allclose(mu, jbar.T @ cq - ref @ drift, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(p, jbar.T @ g, rtol=1e-9, atol=1e-9)
