"""The Pinocchio backend assembles regressors in a workspace fed by Pinocchio's own: results must be fresh
arrays, and the path that reads Pinocchio's returned copies (used when eigenpy hands out no view) must give
the same numbers."""

from __future__ import annotations

import numpy as np
import pytest

import armctl


@pytest.fixture(scope="module")
def puma() -> armctl.Dynamics:
    return armctl.Dynamics(armctl.models.puma560())  # friction (asymmetric Coulomb) and rotors


def _states(n: int, seed: int = 3) -> tuple[np.ndarray, ...]:
    return tuple(np.random.default_rng(seed).uniform(-2.0, 2.0, (4, n)))


def test_results_are_fresh_arrays(puma: armctl.Dynamics) -> None:
    q, qd, qdd, qd_r = _states(puma.n)
    y1 = puma.regressor(q, qd, qdd)
    kept = y1.copy()
    y2 = puma.regressor(qd, q, qd_r)  # another state overwrites the workspace
    p1 = puma.passivity_regressor(q, qd, qd_r, qdd)
    assert not np.shares_memory(y1, y2) and not np.shares_memory(y1, p1)
    assert np.array_equal(y1, kept)


def test_copy_path_matches_view_path(puma: armctl.Dynamics) -> None:
    q, qd, qdd, qd_r = _states(puma.n)
    assert puma.kernel._raw_t is not None  # this Pinocchio/eigenpy hands out the view
    view = (puma.regressor(q, qd, qdd), puma.passivity_regressor(q, qd, qd_r, qdd))
    other = armctl.Dynamics(puma.model)
    other.kernel._raw_t = other.kernel._raw_t_free = None  # as if eigenpy returned copies only
    copy = (other.regressor(q, qd, qdd), other.passivity_regressor(q, qd, qd_r, qdd))
    for a, b in zip(view, copy, strict=True):
        assert np.allclose(a, b, rtol=0, atol=1e-12 * np.abs(a).max())


def test_passivity_torque_is_regressor_times_parameters(puma: armctl.Dynamics) -> None:
    q, qd, qdd, qd_r = _states(puma.n, seed=5)
    tau = puma.passivity_torque(q, qd, qd_r, qdd)
    y = puma.passivity_regressor(q, qd, qd_r, qdd)
    assert np.allclose(tau, y @ puma.parameters(), rtol=1e-10, atol=1e-10 * np.abs(tau).max())


def test_interleaved_calls_do_not_leak_between_states(puma: armctl.Dynamics) -> None:
    # the passivity regressor subtracts in Pinocchio's own workspace; every later call, of either kind and
    # at any state, must still give what a fresh object (clean workspaces, copy path) gives
    fresh = armctl.Dynamics(puma.model)
    fresh.kernel._raw_t = fresh.kernel._raw_t_free = None
    for seed in range(6):
        q, qd, qdd, qd_r = _states(puma.n, seed=seed)
        got = (
            puma.passivity_regressor(q, qd, qd_r, qdd),
            puma.regressor(q, qd, qdd),
            puma.passivity_regressor(qd, q, qdd, qd_r),
        )
        want = (
            fresh.passivity_regressor(q, qd, qd_r, qdd),
            fresh.regressor(q, qd, qdd),
            fresh.passivity_regressor(qd, q, qdd, qd_r),
        )
        for a, b in zip(got, want, strict=True):
            assert np.allclose(a, b, rtol=0, atol=1e-12 * np.abs(b).max())
