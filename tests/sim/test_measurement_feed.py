"""What `simulate` feeds a controller that reads signals besides q and q̇: the force sensor's wrench at the state
of each sample, the torque applied over the last period (after saturation), measured torques; each through the
measurement chain (noise, first-order filter, delay)."""

from __future__ import annotations

import math
import warnings
from typing import Any, ClassVar

import numpy as np
import pytest

import armctl
from armctl.controllers import Controller, Measurement, PDGravity
from armctl.errors import InvalidParameterError, SimulationWarning
from armctl.sim import Forces, ForceSensor, KelvinVoigt, Plane, Sensing
from armctl.sim.signal_chain import SignalChain

Q0 = np.array([0.5, -1.4])  # the two-link arm's tool at x = 1.500, z = −0.304


class Recording(Controller):
    """A PD + gravity law pushing down, that keeps every measurement it is given."""

    reads: ClassVar[frozenset[str]] = frozenset({"wrench", "tau_applied", "tau_measured"})

    def __init__(self, dyn: armctl.Dynamics, push: float) -> None:
        super().__init__(dyn)
        self.push = push
        self.seen: list[Measurement] = []
        self.inner = PDGravity(dyn, kp=2e3, kd=200.0)

    def compute(self, t, q, qd, ref):  # type: ignore[no-untyped-def]
        m = self.measurement
        assert m is not None
        self.seen.append(m)
        assert self.dynamics is not None
        return self.inner.compute(t, q, qd, ref) + self.dynamics.jacobian(q)[:3].T @ np.array([0.0, 0.0, -self.push])

    def reset(self) -> None:
        super().reset()
        self.seen = []


def _floor() -> Plane:
    return Plane(KelvinVoigt(2e5, 3e3), normal=(0.0, 0.0, 1.0), point=(0.0, 0.0, -0.305))


def _run(push: float = 300.0, **sensing: Any) -> tuple[armctl.sim.SimResult, Recording]:
    dyn = armctl.Dynamics(armctl.models.planar_2r())
    ctrl = Recording(dyn, push)
    res = armctl.simulate(
        dyn,
        ctrl,
        armctl.Reference.hold(Q0),
        0.3,
        sensing=Sensing(sensors=ForceSensor("tool", world_axes=True), **sensing),
        integrator="implicit-euler",
        forces=Forces(environment=_floor()),
    )
    return res, ctrl


def test_the_wrench_and_the_applied_torque_are_those_of_the_sample() -> None:
    res, ctrl = _run()
    assert len(ctrl.seen) == len(res.t)
    wrench = np.array([m.wrench for m in ctrl.seen])
    applied = np.array([m.tau_applied for m in ctrl.seen])
    assert wrench[-1, 2] < -50.0  # the arm presses on the floor: the sensor reads it
    np.testing.assert_array_equal(wrench, res.sensor[:, 0])
    np.testing.assert_array_equal(applied[0], np.zeros(2))
    np.testing.assert_array_equal(applied[1:], res.tau_applied[:-1])
    # without noise, the measured torque is the applied one
    np.testing.assert_array_equal(np.array([m.tau_measured for m in ctrl.seen]), applied)
    assert all(m.world_axes and m.frame == "tool" for m in ctrl.seen)


def test_saturation_is_in_the_applied_torque() -> None:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res, ctrl = _run(push=1e5)  # far beyond the 5000 N·m limits: saturated, and over the velocity limits
    assert any(issubclass(w.category, SimulationWarning) and "torque at its limit" in str(w.message) for w in caught)
    applied = np.array([m.tau_applied for m in ctrl.seen])
    assert np.abs(res.tau).max() > 5000.0
    assert np.abs(applied).max() == pytest.approx(5000.0)
    np.testing.assert_array_equal(applied[1:], res.tau_applied[:-1])


def test_delay_shifts_every_signal() -> None:
    res, ctrl = _run(delay=3)
    wrench = np.array([m.wrench for m in ctrl.seen])
    np.testing.assert_array_equal(wrench[3:], res.sensor[:-3, 0])
    np.testing.assert_array_equal(wrench[:3], np.tile(res.sensor[0, 0], (3, 1)))


