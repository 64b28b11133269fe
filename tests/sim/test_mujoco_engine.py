"""``simulate(..., engine="mujoco")``: the native closed loop on a MuJoCo plant.

References: armctl's own simulator where both model the same plant (frictionless, RK4 in both: the same scheme
on the same equations, so the runs agree to rounding); statics for the press on a MuJoCo floor (at rest
J_pᵀ h = τ − g(q), with τ the recorded applied torque and J_p, g from armctl); the Coulomb level for breakaway.
"""

from __future__ import annotations

import pickle
import re
import sys
from typing import ClassVar

import numpy as np
import pytest

import armctl
from armctl.controllers import Measurement
from armctl.errors import InvalidParameterError, ModelLoadError, OptionalDependencyError, UnknownNameError
from armctl.model import Frame, Joint, JointFriction, Link, Motor
from armctl.model.parts import transform
from armctl.references import Sinusoid
from armctl.sim import ForceSensor, MujocoPlant, Sensing, simulate
from armctl.sim.options import regroup
from tests.helpers.mjcf_arms import SPATIAL_ARM
from tests.sim.helpers import ComputedTorque, ForceControl, OpenLoop, PDGravity

pytestmark = pytest.mark.mujoco

REF = Sinusoid(center=[0.2, 0.5, 0.3], amplitude=[0.6, 0.4, 0.8], frequency=[0.7, 1.1, 1.5])


@pytest.fixture(scope="module")
def mj():  # type: ignore[no-untyped-def]
    return pytest.importorskip("mujoco")


@pytest.fixture(scope="module")
def arm(mj) -> armctl.RobotModel:  # type: ignore[no-untyped-def]
    """The spatial arm without joint friction (armature kept)."""
    return armctl.RobotModel.from_mjcf(SPATIAL_ARM, tool_frame="tool").reduced(friction=False)


def both(model: armctl.RobotModel, controller, **options):  # type: ignore[no-untyped-def]
    q0 = REF(0.0).q + np.array([0.1, -0.1, 0.1])
    native = simulate(model, controller, REF, 1.0, q0=q0, **regroup(options))
    mujoco = simulate(model, controller, REF, 1.0, q0=q0, engine="mujoco", **regroup(options))
    return native, mujoco


def test_closed_loop_equals_the_native_one(arm: armctl.RobotModel) -> None:
    """Frictionless, RK4 in both, 1 kHz control, 1 s: the same trajectory within 1e-6 rad (seen: 4e-15)."""
    native, mujoco = both(arm, PDGravity(armctl.Dynamics(arm), 40.0, 4.0), integrator="rk4")
    assert np.ptp(native.q, axis=0).min() > 0.5  # every joint moved
    assert not mujoco.diverged and mujoco.info["engine"] == "mujoco" and mujoco.info["integrator"] == "rk4"
    assert np.abs(native.q - mujoco.q).max() <= 1e-6
    assert np.abs(native.qdd - mujoco.qdd).max() <= 1e-6 * np.abs(native.qdd).max()
    assert np.abs(native.tau - mujoco.tau).max() <= 1e-6 * np.abs(native.tau).max()


def test_sub_steps_euler_and_the_panda(mj) -> None:  # type: ignore[no-untyped-def]
    """Four RK4 sub-steps per period on the Panda, and MuJoCo's Euler (semi-implicit, velocity form: armctl's
    "euler") on a plant without damping, against the native runs."""
    panda = armctl.models.panda()
    dyn = armctl.Dynamics(panda)
    ref = Sinusoid(center=[0, -0.4, 0, -2, 0, 1.6, 0.8], amplitude=[0.3] * 7, frequency=[0.5] * 7)
    ctrl = ComputedTorque(dyn, 100.0, 20.0)  # (stiff PD gains on the light wrist would amplify rounding)
    q0 = ref(0.0).q + 0.05
    for integrator, dt in (("rk4", 2.5e-4), ("euler", 1e-3)):
        a = simulate(dyn, ctrl, ref, 0.5, q0=q0, dt=dt, integrator=integrator)
        b = simulate(dyn, ctrl, ref, 0.5, q0=q0, dt=dt, integrator=integrator, engine="mujoco")
        assert b.info["substeps"] == round(1e-3 / dt)
        assert np.abs(a.q - b.q).max() <= 1e-9, integrator


