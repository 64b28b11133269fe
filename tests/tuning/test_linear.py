"""Linearisation and gains against closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

import armctl
from armctl.errors import InvalidParameterError
from armctl.tuning import closed_loop_poles, linearize, lqr_gains, pd_from_bandwidth
from tests.helpers.arms import dynamics


def test_pendulum_linearisation_is_the_textbook_one() -> None:
    """About q₀: J δq̈ + F_v δq̇ + m g ℓ cos(q₀) δq = δτ, J = I_c + mℓ² + k_r² I_m."""
    m, length, f_v = 2.0, 0.5, 0.05
    ell = length / 2
    j = m * length**2 / 12 + m * ell**2 + 50.0**2 * 5e-5
    for q0 in (0.0, 0.7, math.pi):
        sys = linearize(dynamics("pendulum"), [q0])
        expected = np.array([[0, 1], [-m * 9.81 * ell * math.cos(q0) / j, -f_v / j]])
        assert np.allclose(sys.A, expected, rtol=1e-6, atol=1e-8)
        assert np.allclose(sys.B, [[0], [1 / j]])
    assert (np.linalg.eigvals(linearize(dynamics("pendulum"), [math.pi]).A).real > 0).any()  # upright: unstable


def test_planar_2r_linearisation_against_pinocchio() -> None:
    """Two joints, distinct viscous frictions, q₀ off the vertical: A = [[0, I], [−M⁻¹ ∂g/∂q, −M⁻¹ F_v]] and
    B = [0; M⁻¹] with M from Pinocchio's CRBA and ∂g/∂q from its gravity derivatives (M is not diagonal, so the
    order of the products matters); the output is δq, so the static gain from δτ is (∂g/∂q)⁻¹ (δτ = ∂g/∂q δq)."""
    import pinocchio as pin

    model = armctl.models.planar_2r().with_friction(viscous=[3.0, 0.5])
    pm = model.to_pinocchio()
    data = pm.createData()
    q0 = np.array([-1.2, 0.7])
    m = pin.crba(pm, data, q0).copy()
    m = np.triu(m) + np.triu(m, 1).T  # CRBA fills the upper triangle
    dg = pin.computeGeneralizedGravityDerivatives(pm, data, q0).copy()
    fv, m_inv, eye, zero = np.diag([3.0, 0.5]), np.linalg.inv(m), np.eye(2), np.zeros((2, 2))
    assert not np.allclose(m_inv @ dg, dg @ m_inv) and not np.allclose(m_inv @ fv, fv @ m_inv)
    sys = linearize(armctl.Dynamics(model), q0)
    a = np.block([[zero, eye], [-m_inv @ dg, -m_inv @ fv]])
    np.testing.assert_allclose(sys.A, a, rtol=1e-6, atol=1e-6 * np.abs(a).max())
    np.testing.assert_allclose(sys.B, np.vstack([zero, m_inv]), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(sys.dcgain(), np.linalg.inv(dg), rtol=1e-6)


def test_gains() -> None:
    kp, kd = pd_from_bandwidth(10.0, 0.7)
    assert (kp, kd) == pytest.approx((100.0, 14.0))
    assert np.abs(closed_loop_poles(kp, kd)) == pytest.approx([10.0, 10.0])
    # LQR for ë = v with weights q_p, q_v, r: K_p = √(q_p/r), K_d = √(q_v/r + 2 K_p) (Riccati by hand)
    kp, kd = lqr_gains(100.0, 4.0, 1.0)
    assert kp == pytest.approx(10.0) and kd == pytest.approx(math.sqrt(4.0 + 20.0))


@pytest.mark.parametrize(("qp", "qv", "r"), [(1.0, 0.0, 1.0), (100.0, 4.0, 0.5), (1e8, 1e3, 1e-2), (3.0, 0.0, 7.0)])
def test_lqr_gains_are_python_controls_riccati_solution(qp: float, qv: float, r: float) -> None:
    import control

    k = control.lqr(np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([[0.0], [1.0]]), np.diag([qp, qv]), [[r]])[0]
    assert lqr_gains(qp, qv, r) == pytest.approx((k[0, 0], k[0, 1]), rel=1e-9)


def test_lqr_gains_at_extreme_weights() -> None:
    """Only the ratios of the weights matter: r = 1e-16 with q_p = 1 is q_p = 1e16 with r = 1, which
    python-control solves (at r = 1e-16 itself it returns K = 0)."""
    import control

    k = control.lqr(np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([[0.0], [1.0]]), np.diag([1e16, 0.0]), [[1.0]])[0]
    assert k[0, 0] > 1e7  # the reference itself is sound
    assert lqr_gains(1.0, 0.0, 1e-16) == pytest.approx((k[0, 0], k[0, 1]), rel=1e-9)
    with pytest.raises(InvalidParameterError, match="beyond floating point"):
        lqr_gains(1e300, 0.0, 1e-300)


def test_gains_and_steps_beyond_floating_point_are_named() -> None:
    from armctl.tuning.sampled import SampledDataAnalysis, spectral_radius

    dyn = armctl.Dynamics(armctl.models.planar_2r())
    with pytest.raises(InvalidParameterError, match=r"omega_n = 1e\+200 rad/s .* beyond floating point"):
        pd_from_bandwidth(1e200)  # K_p = inf
    with pytest.raises(InvalidParameterError, match="beyond floating point"):
        pd_from_bandwidth(1e-300, 1e-300)  # K_p = 0
    for step in (1e-300, 1e3):  # q₀ ± 1e-300 rounds to q₀: ∂g/∂q would be exactly 0
        with pytest.raises(InvalidParameterError, match=r"step must be in \[1e-10, 0.1\] rad"):
            linearize(dyn, [0.1, 0.2], step=step)
    with pytest.raises(InvalidParameterError, match=r"cannot be analysed in floating point: K_p T² = inf"):
        spectral_radius(400.0, 40.0, 1e200)
    with pytest.raises(InvalidParameterError, match=r"K_p T² = 1e\+294"):
        SampledDataAnalysis.of(1e300, 1e150, 1e-3)
