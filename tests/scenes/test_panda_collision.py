"""``panda_collision``: the observer detects the unexpected wall within milliseconds of the first contact, its
estimate follows the simulator's true external torques through the first-order lag of its gain, and the reactions
stop the push that computed torque alone keeps up."""

from __future__ import annotations

import math
import warnings
from functools import cache
from typing import Any

import numpy as np
import pytest

from armctl.controllers import CollisionReaction, ComputedTorque, Measurement, MomentumObserver
from armctl.errors import InvalidParameterError, SimulationWarning, UnknownNameError
from armctl.references import Reference
from armctl.scenes import scene
from armctl.scenes.panda_collision import DEFAULTS


@cache
def run(method: str) -> tuple[Any, dict[str, Any]]:
    sc = scene("panda_collision")
    res = sc.run(method)
    return res, sc.metrics(res, method, timing_rounds=0)


@pytest.mark.parametrize("method", ["no_reaction", "gravity", "reflex"])
def test_the_wall_is_detected_within_ten_milliseconds_of_the_first_contact(method: str) -> None:
    res, m = run(method)
    assert not res.diverged
    assert 0.5 < m["contact_at"] < 1.5
    assert 0.0 <= m["detection_delay"] <= 0.01


def test_the_residual_is_the_first_order_lag_of_the_true_external_torques() -> None:
    res, _ = run("no_reaction")
    k_o, h = DEFAULTS["observer_gain"], 1e-3
    gamma = np.exp(-k_o * h)
    lag = np.zeros_like(res.tau_ext)  # the closed form on the simulator's τ_ext: r_k = γ r_k−1 + (1 − γ) τ̄_k
    for k in range(1, len(res.t)):
        mean = 0.5 * (res.tau_ext[k - 1] + res.tau_ext[k])  # the period's mean, by the trapezoid
        lag[k] = gamma * lag[k - 1] + (1.0 - gamma) * mean
    peak = np.abs(res.tau_ext).max()
    assert peak > 5.0
    assert np.abs(res.logs["residual"] - lag).max() < 0.02 * peak


def test_the_estimated_tool_force_follows_the_true_one_while_pushing() -> None:
    res, m = run("no_reaction")
    f = np.linalg.norm(res.contact_force_on_environment[:, 0], axis=1)
    steady = (res.t > m["contact_at"] + 5.0 / DEFAULTS["observer_gain"]) & (res.t > 2.0)  # the path's end: held
    assert steady.any() and (f[steady] > 10.0).all()
    est = res.logs["wrench_estimate"][steady, :3]
    np.testing.assert_allclose(est, res.wrench[steady, :3], atol=0.01 * f.max())


def test_the_reactions_stop_the_push() -> None:
    _, alone = run("no_reaction")
    _, grav = run("gravity")
    _, reflex = run("reflex")
    assert alone["force_after"] > 10.0  # computed torque alone keeps pushing
    assert grav["force_after"] < 0.5 and reflex["force_after"] == 0.0  # reflex: out of contact
    assert grav["push_impulse"] < 0.05 * alone["push_impulse"]
    assert reflex["push_impulse"] < grav["push_impulse"]


def test_collision_reaction_in_a_users_loop_and_bad_input() -> None:
    sc = scene("panda_collision")
    dyn = sc.dynamics("exact")
    ct = ComputedTorque(dyn, 100.0, 20.0)
    obs = MomentumObserver(dyn, 50.0, thresholds=1.0)
    c = CollisionReaction(ct, obs)
    q, qd, ref = sc.q0, np.zeros(7), Reference(sc.q0)
    with pytest.raises(InvalidParameterError, match="tau_applied"):
        c(0.0, q, qd, ref)
    tau = c(0.0, q, qd, ref, measurement=Measurement(tau_applied=np.zeros(7)))
    np.testing.assert_allclose(tau, ct(0.0, q, qd, ref))  # no collision yet: the nominal law
    with pytest.raises(InvalidParameterError, match="thresholds"):
        CollisionReaction(ct, MomentumObserver(dyn, 50.0))
    with pytest.raises(InvalidParameterError, match="reaction"):
        CollisionReaction(ct, obs, reaction="freeze")
    with pytest.raises(InvalidParameterError, match="damping"):
        CollisionReaction(ct, obs, damping=-1.0)
    with pytest.raises(UnknownNameError):
        sc.controller("gravity", {"kpp": 1.0})


def test_the_scene_times_its_controller_with_the_recorded_applied_torques() -> None:
    sc = scene("panda_collision")
    res, _ = run("gravity")
    window = sc.replay_window(res, 20)
    assert len(window["measurement"]) == 20
    assert sc.compute_time("gravity", window, rounds=1) > 0.0


def test_a_diverged_run_keeps_its_joint_error_until_the_divergence() -> None:
    """A diverged run has no tracking error to rank (NaN), and its joint error until the divergence is the RMS and
    max of q − q_ref over the samples it recorded, computed here from the reference itself."""
    sc = scene("panda_collision")
    gains = {"kp": 1e7, "kd": 1e4}  # far beyond the sampled-data border (k·T² ≫ 4), torques unbounded
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SimulationWarning)  # the limits it crosses on its way to diverging
        res = sc.run("no_reaction", gains=gains, saturate=False, duration=0.5)
    assert res.diverged and len(res.t) > 1
    m = sc.metrics(res, "no_reaction", gains=gains, timing_rounds=0)
    assert m["diverged"] and m["diverged_at"] == res.diverged_at
    assert math.isnan(m["rms_error"]) and math.isnan(m["max_error"])
    err = res.q - np.array([sc.reference(t).q for t in res.t])
    assert m["rms_error_until_divergence"] == pytest.approx(float(np.sqrt((err**2).mean())))
    assert m["max_error_until_divergence"] == pytest.approx(float(np.abs(err).max()))
    assert m["error_unit"] == "rad"
    assert math.isnan(m["contact_at"]) or 0.0 <= m["contact_at"] <= res.t[-1]