def test_noise_delay_and_saturation_as_in_the_native_loop(arm: armctl.RobotModel) -> None:
    """The same seed gives the same measurement noise; the delay and the saturation act alike."""
    ctrl = PDGravity(armctl.Dynamics(arm), 400.0, 10.0)  # stiff: the wrist's 8 N·m limit clips
    options = {"noise_q": 1e-3, "noise_qd": 1e-2, "seed": 4, "delay": 2}
    native, mujoco = both(arm, ctrl, **options)
    assert (mujoco.tau != mujoco.tau_applied).any(axis=1).sum() > 50
    assert np.array_equal(native.tau != native.tau_applied, mujoco.tau != mujoco.tau_applied)
    assert np.abs(native.q - mujoco.q).max() <= 1e-6
    assert np.abs(native.q_measured - mujoco.q_measured).max() <= 1e-6
    assert mujoco.info["seed"] == 4 and mujoco.info["delay"] == 2


def test_disturbance_is_held_over_each_step(arm: armctl.RobotModel) -> None:
    """A wrench on the tool: its joint torque −J_toolᵀ h_d is held over each MuJoCo step (the native RK4 follows J
    inside the step), so the runs differ by O(dt): ten times less at a ten times smaller step."""
    ctrl = PDGravity(armctl.Dynamics(arm), 40.0, 4.0)
    wrench = np.array([0.0, 0.0, -5.0, 0.1, 0.0, 0.0])
    gaps = []
    for dt in (1e-3, 1e-4):
        native, mujoco = both(arm, ctrl, disturbance=lambda t: wrench, dt=dt)
        assert np.abs(mujoco.wrench - wrench).max() == 0.0
        gaps.append(np.abs(native.q - mujoco.q).max())
    assert gaps[0] < 1e-3
    assert 7.0 < gaps[0] / gaps[1] < 13.0


def test_press_on_a_mujoco_floor_gives_the_static_force(mj) -> None:  # type: ignore[no-untyped-def]
    """The arm of the user's scene pushes its fingertip sphere down on the scene's plane with 20 N; at rest the
    recorded contact force h must satisfy J_pᵀ h = τ − g(q) (J_p at the sphere's lowest point, τ the applied
    torque, both from armctl), within 2 %."""
    plant = MujocoPlant(SPATIAL_ARM, tool_frame="tool")
    dyn = armctl.Dynamics(plant.model)
    q0 = [0.2, 0.7, -0.0129]  # the fingertip 1 cm above the floor
    res = simulate(
        plant,
        ForceControl(dyn, [0.0, 0.0, -20.0], kd=2.0),
        armctl.Reference.hold(q0),
        2.0,
        q0=q0,
        engine="mujoco",
        integrator="implicitfast",
        saturate=False,
        sensing=Sensing(sensors=ForceSensor("tool", world_axes=True)),
    )
    assert res.info["contact"] and not res.diverged
    q, tau = res.q[-1], res.tau_applied[-1]
    assert np.abs(res.qd[-1]).max() < 1e-6  # at rest
    jac = dyn.jacobian(q, "tool")
    r = np.array([0.0, 0.0, -0.02])  # the sphere's lowest point, from its centre
    skew = np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
    jp = jac[:3] - skew @ jac[3:]
    predicted = np.linalg.solve(jp.T, tau - dyn.gravity_torque(q) + res.tau_friction[-1])
    h = res.contact_force_on_environment[-1]
    assert np.abs(h[:2]).max() == 0.0  # only the last link touches
    assert np.linalg.norm(h[2] - predicted) <= 0.02 * np.linalg.norm(predicted)
    assert abs(predicted[2] + 20.0) < 0.4  # what the controller commands
    assert np.abs(res.wrench[-1, :3] - h[2]).max() <= 1e-12
    assert np.abs(res.sensor[-1, 0, :3] - h[2]).max() <= 1e-12
    assert np.abs(res.tau_ext[-1] - jp.T @ h[2]).max() <= 0.02 * np.abs(jp.T @ h[2]).max()


