"""Fourier excitation: derivatives, periodicity, limits, and the optimiser's inputs."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import armctl
from armctl.dynamics.identification import FourierExcitation, optimize_excitation
from armctl.errors import InvalidParameterError, ShapeError
from tests.helpers.arms import dynamics


def _random(n: int = 3, harmonics: int = 4, seed: int = 0) -> FourierExcitation:
    rng = np.random.default_rng(seed)
    return FourierExcitation(
        rng.standard_normal(n), rng.standard_normal((n, harmonics)), rng.standard_normal((n, harmonics)), period=6.0
    )


def test_velocity_and_acceleration_are_the_derivatives_of_position() -> None:
    traj = _random()
    t = np.linspace(0.1, 5.9, 37)
    h = 1e-5
    q_p, qd_p, _ = traj.evaluate(t + h)
    q_m, qd_m, _ = traj.evaluate(t - h)
    _, qd, qdd = traj.evaluate(t)
    np.testing.assert_allclose((q_p - q_m) / (2 * h), qd, atol=1e-6)
    np.testing.assert_allclose((qd_p - qd_m) / (2 * h), qdd, atol=1e-5)


def test_periodic_and_reference() -> None:
    traj = _random()
    for a, b in zip(traj.evaluate(1.3), traj.evaluate(1.3 + 2 * traj.period), strict=True):
        np.testing.assert_allclose(a, b, atol=1e-9)
    ref = traj(0.7)
    assert isinstance(ref, armctl.Reference)
    np.testing.assert_allclose(ref.qdd, traj.evaluate(0.7)[2])
    assert traj.bandwidth == pytest.approx(4 / 6.0)
    # zero-mean velocity: the motion returns, so every joint reverses (Coulomb friction is excited)
    qd = traj.evaluate(np.linspace(0, traj.period, 2000, endpoint=False))[1]
    assert np.allclose(qd.mean(axis=0), 0.0, atol=1e-9)


def test_optimised_trajectory_respects_limits_on_a_dense_grid() -> None:
    dyn = dynamics("planar_3r")
    design = optimize_excitation(
        dyn, acceleration_limit=3.0, velocity_limit=1.0, period=5.0, harmonics=3, maxiter=15, seed=1
    )
    t = np.linspace(0.0, 5.0, 20001)
    q, qd, qdd = design.trajectory.evaluate(t)
    m = dyn.model
    assert np.all(np.abs(qd) <= 1.0 + 1e-9) and np.all(np.abs(qdd) <= 3.0 + 1e-9)
    assert np.all(q >= np.where(np.isfinite(m.lower), m.lower, -np.inf))
    assert np.all(q <= np.where(np.isfinite(m.upper), m.upper, np.inf))
    # the optimiser improves on its start by a margin (it falls back to the start if it cannot, so a bare
    # "not worse" would hold with no optimisation at all)
    assert design.condition_number < 0.8 * design.initial_condition_number
    # it uses its limits: some joint reaches its velocity or acceleration limit within 10%
    assert np.abs(qd).max() > 0.9 or np.abs(qdd).max() > 2.7


@pytest.mark.parametrize("maxiter", [0, 5])
def test_position_limits_hold_on_both_sides(maxiter: int) -> None:
    # generous velocity and acceleration limits: the joint ranges bind (the best random start, maxiter=0, and a
    # short optimisation both went up to 0.9 rad below the Puma's lower limits when the scaling read the
    # downward swing as the upward one)
    dyn = dynamics("puma560")
    design = optimize_excitation(dyn, acceleration_limit=100.0, velocity_limit=10.0, maxiter=maxiter, seed=0)
    q = design.trajectory.evaluate(np.linspace(0.0, design.trajectory.period, 40001))[0]
    m = dyn.model
    assert np.all(q >= m.lower + 0.05 - 1e-9) and np.all(q <= m.upper - 0.05 + 1e-9)  # default position_margin
    # and the range is used: some joint comes within 10% of its span of a limit
    span = m.upper - m.lower
    assert (np.minimum(q.min(axis=0) - m.lower, m.upper - q.max(axis=0)) < 0.1 * span).any()


def test_limits_are_required_where_the_model_has_none() -> None:
    with pytest.raises(InvalidParameterError, match="velocity_limit"):
        optimize_excitation(dynamics("puma560"), acceleration_limit=3.0, maxiter=0)  # no velocity limits
    with pytest.raises(ShapeError):
        optimize_excitation(dynamics("panda"), acceleration_limit=[1.0, 2.0], maxiter=0)


def test_bad_coefficients_are_refused() -> None:
    with pytest.raises(ShapeError):
        FourierExcitation(np.zeros(2), np.zeros((3, 2)), np.zeros((3, 2)), 1.0)
    with pytest.raises(InvalidParameterError):
        FourierExcitation(np.zeros(2), np.zeros((2, 2)), np.zeros((2, 2)), -1.0)


@pytest.mark.parametrize(("model_limit", "given"), [(0.5, 5.0), (2.0, 0.3)])
def test_velocity_limit_is_the_smaller_of_the_models_and_the_given(model_limit: float, given: float) -> None:
    """velocity_limit, if given, is the smaller of the two (docstring): checked on a dense grid of the design
    against min(model's joint velocity limit, given), both set by hand; the design moves near that bound."""
    base = dynamics("planar_3r").model
    joints = tuple(
        dataclasses.replace(j, limits=dataclasses.replace(j.limits, velocity=model_limit)) for j in base.joints
    )
    dyn = armctl.Dynamics(dataclasses.replace(base, joints=joints))
    assert np.all(dyn.model.velocity_limit == model_limit)
    design = optimize_excitation(
        dyn, acceleration_limit=100.0, velocity_limit=given, period=5.0, harmonics=3, maxiter=0, seed=1
    )
    qd = np.abs(design.trajectory.evaluate(np.linspace(0.0, 5.0, 20001))[1]).max(axis=0)
    bound = min(model_limit, given)
    assert np.all(qd <= bound * (1 + 1e-9))
    assert qd.max() > 0.8 * bound


def test_optimiser_constraint_basis_is_the_fourier_series() -> None:
    """The optimiser's linear maps from one joint's (a, b) to q − q0, q̇, q̈ on its grid (_Basis, from which the
    position, velocity and acceleration constraints are built) against the series written out by hand:
    q = q0 + Σ_l a_l/(ω l) sin(ω l t) − b_l/(ω l) cos(ω l t), q̇ = Σ_l a_l cos + b_l sin,
    q̈ = Σ_l ω l (−a_l sin + b_l cos)."""
    from armctl.dynamics.identification.excitation_design import _Basis

    rng = np.random.default_rng(3)
    period, nh = 4.0, 3
    omega = 2 * np.pi / period
    t = np.linspace(0.0, period, 50, endpoint=False)
    a, b = rng.standard_normal(nh), rng.standard_normal(nh)
    q = sum(
        a[k] / (omega * (k + 1)) * np.sin(omega * (k + 1) * t) - b[k] / (omega * (k + 1)) * np.cos(omega * (k + 1) * t)
        for k in range(nh)
    )
    qd = sum(a[k] * np.cos(omega * (k + 1) * t) + b[k] * np.sin(omega * (k + 1) * t) for k in range(nh))
    qdd = sum(
        omega * (k + 1) * (-a[k] * np.sin(omega * (k + 1) * t) + b[k] * np.cos(omega * (k + 1) * t)) for k in range(nh)
    )
    basis = _Basis(omega, nh, t)
    for mat, expected in ((basis.pos, q), (basis.vel, qd), (basis.acc, qdd)):
        np.testing.assert_allclose(mat @ np.r_[a, b], expected, atol=1e-12)
