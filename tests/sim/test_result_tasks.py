"""SimResult of an operational-space contact run: contact forces in both named senses (and the deprecated
alias), the frame tasks' errors, the summary that headlines them, ``tracked``, and ``plot`` of the contact,
wrench, sensor and task quantities (the lines' data checked against the result's arrays)."""

from __future__ import annotations

import warnings
from pathlib import Path

import matplotlib
import numpy as np
import pinocchio as pin
import pytest

import armctl
from armctl.controllers import Controller
from armctl.controllers.osc import Contact, ContactForceTask, FramePoseTask, OperationalSpaceQP, PostureTask
from armctl.errors import InvalidParameterError, UnknownNameError
from armctl.references import Reference
from armctl.sim import Forces, ForceSensor, KelvinVoigt, Plane, Sensing, SimResult, simulate
from armctl.sim.result import _ARRAYS
from tests.sim.helpers import PDGravity

matplotlib.use("Agg")

FORCE, STIFFNESS = 10.0, 2e4


class PressOnTouch(Controller):
    """Lower the tool at 2 cm/s; at the table, switch a sliding contact on, free the pose task's vertical row and
    ramp the normal force to FORCE in 0.2 s."""

    def __init__(self, dyn: armctl.Dynamics, z_table: float, start: np.ndarray) -> None:
        super().__init__(dyn)
        self.z_table, self.start = z_table, start
        self.pose = FramePoseTask(kp=400.0)
        self.pose.set_trajectory(self.target)
        self.contact = Contact(mode="sliding", mu=0.3, active=False)
        self.force = ContactForceTask(self.contact, 0.0, weight=1.0)
        tasks = [self.pose, self.force, PostureTask(dyn.n, kp=25.0, priority=1)]
        self.qp = OperationalSpaceQP(dyn, tasks, contacts=[self.contact])
        self.touched: float | None = None

    def target(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        pose, twist = self.start.copy(), np.zeros(6)
        pose[2, 3] = max(self.start[2, 3] - 0.02 * t, self.z_table - 0.01)
        twist[2] = -0.02 if pose[2, 3] > self.z_table - 0.01 else 0.0
        return pose, twist, np.zeros(6)

    def compute(self, t: float, q: np.ndarray, qd: np.ndarray, ref: Reference) -> np.ndarray:
        if self.touched is None and self.dynamics.frame_pose(q)[2, 3] <= self.z_table:
            self.touched = t
            self.contact.active = True
            self.pose.weight = [1, 1, 0, 1, 1, 1]
        if self.touched is not None:
            self.force.set_target(FORCE * min(1.0, (t - self.touched) / 0.2))
        tau = self.qp.compute(t, q, qd, ref)
        self.last_log = dict(self.qp.last_log)
        return tau


@pytest.fixture(scope="module")
def run() -> tuple[SimResult, PressOnTouch, Plane]:
    model = armctl.models.panda()
    dyn = armctl.Dynamics(model)
    q0 = model.named_poses["ready"]
    start = dyn.frame_pose(q0)
    z_table = float(start[2, 3]) - 0.005
    table = Plane(KelvinVoigt(STIFFNESS, 50.0), normal=(0, 0, 1), point=(0, 0, z_table), friction=0.3)
    ctrl = PressOnTouch(dyn, z_table, start)
    sensors = [ForceSensor(), ForceSensor(world_axes=True)]
    res = simulate(
        model,
        ctrl,
        Reference.hold(q0),
        0.9,
        q0=q0,
        dt=2e-4,
        forces=Forces(environment=table),
        sensing=Sensing(sensors=sensors),
    )
    return res, ctrl, table


def test_the_force_on_the_robot_is_the_force_task_s_sense_and_the_table_s_law(run: tuple) -> None:
    """The table pushes the arm up: +10 N along its normal at the end, the force task's target, and k δ from the
    recorded penetration (Kelvin–Voigt at rest); the force on the environment, the wrench and the sensors read
    the arm's push, its opposite."""
    res, ctrl, table = run
    on_robot = res.contact_force_on_robot[:, 0]
    assert ctrl.touched is not None and res.status == "ok"
    assert on_robot[-1] @ table.normal == pytest.approx(FORCE, rel=5e-3)
    depth = table.point[2] - res.contact_position[-1, 0, 2]
    assert on_robot[-1, 2] == pytest.approx(STIFFNESS * depth, rel=1e-2)
    np.testing.assert_array_equal(res.contact_force_on_environment, -res.contact_force_on_robot)
    np.testing.assert_allclose(res.wrench[:, :3], res.contact_force_on_environment[:, 0], atol=1e-12)
    np.testing.assert_allclose(res.sensor[:, 1, :3], res.contact_force_on_environment[:, 0], atol=1e-9)
    # in the hand's axes (its z points down at the ready pose): the arm's push on the table is +z there
    assert res.sensor[-1, 0, 2] == pytest.approx(FORCE, rel=5e-3)


def test_contact_force_is_a_deprecated_alias_of_the_force_on_the_environment(run: tuple) -> None:
    res = run[0]
    with pytest.warns(DeprecationWarning, match="contact_force_on_environment") as caught:
        old = res.contact_force
    assert caught[0].filename == __file__  # points at the caller's line
    np.testing.assert_array_equal(old, res.contact_force_on_environment)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the new names do not warn
        res.contact_force_on_environment, res.contact_force_on_robot  # noqa: B018


def test_the_old_keyword_still_builds_a_result_and_the_file_keeps_its_entry(run: tuple, tmp_path: Path) -> None:
    res = run[0]
    arrays = {name: getattr(res, name) for name in _ARRAYS}
    arrays["contact_force"] = arrays.pop("contact_force_on_environment")
    old = SimResult(**arrays)
    np.testing.assert_array_equal(old.contact_force_on_environment, res.contact_force_on_environment)
    with pytest.raises(InvalidParameterError, match="not both"):
        SimResult(**arrays, contact_force_on_environment=res.contact_force_on_environment)
    path = res.save(tmp_path / "run")
    with np.load(path) as data:  # files written before the rename read the same entry
        np.testing.assert_array_equal(data["contact_force"], res.contact_force_on_environment)
    back = SimResult.load(path)
    np.testing.assert_array_equal(back.contact_force_on_robot, res.contact_force_on_robot)
    assert back.plant is None and set(back.task_errors) == set(res.task_errors)  # kept by the file
    for key, errors in res.task_errors.items():
        np.testing.assert_array_equal(back.task_errors[key], errors)
    assert repr(back).splitlines()[1:3] == repr(res).splitlines()[1:3]


def test_logged_task_errors_are_the_target_minus_pinocchio_s_pose(run: tuple) -> None:
    """The pose task's errors, checked against Pinocchio's own forward kinematics of the recorded q and the
    controller's target; the vertical row is NaN (free) once the contact holds it."""
    res, ctrl, _ = run
    pos, rot = res.task_errors["position_error[pose[tool]]"], res.task_errors["orientation_error[pose[tool]]"]
    model = armctl.models.panda()
    pm = model.to_pinocchio()
    pd = pm.createData()
    fid = pm.getFrameId(model.tool_frame)
    for k in np.linspace(0, len(res.t) - 1, 25).astype(int):
        pin.framesForwardKinematics(pm, pd, res.q[k])
        target = ctrl.target(float(res.t[k]))[0]
        e_pos = target[:3, 3] - pd.oMf[fid].translation
        e_rot = pin.log3(target[:3, :3] @ pd.oMf[fid].rotation.T)
        free = res.t[k] >= ctrl.touched - 1e-9  # the row is freed at the touch sample itself
        np.testing.assert_allclose(pos[k, :2], e_pos[:2], atol=1e-12)
        assert np.isnan(pos[k, 2]) if free else pos[k, 2] == pytest.approx(e_pos[2], abs=1e-12)
        np.testing.assert_allclose(rot[k], e_rot, atol=1e-12)


def test_the_summary_headlines_the_task_errors_and_the_run_tracked(run: tuple) -> None:
    res = run[0]
    lines = repr(res).splitlines()
    assert lines[0].endswith(": ok")
    assert lines[1].startswith("  pose[tool] position error: RMS")
    assert lines[2].startswith("  pose[tool] orientation error: RMS")
    assert lines[3].startswith("  joint error against the joint reference")
    assert "tracked: yes" in lines[4]
    summary = res.tracking_errors()[0]
    size = np.sqrt(np.nansum(res.task_errors["position_error[pose[tool]]"] ** 2, axis=1))
    assert summary.rms == pytest.approx(float(np.sqrt(np.mean(size**2))), rel=1e-12)
    assert summary.max < 1e-3 and res.tracked is True


def test_tracked_is_no_for_a_joint_run_that_lags_and_for_a_diverged_run() -> None:
    dyn = armctl.Dynamics(armctl.models.planar_2r())
    ref = armctl.references.Quintic([0.0, 0.0], [1.0, -1.0], 1.0)
    soft = simulate(dyn, PDGravity(dyn, 50.0, 20.0), ref, 1.0)
    stiff = simulate(dyn, PDGravity(dyn, 2e5, 2e3), ref, 1.0)
    assert soft.status == stiff.status == "ok"
    assert soft.tracked is False and soft.tracking_errors()[0].rms > 0.02
    assert stiff.tracked is True and "tracked: yes" in repr(stiff)
    assert repr(soft).splitlines()[1].startswith("  tracking error: RMS")
    nan_after = lambda t, q, qd, r: np.full(2, np.nan) if t > 0.01 else dyn.gravity_torque(q)  # noqa: E731
    diverged = simulate(dyn, nan_after, Reference.hold([0.0, 0.0]), 0.05)
    assert diverged.status == "diverged" and diverged.tracking_errors()[0].max < 1e-12 and diverged.tracked is False


def test_plot_draws_contact_wrench_sensor_and_task_errors(run: tuple) -> None:
    res = run[0]
    names = ("contact_force", "contact_force_on_environment", "wrench", "sensor", "position_error", "q")
    fig = res.plot(names, joints=[3])
    axes = fig.axes
    assert len(axes) == len(names)

    def lines(ax: object) -> dict[str, np.ndarray]:
        return {ln.get_label(): np.asarray(ln.get_ydata()) for ln in ax.lines if not ln.get_label().startswith("_")}

    got = lines(axes[0])
    assert list(got) == ["fx", "fy", "fz"] and "on the robot" in axes[0].get_ylabel()
    for i, c in enumerate("xyz"):
        np.testing.assert_array_equal(got[f"f{c}"], res.contact_force_on_robot[:, 0, i])
        np.testing.assert_array_equal(lines(axes[1])[f"f{c}"], res.contact_force_on_environment[:, 0, i])
    for i, c in enumerate(["fx", "fy", "fz", "mx", "my", "mz"]):
        np.testing.assert_array_equal(lines(axes[2])[c], res.wrench[:, i])
        np.testing.assert_array_equal(lines(axes[3])[f"sensor 1: {c}"], res.sensor[:, 1, i])
    pos = res.task_errors["position_error[pose[tool]]"]
    for i, c in enumerate("xyz"):
        np.testing.assert_array_equal(lines(axes[4])[f"pose[tool] {c}"], pos[:, i])
    np.testing.assert_array_equal(lines(axes[5])["panda_joint4"], res.q[:, 3])
    assert "[m]" in axes[4].get_ylabel() and "[N, N·m]" in axes[2].get_ylabel()


def test_plot_refuses_what_the_result_has_nothing_of() -> None:
    dyn = armctl.Dynamics(armctl.models.planar_2r())
    res = simulate(dyn, PDGravity(dyn, 100.0, 20.0), Reference.hold([0.1, 0.1]), 0.05)
    with pytest.raises(InvalidParameterError, match="no position error: its controller logged no frame task"):
        res.plot(("q", "position_error"))
    with pytest.raises(InvalidParameterError, match="no force sensor"):
        res.plot("sensor")
    with pytest.raises(UnknownNameError, match=r"valid quantities: 'q', .*'contact_force', .*'orientation_error'"):
        res.plot("contact")
    assert res.task_errors == {} and len(res.plot("contact_force").axes[0].lines) == 1  # the zero line only