class _ReadingForceControl(ForceControl):
    """:class:`ForceControl` that reads the force sensor and the applied torque, and keeps what it is given."""

    reads: ClassVar[frozenset[str]] = frozenset({"wrench", "tau_applied"})

    def __init__(self, dyn: armctl.Dynamics, force: list[float], kd: float) -> None:
        super().__init__(dyn, np.array(force), kd)
        self.seen: list[Measurement] = []

    def compute(self, t, q, qd, ref):  # type: ignore[no-untyped-def]
        assert self.measurement is not None
        self.seen.append(self.measurement)
        return super().compute(t, q, qd, ref)


def test_a_controller_that_reads_the_force_sensor_is_fed_on_mujoco(mj) -> None:  # type: ignore[no-untyped-def]
    """The press of :func:`test_press_on_a_mujoco_floor_gives_the_static_force` by a controller that reads the
    wrench and the applied torque: the wrench it reads at rest is the commanded 20 N down (statics), the same as the
    recorded sensor to the rounding of the held torque; the applied torque it reads at sample k is row k − 1 of the
    record (zeros first)."""
    plant = MujocoPlant(SPATIAL_ARM, tool_frame="tool")
    dyn = armctl.Dynamics(plant.model)
    q0 = [0.2, 0.7, -0.0129]
    ctrl = _ReadingForceControl(dyn, [0.0, 0.0, -20.0], kd=2.0)
    res = simulate(
        plant,
        ctrl,
        armctl.Reference.hold(q0),
        2.0,
        q0=q0,
        engine="mujoco",
        integrator="implicitfast",
        saturate=False,
        sensing=Sensing(sensors=ForceSensor("tool", world_axes=True)),
    )
    assert len(ctrl.seen) == len(res.t) and not res.diverged
    wrench = np.array([m.wrench for m in ctrl.seen])
    applied = np.array([m.tau_applied for m in ctrl.seen])
    np.testing.assert_array_equal(applied[0], np.zeros(3))
    np.testing.assert_array_equal(applied[1:], res.tau_applied[:-1])
    assert np.abs(wrench[0]).max() == 0.0  # 1 cm above the floor at the start
    assert np.abs(wrench[-1, :3] - [0.0, 0.0, -20.0]).max() < 0.4
    assert np.abs(wrench[-1] - res.sensor[-1, 0]).max() <= 1e-6 * 20.0


def _turntable() -> armctl.RobotModel:
    """One vertical-axis joint (no gravity torque), Coulomb friction 0.5 N·m, damping, armature."""
    joint = Joint(
        "j",
        "revolute",
        (0.0, 0.0, 1.0),
        np.eye(4),
        Link(2.0, (0.3, 0.0, 0.0), np.diag([0.001, 0.01, 0.01])),
        Motor(0.02, 1.0, gyroscopic=False),
        JointFriction(viscous=0.05, coulomb=0.5),
    )
    return armctl.RobotModel((joint,), "turntable", frames=(Frame("tool", 1, transform(None, (0.4, 0, 0))),))


def test_joint_friction_is_frictionloss(mj) -> None:  # type: ignore[no-untyped-def]
    """Above the Coulomb level both engines slide the same (RK4: the friction force is the Coulomb level in both);
    below it armctl's stick–slip model holds the joint exactly, MuJoCo's soft frictionloss lets it creep."""
    model = _turntable()
    hold = armctl.Reference.hold([0.0])
    runs = {}
    for tau in (0.3, 1.0):
        for engine in ("native", "mujoco"):
            runs[tau, engine] = simulate(model, OpenLoop(lambda t, tau=tau: np.array([tau])), hold, 0.5, engine=engine)
    slide_native, slide_mujoco = runs[1.0, "native"].q[-1, 0], runs[1.0, "mujoco"].q[-1, 0]
    assert slide_native > 0.2
    assert abs(slide_mujoco - slide_native) <= 1e-9 * slide_native
    assert runs[1.0, "mujoco"].info["friction"] == "frictionloss"
    assert np.all(runs[0.3, "native"].q == 0.0)  # exact sticking
    creep = np.abs(runs[0.3, "mujoco"].q).max()
    assert 1e-6 < creep < 1e-2
    assert runs[0.3, "mujoco"].stuck[1:].all() and not runs[1.0, "mujoco"].stuck[-1].any()
    friction = runs[0.3, "mujoco"].tau_friction[-1, 0]
    assert 0.29 < friction < 0.3  # holds (almost) all the load


