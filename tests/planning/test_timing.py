"""Timing laws: closed-form cases and finite-difference consistency of s, ṡ, s̈."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from armctl.errors import SolverError
from armctl.planning import GridTiming, PolynomialTiming, ScaledTiming


def _finite_difference_consistent(timing, t: np.ndarray, h: float = 1e-6) -> None:
    _, sd, sdd = timing.evaluate(t)
    sp, sdp, _ = timing.evaluate(t + h)
    sm, sdm, _ = timing.evaluate(t - h)
    np.testing.assert_allclose((sp - sm) / (2 * h), sd, atol=1e-6)
    np.testing.assert_allclose((sdp - sdm) / (2 * h), sdd, atol=1e-5)


def test_grid_timing_of_constant_acceleration_is_the_parabola() -> None:
    # x = ṡ² = 2 A s is the motion s = A t²/2 from rest, reaching s = 1 at t = √(2/A), whatever the grid
    A = 3.0
    s = np.sort(np.concatenate(([0.0, 1.0], np.random.default_rng(0).uniform(0, 1, 20))))
    timing = GridTiming(s, 2 * A * s)
    assert timing.duration == pytest.approx(math.sqrt(2 / A), rel=1e-12)
    t = np.linspace(0, timing.duration, 50)
    ss, sd, sdd = timing.evaluate(t)
    np.testing.assert_allclose(ss, 0.5 * A * t**2, atol=1e-12)
    np.testing.assert_allclose(sd, A * t, atol=1e-12)
    np.testing.assert_allclose(sdd, A)


def test_grid_timing_reproduces_its_profile_and_is_consistent() -> None:
    s = np.linspace(0, 1, 11)
    x = np.sin(np.pi * s) ** 2 + 0.1 * s * (1 - s)
    timing = GridTiming(s, x)
    ss, sd, _ = timing.evaluate(timing.t)
    np.testing.assert_allclose(ss, s, atol=1e-12)
    np.testing.assert_allclose(sd**2, x, atol=1e-12)
    inner = 0.5 * (timing.t[1:] + timing.t[:-1])  # away from the stage boundaries, where s̈ jumps
    _finite_difference_consistent(timing, inner)


def test_outside_the_motion_the_path_rests_at_its_ends() -> None:
    timing = PolynomialTiming(2.0)
    s, sd, sdd = timing.evaluate(np.array([-1.0, 0.0, 2.0, 5.0]))
    np.testing.assert_allclose(s, [0, 0, 1, 1])
    np.testing.assert_allclose(sd, 0, atol=1e-15)
    np.testing.assert_allclose(sdd[[0, 3]], 0)


def test_polynomial_and_scaled_timings() -> None:
    base = PolynomialTiming(2.0)
    _finite_difference_consistent(base, np.linspace(0.01, 1.99, 17))
    slow = ScaledTiming(base, 1.5)
    assert slow.duration == pytest.approx(3.0)
    t = np.linspace(0, 3, 13)
    s, sd, sdd = slow.evaluate(t)
    s0, sd0, sdd0 = base.evaluate(t / 1.5)
    np.testing.assert_allclose(s, s0)
    np.testing.assert_allclose(sd, sd0 / 1.5)
    np.testing.assert_allclose(sdd, sdd0 / 1.5**2)


def test_a_stage_at_rest_is_refused() -> None:
    with pytest.raises(SolverError, match="zero on the whole stage"):
        GridTiming([0.0, 0.5, 0.6, 1.0], [0.0, 0.0, 1.0, 0.0])


def test_scalar_evaluation_equals_the_vectorised_one() -> None:
    from armctl.planning import LinePath, SplinePath, Trajectory
    from tests.planning.helpers import PANDA_WAYPOINTS

    grid = GridTiming(np.linspace(0, 1, 11), np.r_[0.0, np.linspace(0.5, 2.0, 9), 0.0])
    for timing in (grid, PolynomialTiming(2.0), ScaledTiming(grid, 0.7)):
        t = np.linspace(-0.5, timing.duration + 0.5, 97)
        np.testing.assert_allclose(np.array([timing.at(x) for x in t]).T, timing.evaluate(t), atol=1e-13)
        for path in (SplinePath(PANDA_WAYPOINTS), LinePath(PANDA_WAYPOINTS[0], PANDA_WAYPOINTS[1])):
            traj = Trajectory(path, timing)
            smp = traj.sample(t)
            for k in range(0, 97, 8):
                ref = traj(t[k])
                np.testing.assert_allclose(ref.q, smp.q[k], atol=1e-12)
                np.testing.assert_allclose(ref.qd, smp.qd[k], atol=1e-12)
                np.testing.assert_allclose(ref.qdd, smp.qdd[k], atol=1e-11)


def test_dense_check_samples_each_stage_evenly_in_time() -> None:
    """sample_times of a GridTiming: ``oversample`` samples per stage, evenly in time from the stage's start, the
    gridpoints included, plus the end (its docstring); the reference is np.linspace per stage, built by hand
    from the stage times t_k."""
    from armctl.planning import LinePath, Trajectory
    from armctl.planning.verify import sample_times

    s = np.linspace(0, 1, 6)
    timing = GridTiming(s, [0.0, 0.5, 1.0, 1.2, 0.6, 0.0])  # stages of unequal durations
    traj = Trajectory(LinePath([0.0], [1.0]), timing)
    for oversample in (1, 3, 10):
        hand = [np.linspace(a, b, oversample, endpoint=False) for a, b in itertools.pairwise(timing.t)]
        expected = np.append(np.concatenate(hand), timing.t[-1])
        np.testing.assert_allclose(sample_times(traj, oversample), expected, rtol=0, atol=1e-14)