def test_noise_is_reproducible_and_leaves_the_joint_noise_alone() -> None:
    a, ca = _run(noise_wrench=0.5, noise_tau=0.1, seed=7)
    _, cb = _run(noise_wrench=0.5, noise_tau=0.1, seed=7)
    plain, _ = _run(seed=7)
    wa = np.array([m.wrench for m in ca.seen])
    np.testing.assert_array_equal(wa, np.array([m.wrench for m in cb.seen]))
    noise = wa - a.sensor[:, 0]
    assert 0.4 < noise.std() < 0.6
    tau_noise = np.array([m.tau_measured - m.tau_applied for m in ca.seen])
    assert 0.08 < tau_noise.std() < 0.12
    np.testing.assert_array_equal(a.q_measured, plain.q_measured)


def test_a_controller_that_reads_the_wrench_needs_a_sensor() -> None:
    dyn = armctl.Dynamics(armctl.models.planar_2r())
    with pytest.raises(InvalidParameterError, match=r"reads 'wrench'.*ForceSensor"):
        armctl.simulate(dyn, Recording(dyn, 0.0), armctl.Reference.hold(Q0), 0.01, forces=Forces(environment=_floor()))


def test_a_plain_callable_gets_the_measurement_as_a_keyword() -> None:
    dyn = armctl.Dynamics(armctl.models.planar_2r())
    pd = PDGravity(dyn, kp=200.0, kd=20.0)
    got: list[Measurement] = []

    class Law:
        reads = frozenset({"tau_applied"})
        n = 2

        def __call__(self, t, q, qd, ref, measurement=None):  # type: ignore[no-untyped-def]
            got.append(measurement)
            return pd(t, q, qd, ref)

    res = armctl.simulate(dyn, Law(), armctl.Reference.hold(Q0), 0.01)
    np.testing.assert_array_equal(np.array([m.tau_applied for m in got])[1:], res.tau_applied[:-1])


def test_a_controller_that_reads_nothing_is_called_as_before() -> None:
    dyn = armctl.Dynamics(armctl.models.planar_2r())
    a = armctl.simulate(
        dyn, PDGravity(dyn, 200.0, 20.0), armctl.Reference.hold(Q0), 0.05, forces=Forces(environment=_floor())
    )
    b = armctl.simulate(
        dyn,
        PDGravity(dyn, 200.0, 20.0),
        armctl.Reference.hold(Q0),
        0.05,
        sensing=Sensing(sensors=ForceSensor("tool"), noise_wrench=1.0),
        forces=Forces(environment=_floor()),
    )
    np.testing.assert_array_equal(a.q, b.q)


# ------------------------------------------------------------------------------------------------ the chain
def test_the_filter_is_the_sampled_first_order_lag() -> None:
    """A unit step through the filter at f_c follows y_k = 1 − exp(−2π f_c k Δt) exactly (the ZOH sampling of
    ẏ = 2π f_c (x − y))."""
    dt, fc = 1e-3, 20.0
    chain = SignalChain(1, dt, cutoff=fc)
    ys = [chain([0.0])[0]] + [chain([1.0])[0] for _ in range(200)]
    k = np.arange(201)
    np.testing.assert_allclose(ys, 1.0 - np.exp(-2.0 * math.pi * fc * k * dt), atol=1e-12)


def test_the_chain_delays_by_whole_samples_and_restarts() -> None:
    chain = SignalChain(2, 1e-3, delay=2)
    out = [chain([float(i), -float(i)]).tolist() for i in range(5)]
    assert out == [[0.0, -0.0], [0.0, -0.0], [0.0, -0.0], [1.0, -1.0], [2.0, -2.0]]
    chain.reset()
    assert chain([9.0, 9.0]).tolist() == [9.0, 9.0]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"cutoff": 0.0}, "cutoff must be a positive"),
        ({"cutoff": math.inf}, "cutoff must be a positive"),
        ({"noise": -1.0}, "noise"),
        ({"delay": -1}, "delay"),
    ],
)
def test_bad_chains_are_refused(kwargs: dict[str, Any], match: str) -> None:
    with pytest.raises(InvalidParameterError, match=match):
        SignalChain(3, 1e-3, **kwargs)