# its run saturates the torque, as expected
@pytest.mark.filterwarnings("ignore:torque at its limit on most samples:armctl.errors.SimulationWarning")
def test_divergence_is_a_result(arm: armctl.RobotModel) -> None:
    def late_nan(t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        return np.full(3, np.nan) if t >= 0.25 else np.zeros(3)

    res = simulate(arm, late_nan, REF, 1.0, engine="mujoco")
    assert res.diverged and res.diverged_at == pytest.approx(0.25) and "non-finite torque" in res.divergence
    native = simulate(arm, late_nan, REF, 1.0)
    assert len(res.t) == len(native.t) == 250  # the samples before the bad torque
    fast = simulate(arm, OpenLoop(lambda t: np.full(3, 1e4)), REF, 1.0, engine="mujoco", saturate=False)
    assert fast.diverged and "max_velocity" in fast.divergence and fast.diverged_at < 1.0


def test_what_the_engine_does_not_take(arm: armctl.RobotModel) -> None:
    ctrl = PDGravity(armctl.Dynamics(arm), 40.0, 4.0)
    with pytest.raises(UnknownNameError, match="unknown engine 'bullet'; valid engines: 'native', 'mujoco'"):
        simulate(arm, ctrl, REF, 0.1, engine="bullet")
    with pytest.raises(UnknownNameError, match=r"unknown MuJoCo integrator 'semi-implicit-euler'.*'implicitfast'"):
        simulate(arm, ctrl, REF, 0.1, integrator="semi-implicit-euler", engine="mujoco")
    plane = armctl.sim.Plane(armctl.sim.KelvinVoigt(1e4))
    for option, value in (("environment", plane), ("friction", "smooth"), ("compile", True)):
        with pytest.raises(InvalidParameterError, match=f"{option}=.* is not available with engine='mujoco'"):
            simulate(arm, ctrl, REF, 0.1, engine="mujoco", **regroup({option: value}))
    with pytest.raises(ModelLoadError, match="must be the same, in the same order"):
        MujocoPlant(SPATIAL_ARM, model=armctl.models.planar_3r())


def test_a_mujoco_plant_pickles(mj) -> None:  # type: ignore[no-untyped-def]
    """(for sweeps in worker processes)"""
    plant = pickle.loads(pickle.dumps(MujocoPlant(SPATIAL_ARM, tool_frame="tool")))
    res = simulate(
        plant, OpenLoop(lambda t: np.zeros(3)), armctl.Reference.hold([0.2, 0.7, 0.0]), 0.05, engine="mujoco"
    )
    assert res.q.shape == (51, 3) and plant.model.tool_frame == "tool"


def test_missing_mujoco_is_a_clear_error(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "mujoco", None)  # `import mujoco` now raises ImportError
    model = armctl.models.planar_2r()
    with pytest.raises(OptionalDependencyError, match=re.escape("needs MuJoCo, which is not installed")) as info:
        simulate(model, OpenLoop(lambda t: np.zeros(2)), armctl.Reference.hold([0.0, 0.0]), 0.1, engine="mujoco")
    assert 'pip install "armctl[mujoco]"' in str(info.value) and isinstance(info.value, ImportError)


def test_a_controller_that_raises_keeps_the_samples_up_to_it() -> None:
    """On MuJoCo's plant too: the exception propagates with the samples simulated up to it."""
    pytest.importorskip("mujoco")
    model = armctl.models.planar_2r()
    dyn = armctl.Dynamics(model)
    law = PDGravity(dyn, 50.0, 10.0)

    def breaks(t, q, qd, ref):  # type: ignore[no-untyped-def]
        if t >= 0.05:
            raise ZeroDivisionError("the law divided by zero")
        return law.compute(t, q, qd, ref)

    ref = armctl.Reference.hold([0.5, -0.3])
    with pytest.raises(ZeroDivisionError) as info:
        simulate(dyn, breaks, ref, 0.1, engine="mujoco")
    part = info.value.result  # type: ignore[attr-defined]
    assert len(part.t) == 51 and np.isnan(part.tau[50]).all() and np.isfinite(part.tau[:50]).all()
    np.testing.assert_array_equal(part.reference.q[:50], np.tile([0.5, -0.3], (50, 1)))
