"""The sampled-data model of force control on a compliant environment: its transition matrix against an
independent hybrid simulation (SciPy's integrator between held samples), its critical gain against closed loops of
the Panda pressing on a table (within 15 %), and bad input."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from armctl.bench.interaction_borders import (
    PRELOAD,
    force_control,
    outcome,
    predicted_force_gain,
    press,
)
from armctl.errors import InvalidParameterError
from armctl.tuning.force_stability import critical_force_gain, force_loop_matrix, force_loop_radius

LOOP = {"kp": 400.0, "kd": 40.0, "inertia": 4.0, "period": 1e-3}


def hybrid_growth(k_e: float, k_f: float, delay: int, periods: int = 400) -> float:
    """max |s| over the last 100 periods of ``periods`` over that of the first 100: the continuous plant
    s̈ = a + (f_m − f)/Λ integrated by SciPy between samples, the controller's (a, f_m) from samples ``delay``
    periods old, held."""
    lam, t = LOOP["inertia"], LOOP["period"]
    past = [np.array([1e-4, 0.0])] * (delay + 1)  # the measured states, oldest first
    x = past[-1]
    s = []
    for _ in range(periods):
        s_m, v_m = past[0]
        f_m = k_e * s_m
        a = -LOOP["kp"] * (s_m + k_f * f_m) - LOOP["kd"] * v_m

        def rhs(_t: float, y: np.ndarray, a: float = a, f_m: float = f_m) -> list[float]:
            return [y[1], a + (f_m - k_e * y[0]) / lam]

        x = solve_ivp(rhs, (0.0, t), x, method="DOP853", rtol=1e-10, atol=1e-14).y[:, -1]
        past = [*past[1:], x]
        s.append(abs(x[0]))
    return float(max(s[-100:]) / max(s[:100]))


@pytest.mark.parametrize("delay", [0, 1])
def test_the_transition_matrix_is_the_held_delayed_loop(delay: int) -> None:
    k_e = 1e4
    k_star = critical_force_gain(k_e, delay=delay, **LOOP)
    assert hybrid_growth(k_e, 0.9 * k_star, delay) < 0.8  # decays
    assert hybrid_growth(k_e, 1.1 * k_star, delay) > 1.25  # grows
    # one period of the matrix against one period of the hybrid loop, from a random augmented state
    rng = np.random.default_rng(0)
    z = rng.normal(size=2 * (delay + 1))
    a = force_loop_matrix(k_e, 0.5 * k_star, delay=delay, **LOOP)
    s_m, v_m = z[2 * delay : 2 * delay + 2]
    f_m = k_e * s_m
    acc = -LOOP["kp"] * (s_m + 0.5 * k_star * f_m) - LOOP["kd"] * v_m
    sol = solve_ivp(lambda _t, y: [y[1], acc + (f_m - k_e * y[0]) / LOOP["inertia"]], (0.0, 1e-3), z[:2],
                    method="DOP853", rtol=1e-12, atol=1e-14)  # fmt: skip
    np.testing.assert_allclose((a @ z)[:2], sol.y[:, -1], rtol=1e-8, atol=1e-12)


def test_the_critical_gain_falls_as_one_over_the_stiffness_on_soft_surfaces() -> None:
    soft = [critical_force_gain(k, delay=1, **LOOP) * k for k in (100.0, 300.0, 1000.0)]
    np.testing.assert_allclose(soft, soft[0], rtol=0.05)  # the loop gain k_e K_F* is what counts
    assert critical_force_gain(1e3, delay=2, **LOOP) < critical_force_gain(1e3, delay=1, **LOOP)
    assert force_loop_radius(1e4, 0.0, delay=1, **LOOP) < 1.0


@pytest.mark.parametrize("k_e", [1e3, 3e4, 3e5])
def test_force_control_on_the_panda_turns_unstable_within_15_percent_of_the_prediction(k_e: float) -> None:
    k_star = predicted_force_gain(k_e)
    assert outcome(press(force_control(0.85 * k_star), k_e, preload=PRELOAD)) == "stable"
    assert outcome(press(force_control(1.15 * k_star), k_e, preload=PRELOAD)) == "chatter"


def test_bad_input_is_named() -> None:
    with pytest.raises(InvalidParameterError, match="stiffness"):
        critical_force_gain(-1.0, **LOOP)
    with pytest.raises(InvalidParameterError, match="force_gain"):
        force_loop_matrix(1e4, -1.0, **LOOP)
    with pytest.raises(InvalidParameterError, match="inertia"):
        force_loop_matrix(1e4, 1e-3, kp=400.0, kd=40.0, inertia=0.0, period=1e-3)
