"""Force control, parallel force/position control and admittance pressing on a compliant plane, fed the
plane's force as a user's loop would read a force/torque sensor: parallel force/position control and force
control with integral action reach the desired force exactly at rest, wherever the surface is; admittance at
rest gives the series-spring force k_e k_d / (k_e + k_d) δ_c; the force can come from an observer object."""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin
import pytest

import armctl
from armctl.controllers import Admittance, Controller, ForceControl, Measurement, ParallelForcePosition
from armctl.sim import ForceSensor, KelvinVoigt, Plane

Q_READY = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
KE = 2e4  # [N/m] the plane's stiffness


@pytest.fixture(scope="module")
def panda() -> armctl.Dynamics:
    return armctl.Dynamics(armctl.models.panda())


class PlaneSensor(Controller):
    """A user's loop around a force-reading controller: the wrench the arm exerts on ``plane`` at the tool,
    computed from the measured state with the plane's own law, handed over as a Measurement (world axes)."""

    def __init__(self, dyn: armctl.Dynamics, plane: Plane, inner: Controller) -> None:
        super().__init__(dyn)
        self.plane, self.inner = plane, inner

    def reset(self) -> None:
        super().reset()
        self.inner.reset()

    def compute(self, t: float, q: Any, qd: Any, ref: armctl.Reference) -> Any:
        assert self.dynamics is not None
        p = self.dynamics.frame_pose(q)[:3, 3]
        v = self.dynamics.jacobian(q)[:3] @ qd
        force_on_arm = self.plane.force(p, v, False)[0]
        h = np.zeros(6) if force_on_arm is None else np.concatenate((-force_on_arm, np.zeros(3)))
        tau = self.inner(t, q, qd, ref, measurement=Measurement(wrench=h, world_axes=True))
        self.last_log = dict(self.inner.last_log)
        return tau


def press(dyn: armctl.Dynamics, ctrl: Controller, z_surface: float, duration: float) -> Any:
    plane = Plane(KelvinVoigt(KE, 100.0), point=(0.0, 0.0, z_surface))
    return armctl.simulate(
        dyn.model,
        PlaneSensor(dyn, plane, ctrl),
        armctl.Reference(Q_READY),
        duration,
        q0=Q_READY,
        dt=2e-4,
        environment=plane,
        sensors=ForceSensor(world_axes=True),
    )


@pytest.mark.parametrize("inner", ["computed_torque", "osc"])
def test_parallel_force_position_has_no_force_error_at_rest(panda: armctl.Dynamics, inner: str) -> None:
    pose = panda.frame_pose(Q_READY)
    z_surface = pose[2, 3] - 0.003  # unknown to the controller: its target is 2 mm above the tool
    target = pose.copy()
    target[2, 3] += 0.002
    target[0, 3] += 0.01  # and 1 cm along x
    ctrl = ParallelForcePosition(panda, [0.0, 0.0, -10.0], 2e-4, 1e-3, inner=inner)
    ctrl.set_target(target)
    res = press(panda, ctrl, z_surface, 3.0)
    assert not res.diverged
    f = res.sensor[:, 0, :3]
    assert f[-1, 2] == pytest.approx(-10.0, abs=1e-3)  # the simulator's reading: 10 N down, exactly
    assert np.abs(f[-1, :2]).max() < 1e-3  # nothing along the surface
    x_end = panda.frame_pose(res.q[-1])[:3, 3]
    np.testing.assert_allclose(x_end[:2], target[:2, 3], atol=1e-4)  # the position target along the surface


def test_force_control_with_integral_action_has_no_force_error_at_rest(panda: armctl.Dynamics) -> None:
    pose = panda.frame_pose(Q_READY)
    z_surface = pose[2, 3] - 0.002
    ctrl = ForceControl(panda, [0.0, 0.0, -15.0], 1e-4, 1e-3, directions=[0.0, 0.0, 1.0])
    target = pose.copy()
    target[1, 3] += 0.02  # along y: position control
    ctrl.set_target(target)
    res = press(panda, ctrl, z_surface, 3.0)
    assert not res.diverged
    assert res.sensor[-1, 0, 2] == pytest.approx(-15.0, abs=1e-3)
    assert panda.frame_pose(res.q[-1])[1, 3] == pytest.approx(target[1, 3], abs=1e-4)


