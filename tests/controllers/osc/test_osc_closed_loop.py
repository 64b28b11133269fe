"""Closed-loop behaviour of the operational-space QP in armctl's simulator, with joint friction
(viscous + Coulomb, real stiction in the plant). Errors are measured from the plant's own kinematics against
the references written here."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import armctl
from armctl import sim
from armctl.controllers.osc import (
    ClosedFormOSC,
    FramePoseTask,
    FramePositionTask,
    OperationalSpaceQP,
    PostureTask,
    TorqueLimit,
)
from armctl.errors import SimulationWarning
from armctl.scenes.panda_contact import PressAndSlide
from armctl.sim import Forces
from tests.controllers.osc.helpers import Q_HOME, panda_dynamics

Q_SINGULAR = np.array([0.0, 0.3, 0.0, -0.46700102, 0.0, 1.571, 0.785])  # σ_min(J) ≈ 2e-7, see test_osc_closed_form


def _circle(p0: np.ndarray, radius: float = 0.05, freq: float = 0.5):  # type: ignore[no-untyped-def]
    """A horizontal circle of diameter 2·radius through the start pose p0 (4×4), orientation held."""
    w = 2 * math.pi * freq

    def fn(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        c, s = math.cos(w * t), math.sin(w * t)
        pose = p0.copy()
        pose[0, 3] += radius * (c - 1.0)
        pose[1, 3] += radius * s
        return (
            pose,
            np.array([-radius * w * s, radius * w * c, 0, 0, 0, 0.0]),
            np.array([-radius * w * w * c, -radius * w * w * s, 0, 0, 0, 0.0]),
        )

    return fn


def _position_errors(dyn: armctl.Dynamics, res, target) -> np.ndarray:  # type: ignore[no-untyped-def]
    return np.array(
        [np.linalg.norm(dyn.frame_pose(q)[:3, 3] - target(t)[0][:3, 3]) for t, q in zip(res.t, res.q, strict=True)]
    )


def test_circle_tracking_with_the_exact_model() -> None:
    """10 cm circle at 0.5 Hz: position RMS ≤ 1 mm, the torque limits never exceeded."""
    dyn = panda_dynamics(friction=True)
    circle = _circle(dyn.frame_pose(Q_HOME))
    task = FramePoseTask(kp=400.0)
    task.set_trajectory(circle)
    ctrl = OperationalSpaceQP(dyn, [task, PostureTask(7, kp=25.0, priority=1)])  # default limits
    qd0 = np.linalg.pinv(dyn.jacobian(Q_HOME)) @ circle(0.0)[1]  # start on the circle's velocity
    res = sim.simulate(dyn, ctrl, armctl.Reference(Q_HOME), 2.0, q0=Q_HOME, qd0=qd0)
    assert not res.diverged
    err = _position_errors(dyn, res, circle)
    assert math.sqrt(np.mean(err**2)) <= 1e-3, err.max()
    assert (np.abs(res.tau) <= dyn.model.effort_limit).all()
    assert (np.abs(res.qd) <= dyn.model.velocity_limit).all()


def test_press_and_slide_on_a_table_with_friction() -> None:
    """Approach, press with 10 N, slide 10 cm against μ = 0.3: after settling the normal force stays within
    ±10 % of 10 N, contact is never lost (no bounce), and the slide is done; the plant feels the contact as
    −Jᵀh_e (the simulator's plane)."""
    dyn = panda_dynamics(friction=True)
    z_table, mu = dyn.frame_pose(Q_HOME)[2, 3] - 0.005, 0.3
    scene = PressAndSlide(dyn, z_table, mu, slide_start=0.75, slide_time=1.0)
    plane = sim.Plane(sim.KelvinVoigt(2e4, 50.0), normal=(0, 0, 1), point=(0, 0, z_table), friction=mu)
    with warnings.catch_warnings():
        warnings.simplefilter("error", SimulationWarning)  # a run the simulator vouches for: at 1 ms steps the
        # friction's regularisation below its slip velocity is too stiff for RK4 (armctl.sim.after_run)
        res = sim.simulate(
            dyn, scene, armctl.Reference(Q_HOME), 1.95, q0=Q_HOME, dt=2e-4, forces=Forces(environment=plane)
        )
    assert not res.diverged and scene.touched is not None
    fn = res.contact_force_on_robot[:, 0, 2]  # the table's push on the arm [N]
    touch = int(np.searchsorted(res.t, scene.touched))
    assert (fn[touch + 1 :] > 0).all()  # never leaves the table
    settled = res.t >= scene.touched + 0.4
    assert np.abs(fn[settled] - 10.0).max() <= 1.0, (fn[settled].min(), fn[settled].max())
    x = np.array([dyn.frame_pose(q)[:3, 3] for q in res.q])
    assert abs(x[-1, 0] - x[0, 0] - 0.1) < 2e-3  # slid the 10 cm
    assert (x[settled, 2] < z_table).all()  # pressed into the (compliant) table all along
    assert (np.abs(res.tau) <= dyn.model.effort_limit).all()


def _through_singularity():  # type: ignore[no-untyped-def]
    """A joint path crossing Q_SINGULAR at t = 0.5 s and the tool pose along it (a feasible trajectory)."""
    dyn = panda_dynamics(friction=True)
    v = np.zeros(7)
    v[1], v[3] = 0.1, -0.3

    def path(t: float) -> np.ndarray:
        return Q_SINGULAR + (t - 0.5) * v

    def target(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        q, h = path(t), 1e-6
        drift = (dyn.jacobian(q + h * v) - dyn.jacobian(q - h * v)) @ v / (2 * h)
        return dyn.frame_pose(q), dyn.jacobian(q) @ v, drift

    return dyn, path, v, target


def test_through_a_singularity_closed_form_spikes_and_the_qp_degrades_gracefully() -> None:
    """Tracking a pose trajectory through a singular configuration: the closed-form controller asks for
    torques far beyond the limits (the plant clips them), the QP stays within them and keeps tracking."""
    dyn, path, v, target = _through_singularity()
    ratios, errors = {}, {}
    for kind in ("closed_form", "qp"):
        task = FramePoseTask(kp=100.0)
        task.set_trajectory(target)
        ctrl = (
            ClosedFormOSC(dyn, task, PostureTask(7, kp=25.0))
            if kind == "closed_form"
            else OperationalSpaceQP(dyn, [task, PostureTask(7, kp=25.0, priority=1)])
        )
        res = sim.simulate(dyn, ctrl, lambda t: armctl.Reference(path(t), v), 1.0, q0=path(0.0), qd0=v)
        assert not res.diverged
        sigma = min(np.linalg.svd(dyn.jacobian(q), compute_uv=False).min() for q in res.q[400:600])
        assert sigma < 1e-3  # the arm did go through the singular configuration
        ratios[kind] = np.max(np.abs(res.tau) / dyn.model.effort_limit)
        errors[kind] = _position_errors(dyn, res, target).max()
    assert ratios["closed_form"] > 3.0  # the spike, shown
    assert ratios["qp"] <= 1.0
    assert errors["qp"] < 2e-3  # graceful: it still tracks within 2 mm


# its run goes beyond a velocity limit on the way, as expected
@pytest.mark.filterwarnings("ignore:the run went beyond the plant's limits:armctl.errors.SimulationWarning")
def test_tight_torque_limits_posture_gives_way_before_the_task() -> None:
    """Holding the tool still (priority 0) while the posture (priority 1) swings the elbow along the null
    space at 2 Hz, with the torque limits at 100 % and then 28 % of the Panda's (gravity alone needs 25 % on
    joint 4): with tight limits the torques saturate cleanly (within the limits, few entries into saturation,
    no chattering) and the posture tracks worse, while the position hold does not."""
    import scipy.linalg

    dyn = panda_dynamics(friction=True)
    p_hold = dyn.frame_pose(Q_HOME)[:3, 3]
    swing = 0.4 * scipy.linalg.null_space(dyn.jacobian(Q_HOME)[:3])[:, 0]  # a self-motion direction
    w = 4 * math.pi

    def ref(t: float) -> armctl.Reference:
        return armctl.Reference(
            Q_HOME + swing * math.sin(w * t), swing * w * math.cos(w * t), -swing * w * w * math.sin(w * t)
        )

    out = {}
    for scale in (1.0, 0.28):
        task = FramePositionTask(kp=400.0)
        task.set_target(p_hold)
        ctrl = OperationalSpaceQP(dyn, [task, PostureTask(7, kp=400.0, priority=1)], limits=[TorqueLimit(scale=scale)])
        res = sim.simulate(dyn, ctrl, ref, 1.0, q0=Q_HOME, qd0=ref(0.0).qd)
        assert not res.diverged
        limit = scale * dyn.model.effort_limit
        assert (np.abs(res.tau) <= limit).all()
        pos_rms = math.sqrt(np.mean([np.sum((dyn.frame_pose(q)[:3, 3] - p_hold) ** 2) for q in res.q]))
        post_rms = math.sqrt(np.mean([np.sum((q - ref(t).q) ** 2) for t, q in zip(res.t, res.q, strict=True)]))
        saturated = np.abs(res.tau) >= limit - 1e-6
        entries = int((np.diff(saturated.astype(int), axis=0) == 1).sum())
        out[scale] = (pos_rms, post_rms, int(saturated.sum()), entries)
    (pos_loose, post_loose, sat_loose, _), (pos_tight, post_tight, sat_tight, entries) = out[1.0], out[0.28]
    assert sat_loose == 0 and sat_tight > 100, out  # the tight run saturates, often
    assert entries <= 0.15 * sat_tight, out  # in long stretches, not in and out at every step
    assert post_tight > 1.3 * post_loose, out  # the posture gave way
    assert pos_tight <= 1e-3 and pos_loose <= 1e-3, out  # the position hold did not
