"""Zero-order hold, sub-steps, measurement delay and noise, saturation, references and controller logs,
checked against the exact discretisation of a sliding mass written out here."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.sim import Forces, Sensing, simulate
from tests.sim.helpers import ComputedTorque, OpenLoop, slider, zero_torque

MASS = 2.0


class PositionP:
    """u = −K (q_measured − r), counting its resets and recording what it saw."""

    def __init__(self, gain: float) -> None:
        self.gain = gain
        self.resets = 0
        self.seen: list[tuple[float, float, float]] = []

    def reset(self) -> None:
        self.resets += 1
        self.seen.clear()

    def __call__(self, t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        self.seen.append((t, float(q[0]), float(ref.q[0])))
        return -self.gain * (q - ref.q)


def exact_zoh(gain: float, period: float, steps: int, delay: int, q0: float, r: float = 0.0) -> np.ndarray:
    """q_k of a mass under u_k = −K(q_{k−d} − r) held over each period: the exact discretisation
    x_{k+1} = A x_k + B u_k, A = [[1, T], [0, 1]], B = [T²/2m, T/m]."""
    a = np.array([[1.0, period], [0.0, 1.0]])
    b = np.array([period**2 / (2 * MASS), period / MASS])
    x = np.array([q0, 0.0])
    qs = [q0]
    for k in range(steps):
        u = -gain * (qs[max(k - delay, 0)] - r)
        x = a @ x + b * u
        qs.append(x[0])
    return np.array(qs)


@pytest.mark.parametrize("dt", [None, 2.5e-4, 1e-4])
@pytest.mark.parametrize("delay", [0, 3])
def test_zero_order_hold_with_substeps_and_delay_is_the_exact_discretisation(dt: float | None, delay: int) -> None:
    gain, period = 400.0, 2e-3
    ctrl = PositionP(gain)
    res = simulate(
        slider(MASS),
        ctrl,
        armctl.Reference.hold([0.0]),
        0.5,
        q0=[0.1],
        control_dt=period,
        dt=dt,
        sensing=Sensing(delay=delay),
    )
    expected = exact_zoh(gain, period, 250, delay, 0.1)
    np.testing.assert_allclose(res.q[:, 0], expected, atol=1e-12)
    assert res.info["substeps"] == (1 if dt is None else round(period / dt))
    # the torque is constant over each period: commanded from the measurement `delay` periods before
    np.testing.assert_allclose(res.tau[:, 0], -gain * expected[np.maximum(np.arange(251) - delay, 0)], atol=1e-9)
    assert ctrl.resets == 1 and len(ctrl.seen) == 251


def test_reference_callable_is_sampled_at_control_instants() -> None:
    ctrl = PositionP(10.0)

    def ref(t: float) -> armctl.Reference:
        return armctl.Reference([np.sin(3 * t)], [3 * np.cos(3 * t)])

    res = simulate(slider(MASS), ctrl, ref, 0.2, control_dt=4e-3)
    t_seen, _, r_seen = np.array(ctrl.seen).T
    np.testing.assert_allclose(t_seen, res.t)
    np.testing.assert_allclose(r_seen, np.sin(3 * res.t))
    assert res.q[0, 0] == 0.0 and res.qd[0, 0] == pytest.approx(3.0)  # started on the reference


def test_measurement_noise_is_seeded_and_has_the_asked_deviation() -> None:
    runs = [
        simulate(slider(MASS), zero_torque, armctl.Reference.hold([0.3]), 2.0, sensing=Sensing([2e-3], 0.05, s))
        for s in (7, 7, 8)
    ]
    np.testing.assert_array_equal(runs[0].q_measured, runs[1].q_measured)
    assert not np.array_equal(runs[0].q_measured, runs[2].q_measured)
    res = runs[0]
    assert (res.q == 0.3).all()  # noise is in the measurement, not the plant
    assert np.std(res.q_measured - res.q) == pytest.approx(2e-3, rel=0.1)
    assert np.std(res.qd_measured - res.qd) == pytest.approx(0.05, rel=0.1)


def test_the_same_seed_gives_the_same_noise_whatever_the_duration() -> None:
    """A longer run is the shorter one continued: over their common samples the measurements agree."""
    noisy = Sensing(noise_q=2e-3, noise_qd=0.05, seed=11)
    short, long = (
        simulate(slider(MASS), zero_torque, armctl.Reference.hold([0.3]), d, sensing=noisy) for d in (0.5, 1.0)
    )
    k = len(short.t)
    np.testing.assert_array_equal(long.q_measured[:k], short.q_measured)
    np.testing.assert_array_equal(long.qd_measured[:k], short.qd_measured)


# its run saturates the torque, as expected
@pytest.mark.filterwarnings("ignore:torque at its limit on most samples:armctl.errors.SimulationWarning")
def test_torques_saturate_at_the_effort_limits() -> None:
    model = slider(MASS, effort=5.0)
    push = OpenLoop(lambda t: np.array([12.0]))
    res = simulate(model, push, armctl.Reference.hold([0.0]), 0.2)
    assert (res.tau == 12.0).all() and (res.tau_applied == 5.0).all()
    assert res.q[-1, 0] == pytest.approx(0.5 * 5.0 / MASS * 0.2**2, rel=1e-12)
    free = simulate(model, push, armctl.Reference.hold([0.0]), 0.2, saturate=False)
    assert free.q[-1, 0] == pytest.approx(0.5 * 12.0 / MASS * 0.2**2, rel=1e-12)


def test_controller_logs_are_stacked_per_sample() -> None:
    dyn = armctl.Dynamics(armctl.models.planar_2r())
    res = simulate(dyn, ComputedTorque(dyn, 100.0, 20.0), armctl.Reference.hold([0.2, 0.1]), 0.5, q0=[0.0, 0.0])
    err = res.logs["error_norm"]
    assert err.shape == (501,)
    assert err[0] == pytest.approx(np.hypot(0.2, 0.1)) and err[-1] < 0.06 * err[0]
    np.testing.assert_allclose(err, np.linalg.norm(res.q - [0.2, 0.1], axis=1), rtol=1e-12)


# its run saturates the torque, as expected
@pytest.mark.filterwarnings("ignore:torque at its limit on most samples:armctl.errors.SimulationWarning")
def test_qdd_is_the_acceleration_at_each_sample() -> None:
    """Recorded q̈ against Dynamics.forward_dynamics of the recorded state and applied torque."""
    dyn = armctl.Dynamics(armctl.models.planar_2r())
    for integrator in ("rk4", "implicit-euler", "semi-implicit-euler", "euler"):
        res = simulate(
            dyn,
            ComputedTorque(dyn, 50.0, 10.0),
            armctl.Reference.hold([0.5, -0.5]),
            0.05,
            integrator=integrator,
            q0=[0.0, 0.0],
        )
        for k in (0, 17, 50):
            expected = dyn.forward_dynamics(res.q[k], res.qd[k], res.tau_applied[k])
            np.testing.assert_allclose(res.qdd[k], expected, rtol=1e-9, atol=1e-9)


@pytest.mark.steps_may_differ("RK4 gains energy on this contact (res.info['energy_gain']): rounding differences grow")
def test_runs_are_deterministic() -> None:
    """The same scene twice in one process (friction, contact, events) gives bit-identical results: no state
    survives a run and nothing uninitialised enters one."""
    from armctl.sim import KelvinVoigt, Plane

    model = armctl.models.planar_2r().with_friction(viscous=10.0, coulomb=30.0, static=40.0)
    dyn = armctl.Dynamics(model)
    wall = Plane(KelvinVoigt(1e5, 1e3), normal=(-1.0, 0.0, 0.0), point=(1.6, 0.0, 0.0), friction=0.3)
    runs = [
        simulate(
            model,
            ComputedTorque(dyn, 100.0, 20.0),
            armctl.Reference.hold([0.4, -0.2]),
            0.5,
            q0=[1.0, -0.5],
            integrator=integ,
            forces=Forces(environment=wall),
        )
        for integ in ("rk4", "rk4", "implicit-euler", "implicit-euler")
    ]
    for a, b in (runs[:2], runs[2:]):
        np.testing.assert_array_equal(a.q, b.q)
        np.testing.assert_array_equal(a.contact_force_on_environment, b.contact_force_on_environment)
        np.testing.assert_array_equal(a.work_friction, b.work_friction)
