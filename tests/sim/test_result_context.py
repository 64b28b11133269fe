"""A SimResult carries its context: the reference it was given, its tracking error, how close each joint came
to the plant's limits, and a status that says when the run was saturated or overran a limit."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import armctl
from armctl.controllers import ComputedTorque, PDGravity
from armctl.errors import SimulationWarning
from armctl.references import Quintic
from armctl.sim import simulate
from armctl.sim.limits import SATURATION_SHARE

UR5_GOAL = np.array([0.5, -0.8, 0.9, 0.3, -0.4, 0.6])


def _run(*args: object, **kw: object) -> tuple[armctl.sim.SimResult, list[str]]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = simulate(*args, **kw)  # type: ignore[arg-type]
    return res, [str(w.message) for w in caught if issubclass(w.category, SimulationWarning)]


@pytest.fixture(scope="module")
def ur5_tracking() -> tuple[armctl.sim.SimResult, list[str], Quintic]:
    model = armctl.models.ur5()
    ref = Quintic(np.zeros(6), UR5_GOAL, 1.0)
    res, said = _run(model, ComputedTorque(armctl.Dynamics(model), 100.0, 20.0), ref, 1.0, delay=2)
    return res, said, ref


def test_reference_is_the_one_evaluated_at_every_sample(ur5_tracking: tuple) -> None:
    """res.reference equals the reference evaluated again, independently, at res.t (a delay changes what the
    controller measures, not the reference time); res.error = reference.q − q."""
    res, _, ref = ur5_tracking
    want = [ref(float(t)) for t in res.t]
    assert res.reference.q.shape == res.q.shape == (1001, 6)
    np.testing.assert_array_equal(res.reference.t, res.t)
    for name in ("q", "qd", "qdd"):
        np.testing.assert_allclose(getattr(res.reference, name), [getattr(r, name) for r in want], rtol=0, atol=1e-15)
    np.testing.assert_allclose(res.error, np.array([r.q for r in want]) - res.q, rtol=0, atol=1e-15)
    assert not res.error.flags.writeable and not res.reference.q.flags.writeable
    np.testing.assert_array_equal(res.reference[10].q, want[10].q)


def test_a_fixed_reference_is_recorded_at_every_sample() -> None:
    goal = armctl.Reference([0.3])
    res, _ = _run(armctl.models.pendulum(), PDGravity(armctl.Dynamics(armctl.models.pendulum()), 50.0, 10.0), goal, 0.1)
    np.testing.assert_array_equal(res.reference.q, np.full((101, 1), 0.3))
    np.testing.assert_array_equal(res.reference.qd, np.zeros((101, 1)))
    np.testing.assert_allclose(res.error[:, 0], 0.3 - res.q[:, 0], rtol=0, atol=0)


def _limit_report_by_hand(res: armctl.sim.SimResult, model: armctl.RobotModel) -> dict[str, list[float]]:
    """The per-joint figures of res.limits, from the joints' own JointLimits and the recorded arrays, one joint
    and one sample at a time."""
    out: dict[str, list[float]] = {k: [] for k in ("saturated", "torque_peak", "velocity_peak", "overrun")}
    for j, joint in enumerate(model.joints):
        lim = joint.limits
        tau, qd, q = res.tau[:, j].tolist(), res.qd[:, j].tolist(), res.q[:, j].tolist()
        out["saturated"].append(sum(abs(x) > lim.effort for x in tau) / len(tau))
        out["torque_peak"].append(max(abs(x) for x in tau) / lim.effort)
        out["velocity_peak"].append(max(abs(x) for x in qd) / lim.velocity)
        out["overrun"].append(max(max(lim.lower - x, x - lim.upper, 0.0) for x in q))
    return out


def test_limits_of_a_run_within_them(ur5_tracking: tuple) -> None:
    res, said, _ = ur5_tracking
    by_hand = _limit_report_by_hand(res, armctl.models.ur5())
    np.testing.assert_allclose(res.limits.saturated, by_hand["saturated"], rtol=0, atol=0)
    np.testing.assert_allclose(res.limits.torque_peak, by_hand["torque_peak"], rtol=1e-15)
    np.testing.assert_allclose(res.limits.velocity_peak, by_hand["velocity_peak"], rtol=1e-15)
    np.testing.assert_allclose(res.limits.position_overrun, by_hand["overrun"], rtol=0, atol=0)
    assert res.limits.torque_peak.max() < 1.0 and res.limits.velocity_peak.max() < 1.0
    assert res.status == "ok" and said == []
    assert res.limits.joint_names == armctl.models.ur5().joint_names


@pytest.mark.steps_may_differ("bang-bang torques at the effort limits: rounding differences switch them")
def test_a_run_saturated_on_most_samples_warns_and_says_how_much() -> None:
    """UR5 computed torque at kp = 1e8, kd = 1e5: the command exceeds the effort limits on about 99 % of the
    samples. The run neither diverges nor loses track badly, and still it is reported as saturated."""
    model = armctl.models.ur5()
    ref = Quintic(np.zeros(6), UR5_GOAL, 1.0)
    res, said = _run(model, ComputedTorque(armctl.Dynamics(model), 1e8, 1e5), ref, 1.0)
    by_hand = _limit_report_by_hand(res, model)
    np.testing.assert_allclose(res.limits.saturated, by_hand["saturated"], rtol=0, atol=0)
    assert min(by_hand["saturated"]) > 0.98 and max(by_hand["torque_peak"]) > 100.0
    # clipped at the limits: the applied torque is the command held at ±τ̄ on those samples
    effort = np.array([j.limits.effort for j in model.joints])
    over = np.abs(res.tau) > effort
    np.testing.assert_array_equal(np.abs(res.tau_applied)[over], np.broadcast_to(effort, over.shape)[over])
    assert not res.diverged and res.status == "saturated"
    assert res.limits.saturated_joints() == list(range(6)) and res.limits.is_saturated
    sat = [s for s in said if s.startswith("torque at its limit on most samples")]
    assert len(sat) == 1
    assert f"shoulder_pan_joint {by_hand['saturated'][0]:.0%}" in sat[0]  # which joint, and how much
    assert "saturated" in repr(res) and f"{by_hand['saturated'][0]:.0%}" in repr(res)


def test_saturation_on_a_few_samples_is_counted_but_not_a_status() -> None:
    """A step in the set-point saturates the first samples only: counted in res.limits, below
    SATURATION_SHARE, so the run is "ok" and nothing is said."""
    model = armctl.models.pendulum()
    res, said = _run(model, PDGravity(armctl.Dynamics(model), 400.0, 30.0), armctl.Reference([1.0]), 1.0, q0=[0.0])
    share = float(np.mean(np.abs(res.tau[:, 0]) > 20.0))
    assert 0.0 < share < SATURATION_SHARE
    assert res.limits.saturated[0] == share and res.status == "ok" and said == []


def test_a_position_overrun_is_flagged() -> None:
    """The Panda told to hold joint 4 beyond its upper limit goes there: res.limits says how far, the status is
    "over limits", and a warning names the joint."""
    model = armctl.models.panda()
    q_goal = np.array([0.0, 0.0, 0.0, -1.5, 0.0, 1.5, 0.0])
    q0 = q_goal.copy()
    q_goal[3] = 0.1  # upper limit −0.0698
    res, said = _run(model, PDGravity(armctl.Dynamics(model), 50.0, 10.0), armctl.Reference(q_goal), 1.0, q0=q0)
    by_hand = _limit_report_by_hand(res, model)
    assert by_hand["overrun"][3] > 0.1
    np.testing.assert_allclose(res.limits.position_overrun, by_hand["overrun"], rtol=0, atol=0)
    outside = float(np.mean(res.q[:, 3] > model.joints[3].limits.upper))
    assert res.limits.position_over[3] == outside > 0.3
    assert res.status == "over limits" and res.limits.overrun
    assert any("panda_joint4 outside its position range" in s for s in said)


def test_a_velocity_overrun_is_flagged_beyond_the_tolerance() -> None:
    """The pendulum swung over the top without torque passes its 10 rad/s velocity limit at the bottom."""
    model = armctl.models.pendulum()
    res, said = _run(model, lambda t, q, qd, ref: np.zeros(1), armctl.Reference([np.pi - 0.01]), 2.0, qd0=[7.0])
    peak = float(np.abs(res.qd[:, 0]).max()) / 10.0
    assert peak > 1.01
    assert res.limits.velocity_peak[0] == pytest.approx(peak, rel=1e-15)
    assert res.limits.velocity_over[0] == float(np.mean(np.abs(res.qd[:, 0]) > 10.0 * 1.01))
    assert res.status == "over limits" and any("over its velocity limit" in s for s in said)


def test_reference_and_limits_survive_save_and_load(ur5_tracking: tuple, tmp_path: Path) -> None:
    res, _, _ = ur5_tracking
    back = type(res).load(res.save(tmp_path / "run"))
    for name in ("q", "qd", "qdd"):
        np.testing.assert_array_equal(getattr(back.reference, name), getattr(res.reference, name))
    np.testing.assert_array_equal(back.error, res.error)
    for name in ("saturated", "torque_peak", "velocity_peak", "position_overrun", "effort"):
        np.testing.assert_array_equal(getattr(back.limits, name), getattr(res.limits, name))
    assert back.joint_names == res.joint_names and back.status == res.status


def test_repr_summarises_the_run(ur5_tracking: tuple) -> None:
    res, _, _ = ur5_tracking
    text = repr(res)
    rms = float(np.sqrt((res.error**2).mean()))
    assert text.startswith("SimResult(ur5, n = 6, 1001 samples over 1 s, rk4): ok")
    assert f"RMS {rms:.3g}" in text and "peak |τ applied|" in text
