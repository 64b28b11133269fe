"""Divergence stops the run and is reported with time and state, never raised and never a NaN trajectory."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.sim import simulate
from tests.sim.helpers import slider

MASS, PERIOD = 2.0, 1e-3


class SampledPD:
    """u = −k_p q − k_d q̇ on the measured state."""

    def __init__(self, kp: float, kd: float) -> None:
        self.kp, self.kd = kp, kd

    def __call__(self, t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        return -self.kp * q - self.kd * qd


def spectral_radius(kp: float, kd: float) -> float:
    """Largest |eigenvalue| of the sampled loop x_{k+1} = (A − B K) x_k of a mass under a held PD."""
    a = np.array([[1.0, PERIOD], [0.0, 1.0]])
    b = np.array([[PERIOD**2 / (2 * MASS)], [PERIOD / MASS]])
    return float(np.abs(np.linalg.eigvals(a - b @ np.array([[kp, kd]]))).max())


@pytest.mark.parametrize(("kd", "stable"), [(40.0, True), (5000.0, False)])
def test_sampled_high_gain_diverges_where_theory_says_so(kd: float, stable: bool) -> None:
    kp = 400.0
    assert (spectral_radius(kp, kd) < 1.0) == stable
    res = simulate(slider(MASS), SampledPD(kp, kd), armctl.Reference.hold([0.0]), 2.0, q0=[0.1])
    assert res.diverged != stable
    if stable:
        assert abs(res.q[-1, 0]) < 1e-3
        assert res.diverged_at is None and res.divergence == "" and res.diverged_q is None
        return
    assert 0.0 < res.diverged_at < 2.0  # type: ignore[operator]
    assert "max_velocity" in res.divergence
    assert np.abs(res.diverged_qd).max() > 1e3  # type: ignore[arg-type]
    n = len(res.t)
    assert res.t[-1] == pytest.approx(res.diverged_at - PERIOD)
    for name in ("q", "qd", "qdd", "tau", "tau_applied", "energy", "work_actuator"):
        arr = getattr(res, name)
        assert len(arr) == n and np.isfinite(arr).all(), name
    assert "diverged" in repr(res)


def test_a_controller_that_returns_nan_is_a_divergence() -> None:
    def flaky(t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        return np.array([np.nan]) if t >= 0.05 else np.array([1.0])

    res = simulate(slider(MASS), flaky, armctl.Reference.hold([0.0]), 0.2)
    assert res.diverged and res.diverged_at == pytest.approx(0.05)
    assert "non-finite torque" in res.divergence
    assert len(res.t) == 50 and np.isfinite(res.q).all()
    assert res.diverged_q is not None and np.isfinite(res.diverged_q).all()


def test_position_bound() -> None:
    push = lambda t, q, qd, ref: np.array([100.0])  # noqa: E731
    res = simulate(slider(MASS), push, armctl.Reference.hold([0.0]), 1.0, max_position=2.0)
    assert res.diverged and "max_position" in res.divergence
    assert res.diverged_q[0] > 2.0 and (np.abs(res.q) <= 2.0).all()  # type: ignore[index]
    # 0.5 (F/m) t² = 2 → t = 0.283 s; detected at the first sample beyond
    assert res.diverged_at == pytest.approx(np.sqrt(2 * 2.0 * MASS / 100.0), abs=2e-3)


# its run goes beyond a velocity limit on the way, as expected
@pytest.mark.filterwarnings("ignore:the run went beyond the plant's limits:armctl.errors.SimulationWarning")
# its run saturates the torque, as expected
@pytest.mark.filterwarnings("ignore:torque at its limit on most samples:armctl.errors.SimulationWarning")
def test_unstable_closed_loop_on_an_arm_reports_instead_of_raising() -> None:
    """Positive position feedback on the Panda: it runs away; the result says when and where."""
    dyn = armctl.Dynamics(armctl.models.panda())
    q0 = np.array([0.0, -0.4, 0.0, -2.0, 0.0, 1.6, 0.8])

    def runaway(t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        return dyn.gravity_torque(q) + 500.0 * (q - ref.q) + 50.0 * qd

    res = simulate(dyn, runaway, armctl.Reference.hold(q0 + 0.01), 3.0, q0=q0, max_velocity=50.0, saturate=False)
    assert res.diverged and res.diverged_at < 3.0  # type: ignore[operator]
    assert np.abs(res.diverged_qd).max() > 50.0  # type: ignore[arg-type]
    assert np.isfinite(res.q).all() and np.abs(res.qd).max() <= 50.0