def test_proportional_force_control_leaves_the_predicted_error(panda: armctl.Dynamics) -> None:
    # K_I = 0: at rest f_d − f = (f_d − k_e δ_d) / (1 + k_e K_F), δ_d the target's depth beyond the surface
    pose = panda.frame_pose(Q_READY)
    z_surface = pose[2, 3] - 0.002
    kf, fd, depth = 2e-4, 10.0, 0.0002  # k_e δ_d = 4 N: an error of 1.2 N
    ctrl = ForceControl(panda, [0.0, 0.0, -fd], kf, directions=[0.0, 0.0, 1.0])
    target = pose.copy()
    target[2, 3] = z_surface - depth
    ctrl.set_target(target)
    res = press(panda, ctrl, z_surface, 2.0)
    normal = -res.sensor[-1, 0, 2]
    assert fd - normal == pytest.approx((fd - KE * depth) / (1.0 + KE * kf), rel=0.01)


def test_admittance_at_rest_gives_the_series_spring_force(panda: armctl.Dynamics) -> None:
    pose = panda.frame_pose(Q_READY)
    z_surface = pose[2, 3] - 0.002
    kd, depth = 500.0, 0.01
    ctrl = Admittance(panda, [kd, kd, kd, 50.0, 50.0, 50.0])
    target = pose.copy()
    target[2, 3] = z_surface - depth
    ctrl.set_target(target)
    res = press(panda, ctrl, z_surface, 2.0)
    assert -res.sensor[-1, 0, 2] == pytest.approx(KE * kd / (KE + kd) * depth, rel=0.01)


class PlaneObserver:
    """An observer-like force source: reports the plane's force (arm side) at the tool; counts its updates."""

    def __init__(self, dyn: armctl.Dynamics, plane: Plane) -> None:
        self.dyn, self.plane, self.updates, self.q, self.qd = dyn, plane, 0, None, None

    def update(self, t: float, q: Any, qd: Any, tau_applied: Any) -> Any:
        self.updates += 1
        self.q, self.qd = q, qd
        return np.zeros(len(q))

    def wrench(self, q: Any, frame: str | None = None) -> Any:
        p = self.dyn.frame_pose(q)[:3, 3]
        f = self.plane.force(p, self.dyn.jacobian(q)[:3] @ self.qd, False)[0]
        return np.zeros(6) if f is None else np.concatenate((-f, np.zeros(3)))


def test_an_observer_is_a_force_source(panda: armctl.Dynamics) -> None:
    pose = panda.frame_pose(Q_READY)
    plane = Plane(KelvinVoigt(KE, 100.0), point=(0.0, 0.0, pose[2, 3] - 0.002))
    obs = PlaneObserver(panda, plane)
    ctrl = ParallelForcePosition(panda, [0.0, 0.0, -10.0], 2e-4, 1e-3, force_source=obs)
    assert ctrl.reads == {"tau_applied"}
    ctrl.set_target(pose)

    def loop(t: float, q: Any, qd: Any, ref: armctl.Reference) -> Any:
        return ctrl(t, q, qd, ref, measurement=Measurement(tau_applied=np.zeros(7)))

    res = armctl.simulate(
        panda.model,
        loop,
        armctl.Reference(Q_READY),
        3.0,
        q0=Q_READY,
        dt=2e-4,
        environment=plane,
        sensors=ForceSensor(world_axes=True),
    )
    assert obs.updates == len(res.t) - 1 or obs.updates == len(res.t)
    assert res.sensor[-1, 0, 2] == pytest.approx(-10.0, abs=1e-3)


@pytest.mark.parametrize("world_axes", [False, True])
def test_simulate_feeds_the_sensor_reading(panda: armctl.Dynamics, world_axes: bool) -> None:
    # the sensor reads in its own (tool) axes or in world axes: the controller turns either into world axes
    pose = panda.frame_pose(Q_READY)
    plane = Plane(KelvinVoigt(KE, 100.0), point=(0.0, 0.0, pose[2, 3] - 0.002))
    ctrl = ParallelForcePosition(panda, [0.0, 0.0, -10.0], 2e-4, 1e-3)
    ctrl.set_target(pose)
    res = armctl.simulate(
        panda.model,
        ctrl,
        armctl.Reference(Q_READY),
        3.0,
        q0=Q_READY,
        dt=2e-4,
        environment=plane,
        sensors=ForceSensor(world_axes=world_axes),
    )
    assert not res.diverged
    rot = panda.frame_pose(res.q[-1])[:3, :3]
    f_world = res.sensor[-1, 0, :3] if world_axes else rot @ res.sensor[-1, 0, :3]
    np.testing.assert_allclose(f_world, [0.0, 0.0, -10.0], atol=1e-3)


