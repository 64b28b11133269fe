"""The simulator's hot path for plants without friction, contact or disturbance (``fast_step``) against the
textbook RK4 of :func:`armctl.sim.integrators.rk4`, written as four stage evaluations."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.sim.integrators import fast_step, rk4
from armctl.sim.plant import Plant

pytestmark = pytest.mark.one_step  # sweeps and the step functions themselves: not a choice of step


def test_fast_rk4_is_rk4_step_after_step_and_keeps_its_results() -> None:
    dyn = armctl.Dynamics(armctl.models.panda())
    plant = Plant(dyn)
    step = fast_step("rk4", plant)
    assert step is not None
    rng = np.random.default_rng(3)
    q, v = rng.uniform(-1.0, 1.0, (2, 7))
    ref_q, ref_v = q.copy(), v.copy()
    kept = []
    for k in range(6):
        tau = rng.uniform(-5.0, 5.0, 7)
        h = 1e-3 if k != 3 else 5e-4  # a step of another size in between
        q, v, a1 = step(q, v, tau, h)
        ref_q, ref_v, ref_a1 = rk4(
            lambda t, q_, v_, tau_: dyn.forward_dynamics(q_, v_, tau_), 0.0, ref_q, ref_v, tau, h
        )
        np.testing.assert_allclose(q, ref_q, rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(v, ref_v, rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(a1, ref_a1, rtol=1e-13, atol=1e-13)
        kept.append((q, q.copy()))
    # a result stays valid through the next step (which reads it in place), until the one after
    assert np.array_equal(kept[-1][0], kept[-1][1]) and np.array_equal(kept[-2][0], kept[-2][1])
    # a state from elsewhere (not the last result) is copied in, and the caller's arrays are not written
    q0, v0 = rng.uniform(-1.0, 1.0, (2, 7))
    q0_copy, v0_copy = q0.copy(), v0.copy()
    q, v, _ = step(q0, v0, np.zeros(7), 1e-3)
    ref_q, ref_v, _ = rk4(
        lambda t, q_, v_, tau_: dyn.forward_dynamics(q_, v_, tau_), 0.0, q0_copy, v0_copy, np.zeros(7), 1e-3
    )
    np.testing.assert_allclose(q, ref_q, rtol=1e-13, atol=1e-15)
    assert np.array_equal(q0, q0_copy) and np.array_equal(v0, v0_copy)


def test_fast_rk4_takes_its_own_results_in_any_order() -> None:
    """States that alias the step's own arrays (its last q₁ and q̇₁ swapped, the same array for both, q from two
    steps back) are read as values, like any other input."""
    dyn = armctl.Dynamics(armctl.models.panda())
    step = fast_step("rk4", Plant(dyn))
    assert step is not None

    def textbook(q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        q1, v1, _ = rk4(
            lambda t, q_, v_, tau_: dyn.forward_dynamics(q_, v_, tau_), 0.0, q.copy(), v.copy(), np.zeros(7), 1e-3
        )
        return q1, v1

    rng = np.random.default_rng(5)
    q1, v1, _ = step(*rng.uniform(-1.0, 1.0, (2, 7)), np.zeros(7), 1e-3)
    q2, v2, _ = step(q1, v1, np.zeros(7), 1e-3)
    for q, v in ((v2, q2), (q2, q2), (q1, v2)):  # swapped; one array for both; q two steps back
        want = textbook(q, v)
        got_q, got_v, _ = step(q, v, np.zeros(7), 1e-3)
        np.testing.assert_allclose(got_q, want[0], rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(got_v, want[1], rtol=1e-13, atol=1e-15)
        q2, v2 = got_q, got_v
        q1 = q2  # (kept for the next case's "two steps back")
