"""The controllers log their main terms, and the terms add up to what they commanded. Each term is checked
against its own formula evaluated from the recorded state and reference, with the model terms from the
Lagrange backend (a second implementation of the dynamics)."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.controllers import ComputedTorque, PassivityBased, PDGravity
from armctl.references import Quintic
from armctl.sim import simulate

KP, KD, KI = 100.0, 20.0, 5.0


@pytest.fixture(scope="module")
def arm() -> tuple[armctl.RobotModel, armctl.Dynamics, Quintic]:
    model = armctl.models.planar_2r().reduced(rotors=False)  # (where both backends model the same arm)
    return model, armctl.Dynamics(model, backend="lagrange"), Quintic([0.0, 0.0], [0.6, -0.4], 0.5)


def _run(arm: tuple, ctrl: armctl.controllers.Controller) -> armctl.sim.SimResult:
    model, _, ref = arm
    return simulate(model, ctrl, ref, 0.5, q0=[0.05, -0.02])


def _feedback(res: armctl.sim.SimResult, kp: float, kd: float) -> np.ndarray:
    return kp * (res.reference.q - res.q) + kd * (res.reference.qd - res.qd)


def test_pd_gravity_logs_feedback_and_gravity(arm: tuple) -> None:
    model, lagrange, _ = arm
    res = _run(arm, PDGravity(armctl.Dynamics(model), KP, KD, ki=KI))
    assert set(res.logs) == {"feedback", "gravity", "integral"}
    np.testing.assert_allclose(res.logs["feedback"], _feedback(res, KP, KD), rtol=1e-12, atol=1e-12)
    gravity = np.array([lagrange.gravity_torque(q) for q in res.q])
    np.testing.assert_allclose(res.logs["gravity"], gravity, rtol=1e-9, atol=1e-9)
    # the integral by the rectangle rule over the samples before each one
    e = res.reference.q - res.q
    integral = KI * np.vstack(([0.0, 0.0], np.cumsum(e[1:] * np.diff(res.t)[:, None], axis=0)))
    np.testing.assert_allclose(res.logs["integral"], integral, rtol=1e-9, atol=1e-12)
    total = res.logs["feedback"] + res.logs["gravity"] + res.logs["integral"]
    np.testing.assert_allclose(total, res.tau, rtol=1e-12, atol=1e-12)


def test_computed_torque_logs_feedforward_and_feedback(arm: tuple) -> None:
    model, lagrange, _ = arm
    res = _run(arm, ComputedTorque(armctl.Dynamics(model), KP, KD))
    assert set(res.logs) == {"feedforward", "feedback"}
    np.testing.assert_array_equal(res.logs["feedforward"], res.reference.qdd)
    np.testing.assert_allclose(res.logs["feedback"], _feedback(res, KP, KD), rtol=1e-12, atol=1e-12)
    v = res.logs["feedforward"] + res.logs["feedback"]
    tau = np.array([lagrange.inverse_dynamics(q, qd, a) for q, qd, a in zip(res.q, res.qd, v, strict=True)])
    np.testing.assert_allclose(tau, res.tau, rtol=1e-9, atol=1e-9)


def test_passivity_logs_model_term_damping_and_s(arm: tuple) -> None:
    model, lagrange, _ = arm
    lam = 5.0
    res = _run(arm, PassivityBased(armctl.Dynamics(model), lam, KD))
    s = (res.qd - res.reference.qd) + lam * (res.q - res.reference.q)  # s = q̃̇ + Λq̃
    np.testing.assert_allclose(res.logs["s"], s, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res.logs["damping"], KD * s, rtol=1e-12, atol=1e-12)
    qd_r = res.reference.qd - lam * (res.q - res.reference.q)
    qdd_r = res.reference.qdd - lam * (res.qd - res.reference.qd)
    # M q̈_r + C q̇_r + g from the Lagrange backend's M and C (friction-free arm)
    want = np.array(
        [
            lagrange.mass_matrix(q) @ a + lagrange.coriolis_matrix(q, qd) @ r + lagrange.gravity_torque(q)
            for q, qd, r, a in zip(res.q, res.qd, qd_r, qdd_r, strict=True)
        ]
    )
    np.testing.assert_allclose(res.logs["model"], want, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(res.logs["model"] - res.logs["damping"], res.tau, rtol=1e-12, atol=1e-12)


def test_friction_compensation_is_logged_as_its_own_term() -> None:
    model = armctl.models.pendulum().with_friction(viscous=0.3, coulomb=0.5)
    ctrl = ComputedTorque(armctl.Dynamics(model), KP, KD)
    res = simulate(model, ctrl, Quintic([0.0], [0.5], 0.5), 0.5)
    want = 0.3 * res.qd + 0.5 * np.sign(res.qd)
    np.testing.assert_allclose(res.logs["friction"], want, rtol=1e-12, atol=1e-12)