@pytest.mark.parametrize("inner", ["computed_torque", "osc"])
def test_generated_inner_loop_matches_the_numpy_loop(panda: armctl.Dynamics, inner: str) -> None:
    # two implementations: generated C from the recursive algorithms and CasADi, and Pinocchio with NumPy
    made = [
        ForceControl(panda, [0.0, 0.0, -5.0], 1e-4, 1e-3, directions=[0.0, 0.0, 1.0], inner=inner, compile=c)
        for c in (True, False)
    ]
    assert made[0].inner.generated is not None and made[1].inner.generated is None
    rng = np.random.default_rng(11)
    target = panda.frame_pose(Q_READY)
    twist = np.array([0.05, -0.02, 0.0, 0.1, 0.0, -0.1])
    for c in made:
        c.set_target(target, twist)
    for k in range(5):
        q = Q_READY + rng.uniform(-0.4, 0.4, 7)
        qd = rng.uniform(-1.0, 1.0, 7)
        m = Measurement(wrench=rng.normal(size=6), world_axes=bool(k % 2))
        ref = armctl.Reference(Q_READY + rng.uniform(-0.2, 0.2, 7))
        fast, slow = (c(0.001 * k, q, qd, ref, measurement=m) for c in made)
        np.testing.assert_allclose(fast, slow, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(made[0].last_log["error"], made[1].last_log["error"], atol=1e-12)


def test_admittance_yields_to_a_moment_by_its_rotational_stiffness(panda: armctl.Dynamics) -> None:
    # a constant wrench the arm exerts (a moment about z): at rest the tool has turned by −K⁻¹ m
    push = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.5])
    k = np.array([500.0, 500.0, 500.0, 20.0, 20.0, 10.0])
    ctrl = Admittance(panda, k)
    target = panda.frame_pose(Q_READY)
    ctrl.set_target(target)

    def loop(t: float, q: Any, qd: Any, ref: armctl.Reference) -> Any:
        return ctrl(t, q, qd, ref, measurement=Measurement(wrench=push, world_axes=True))

    res = armctl.simulate(panda.model, loop, armctl.Reference(Q_READY), 3.0, q0=Q_READY, disturbance=lambda t: push)
    rot = panda.frame_pose(res.q[-1])[:3, :3]
    turned = pin.log3(rot @ target[:3, :3].T)
    np.testing.assert_allclose(turned, -push[3:] / k[3:], atol=1e-4)
    np.testing.assert_allclose(panda.frame_pose(res.q[-1])[:3, 3], target[:3, 3], atol=1e-5)


@pytest.mark.parametrize("axes", [6, 3])
def test_generated_admittance_matches_the_numpy_admittance(panda: armctl.Dynamics, axes: int) -> None:
    k = [500.0, 400.0, 600.0, 20.0, 30.0, 25.0][:axes]
    made = [Admittance(panda, k, compile=c) for c in (True, False)]
    assert made[0].inner.generated is not None and made[1].inner.generated is None
    rng = np.random.default_rng(5)
    target = panda.frame_pose(Q_READY)
    for c in made:
        c.set_target(target, [0.02, 0.0, -0.01, 0.0, 0.1, 0.0])
    for k_step in range(6):
        q = Q_READY + rng.uniform(-0.3, 0.3, 7)
        qd = rng.uniform(-1.0, 1.0, 7)
        m = Measurement(wrench=rng.normal(size=6) * 5.0, world_axes=True)
        ref = armctl.Reference(Q_READY)
        fast, slow = (c(0.01 * k_step, q, qd, ref, measurement=m) for c in made)
        np.testing.assert_allclose(fast, slow, rtol=1e-8, atol=1e-8)
        np.testing.assert_allclose(made[0].last_log["compliant"], made[1].last_log["compliant"], atol=1e-12)
