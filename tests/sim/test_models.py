"""Friction and normal-force laws against their closed forms, and their derivatives (used by the implicit
schemes) against finite differences."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import armctl
from armctl.errors import UnknownNameError
from armctl.sim import HuntCrossley, KelvinVoigt, Plane, SmoothFriction, StickSlip
from armctl.sim.friction import make_friction, stribeck_curve

MODEL = armctl.models.planar_2r().with_friction(
    viscous=[2.0, 1.0], coulomb=[5.0, 3.0], coulomb_negative=[4.0, 3.0], static=[7.0, 3.5], stribeck_velocity=[0.1, 0.0]
)


def test_smooth_friction_is_tanh_times_the_stribeck_level() -> None:
    fr = SmoothFriction(MODEL, velocity=0.02)
    for v1, v2 in [(0.3, -0.05), (-0.2, 1e-3), (0.0, 0.0)]:
        level1 = (5.0 if v1 > 0 else 4.0) + ((7.0 - (5.0 if v1 > 0 else 4.0)) * math.exp(-((v1 / 0.1) ** 2)))
        expected = [2.0 * v1 + math.tanh(v1 / 0.02) * level1, 1.0 * v2 + math.tanh(v2 / 0.02) * 3.0]
        np.testing.assert_allclose(fr.torque(np.array([v1, v2])), expected, rtol=1e-12, atol=1e-15)


def test_stick_slip_kinetic_torque_is_the_stribeck_curve() -> None:
    fr = StickSlip(MODEL)
    v = np.array([0.05, -0.4])
    tau = fr.torque(v, np.sign(v))
    assert tau[0] == pytest.approx(stribeck_curve(0.05, 5.0, 7.0, 0.1, 2.0))
    assert tau[1] == pytest.approx(-(0.4 * 1.0 + 3.0))  # no Stribeck hump without v_s
    np.testing.assert_array_equal(fr.capable, [True, True])
    assert fr.breakaway_pos.tolist() == [7.0, 3.5] and fr.breakaway_neg.tolist() == [7.0, 3.5]
    assert not StickSlip(MODEL, stribeck=False).has_stribeck


@settings(max_examples=40, deadline=None)
@given(v=st.lists(st.floats(-2.0, 2.0).filter(lambda x: abs(x) > 1e-3), min_size=2, max_size=2))
def test_friction_slopes_match_finite_differences(v: list[float]) -> None:
    qd = np.array(v)
    eps = 1e-7
    for fr in (SmoothFriction(MODEL, velocity=0.05), StickSlip(MODEL)):
        d = np.sign(qd)
        fd = (fr.torque(qd + eps, d) - fr.torque(qd - eps, d)) / (2 * eps)
        np.testing.assert_allclose(fr.slope(qd, d), fd, rtol=1e-5, atol=1e-5)


def test_unknown_friction_model() -> None:
    with pytest.raises(UnknownNameError, match="stick-slip"):
        make_friction("coulomb", MODEL)


def test_kelvin_voigt_and_hunt_crossley_forces() -> None:
    kv = KelvinVoigt(1e4, 50.0)
    assert kv.force(1e-3, 0.1) == (1e4 * 1e-3 + 50.0 * 0.1, 1e4, 50.0)
    assert kv.force(1e-3, -1.0) == (0.0, 0.0, 0.0)  # never pulls
    hc = HuntCrossley(1e5, 0.4, exponent=1.5)
    f, dk, dd = hc.force(2e-3, 0.3)
    assert f == pytest.approx(1e5 * 2e-3**1.5 * (1 + 0.4 * 0.3))
    assert dk == pytest.approx(1.5e5 * 2e-3**0.5 * (1 + 0.4 * 0.3))
    assert dd == pytest.approx(1e5 * 2e-3**1.5 * 0.4)
    assert hc.force(2e-3, -3.0)[0] == 0.0
    assert hc.depth_at(1e5 * 2e-3**1.5) == pytest.approx(2e-3)


@settings(max_examples=30, deadline=None)
@given(
    p=st.lists(st.floats(-0.01, 0.01), min_size=3, max_size=3),
    v=st.lists(st.floats(-0.5, 0.5), min_size=3, max_size=3),
    mu=st.sampled_from([0.0, 0.6]),
)
def test_plane_force_derivatives_match_finite_differences(p: list[float], v: list[float], mu: float) -> None:
    """∂F/∂p and ∂F/∂v of a tilted Hunt–Crossley plane with friction, away from the kinks (contact edge, slip
    velocity), against central differences."""
    plane = Plane(
        HuntCrossley(1e5, 0.3), normal=(0.2, -0.1, 1.0), point=(0.0, 0.0, 0.005), friction=mu, slip_velocity=0.05
    )
    pv, vv = np.array(p), np.array(v)
    force, dfdp, dfdv = plane.force(pv, vv, True)
    if force is None:
        return
    vt = vv - (plane.normal @ vv) * plane.normal
    if plane.depth(pv) < 1e-5 or abs(np.linalg.norm(vt) - 0.05) < 1e-3:
        return
    eps = 1e-8
    for j in range(3):
        e = np.zeros(3)
        e[j] = eps
        fp = (plane.force(pv + e, vv, False)[0] - plane.force(pv - e, vv, False)[0]) / (2 * eps)
        fv = (plane.force(pv, vv + e, False)[0] - plane.force(pv, vv - e, False)[0]) / (2 * eps)
        np.testing.assert_allclose(dfdp[:, j], fp, rtol=1e-5, atol=1e-3)
        np.testing.assert_allclose(dfdv[:, j], fv, rtol=1e-5, atol=1e-3)


@pytest.mark.parametrize("mu", [0.0, 0.6])
def test_contact_joint_stiffness_and_damping_are_the_point_law_through_the_jacobian(mu: float) -> None:
    """Environment.joint_torque on planar_2r pressing a tilted Hunt–Crossley plane with friction: τ_c = Jᵀ F,
    D = ∂τ_c/∂q̇ (central differences of τ_c in q̇) and K = Jᵀ (∂F/∂p) J (the module's definition, J̇-terms
    neglected; central differences of F along the tool's path p(q) from Pinocchio's forward kinematics)."""
    dyn = armctl.Dynamics(armctl.models.planar_2r())
    q, qd = np.array([0.5, -1.4]), np.array([0.3, -0.2])
    unit = np.array([-1.0, 0.0, 0.5]) / math.sqrt(1.25)
    tool = dyn.frame_pose(q)[:3, 3]
    plane = Plane(HuntCrossley(1e5, 0.3), normal=unit, point=tool + 0.005 * unit, friction=mu, slip_velocity=0.05)
    jac = dyn.jacobian(q)[:3]
    speed = np.linalg.norm(jac @ qd - (unit @ jac @ qd) * unit)
    assert speed > 0.1  # sliding, away from the slip velocity's kink
    kin = plane.kinematics(dyn)
    tau, stiff, damp = plane.joint_torque(kin, q, qd, stiffness=True)
    force = plane.force(tool, jac @ qd, False)[0]
    np.testing.assert_allclose(tau, jac.T @ force, rtol=1e-10)
    eps = 1e-7
    for j in range(2):
        e = np.zeros(2)
        e[j] = eps
        dtau = (plane.joint_torque(kin, q, qd + e)[0] - plane.joint_torque(kin, q, qd - e)[0]) / (2 * eps)
        np.testing.assert_allclose(damp[:, j], dtau, rtol=1e-5, atol=1e-6 * np.abs(damp).max())
        up, down = (dyn.frame_pose(q + s * e)[:3, 3] for s in (1.0, -1.0))
        df = (plane.force(up, jac @ qd, False)[0] - plane.force(down, jac @ qd, False)[0]) / (2 * eps)
        np.testing.assert_allclose(stiff[:, j], jac.T @ df, rtol=1e-5, atol=1e-6 * np.abs(stiff).max())
