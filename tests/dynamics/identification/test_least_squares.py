"""OLS / WLS: standard deviations against Monte Carlo, weights against the true noise, and bad input
(rank-deficient data reported with the unidentifiable directions, never a silent least-squares answer)."""

from __future__ import annotations

import numpy as np
import pytest

from armctl.dynamics.identification import (
    FourierExcitation,
    IdentificationData,
    build_problem,
    find_base_parameters,
    identify,
    solve_least_squares,
)
from armctl.dynamics.identification.base_parameters import BaseParameters
from armctl.dynamics.identification.problem import IdentificationProblem
from armctl.errors import IdentifiabilityError, InvalidParameterError, ShapeError
from tests.helpers.arms import dynamics


def _linear_problem(w: np.ndarray, y: np.ndarray, n: int) -> IdentificationProblem:
    """A problem straight from a matrix (identity 'base' map), to test the estimator as pure statistics."""
    p = w.shape[1]
    base = BaseParameters(tuple(range(p)), (), np.zeros((p, 0)), tuple(f"x{i}" for i in range(p)), 1e-8)
    return IdentificationProblem(w, y, base, n, False, base.names)


def test_ols_standard_deviations_match_monte_carlo() -> None:
    rng = np.random.default_rng(0)
    n, s, p = 2, 150, 5
    w = rng.standard_normal((n * s, p)) * np.array([1.0, 3.0, 0.2, 1.0, 5.0])
    theta = rng.standard_normal(p)
    draws, stds = [], []
    for _ in range(400):
        y = w @ theta + 0.3 * rng.standard_normal(n * s)
        est = solve_least_squares(_linear_problem(w, y, n), weighted=False)
        draws.append(est.theta)
        stds.append(est.std)
    np.testing.assert_allclose(np.std(draws, axis=0), np.mean(stds, axis=0), rtol=0.12)
    assert np.all(np.abs(np.mean(draws, axis=0) - theta) <= 4 * np.mean(stds, axis=0) / np.sqrt(400))  # unbiased


def test_wls_finds_the_noise_of_each_joint_and_beats_ols() -> None:
    rng = np.random.default_rng(1)
    n, s, p = 3, 400, 6
    sigma = np.array([0.05, 1.0, 0.2])
    w = rng.standard_normal((n * s, p))
    theta = rng.standard_normal(p)
    ols_err, wls_err = [], []
    for _ in range(60):
        y = w @ theta + np.tile(sigma, s) * rng.standard_normal(n * s)
        prob = _linear_problem(w, y, n)
        wls, ols = solve_least_squares(prob, weighted=True), solve_least_squares(prob, weighted=False)
        np.testing.assert_allclose(wls.noise_std, sigma, rtol=0.15)
        ols_err.append(ols.theta - theta)
        wls_err.append(wls.theta - theta)
    assert np.mean(np.square(wls_err)) < 0.5 * np.mean(np.square(ols_err))
    # the WLS σ describe the WLS scatter
    np.testing.assert_allclose(np.std(wls_err, axis=0), wls.std, rtol=0.3)


def _data(name: str, moving: list[int], seconds: float = 6.0, seed: int = 0) -> IdentificationData:
    """Exact samples of ``name`` moving only the joints in ``moving`` (the others held at mid-range)."""
    dyn = dynamics(name)
    n = dyn.n
    rng = np.random.default_rng(seed)
    a, b = np.zeros((2, n, 3))
    a[moving], b[moving] = 0.3 * rng.standard_normal((2, len(moving), 3))
    traj = FourierExcitation(np.full(n, 0.3), a, b, period=seconds)
    t = np.arange(0.0, seconds, 0.02)
    q, qd, qdd = traj.evaluate(t)
    tau = np.array([dyn.inverse_dynamics(*x) for x in zip(q, qd, qdd, strict=True)])
    return IdentificationData(t, q, qd, qdd, tau)


def test_too_little_excitation_names_the_unidentifiable_directions() -> None:
    dyn = dynamics("planar_3r")
    data = _data("planar_3r", moving=[0])  # joints 2 and 3 never move
    problem = build_problem(dyn, data, offsets=False)
    with pytest.raises(IdentifiabilityError) as info:
        solve_least_squares(problem)
    err = info.value
    d = np.asarray(err.directions)
    assert d.ndim == 2 and d.shape[1] == problem.n_unknowns and d.shape[0] >= 1
    # independent check: each reported direction is (numerically) invisible in these data …
    w = problem.regressor / np.linalg.norm(problem.regressor, axis=0).clip(1e-300)
    w_d = problem.regressor @ d.T
    assert np.linalg.norm(w_d, axis=0).max() <= 1e-6 * np.linalg.norm(problem.regressor)
    # … and together they span the whole null space of the data (rank + directions = unknowns)
    assert np.linalg.matrix_rank(w, tol=1e-7 * np.linalg.norm(w, 2)) + d.shape[0] == problem.n_unknowns
    # the message names parameters, e.g. joint 3's friction (it never moves)
    assert "Fv[2]" in str(err) or "Fc[2]" in str(err)
    # identify() refuses too, rather than answering
    with pytest.raises(IdentifiabilityError):
        identify(dyn, data, consistent=False)


def test_full_excitation_passes_the_same_check() -> None:
    problem = build_problem(dynamics("planar_3r"), _data("planar_3r", moving=[0, 1, 2]), offsets=False)
    est = solve_least_squares(problem)
    truth = problem.base.project(dynamics("planar_3r").model.parameters())
    np.testing.assert_allclose(est.theta, truth, atol=1e-8 * np.abs(truth).max())


def test_fewer_equations_than_unknowns() -> None:
    dyn = dynamics("puma560")
    data = _data("puma560", moving=list(range(6)))
    short = IdentificationData(data.t[:4], data.q[:4], data.qd[:4], data.qdd[:4], data.tau[:4])
    with pytest.raises(IdentifiabilityError, match="more samples"):
        solve_least_squares(build_problem(dyn, short))


def test_mismatched_experiments_are_refused() -> None:
    dyn = dynamics("planar_2r")
    with pytest.raises(ShapeError, match="data have 3 joints, the model 2"):
        build_problem(dyn, _data("planar_3r", moving=[0, 1, 2]))  # 3 joints of data for a 2-joint arm
    with pytest.raises(ShapeError, match="base parameters are for 3 joints"):
        build_problem(dyn, _data("planar_2r", moving=[0, 1]), base=find_base_parameters(dynamics("planar_3r")))
    with pytest.raises(InvalidParameterError, match="data must be an IdentificationData"):
        build_problem(dyn, [])
