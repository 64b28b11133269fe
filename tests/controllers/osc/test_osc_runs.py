"""Closed-loop runs of the operational-space QP that must complete: targets out of reach, joints driven into
their velocity limits, a lower priority level that fails; and inputs whose scale makes the QP meaningless,
refused before any solve. The plant is the controller's own model, integrated at the control rate, so every
recorded sample is a plant step."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import armctl
from armctl import sim
from armctl.controllers.osc import (
    FramePoseTask,
    OperationalSpaceQP,
    PostureTask,
    ProxQPSolver,
    QPFailure,
    SolverChain,
    contact_qp,
    generated_cascade,
)
from armctl.controllers.osc import diagnose as diagnose_module
from armctl.errors import InvalidParameterError, SolverWarning
from tests.controllers.osc.helpers import Q_HOME, panda_dynamics


def _reach(direction: tuple[float, float, float], distance: float, kp: float) -> tuple[FramePoseTask, np.ndarray]:
    """A pose task towards a point ``distance`` [m] from the base along ``direction``, the ready orientation."""
    dyn = panda_dynamics()
    target = dyn.frame_pose(Q_HOME)
    target[:3, 3] = distance * np.asarray(direction) / np.linalg.norm(direction)
    task = FramePoseTask(kp=kp)
    task.set_target(target)
    return task, target


def _run(task: FramePoseTask) -> tuple[OperationalSpaceQP, sim.SimResult, list[warnings.WarningMessage]]:
    """3 s with the default limits (torque, position viability, velocity) and a posture task in the same level."""
    dyn = panda_dynamics()
    ctrl = OperationalSpaceQP(dyn, [task, PostureTask(7, kp=100.0, weight=1e-3)])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = sim.simulate(dyn, ctrl, armctl.Reference(Q_HOME), 3.0, q0=Q_HOME)
    return ctrl, res, caught


def _check_limits(res: sim.SimResult) -> np.ndarray:
    """Torque limits exactly, position limits to 1 µrad (a torque held over the period, not the QP's q̈,
    drives the plant: see JointPositionLimit), velocity limits within 0.1 %; returns |q̇| / q̇_max."""
    model = panda_dynamics().model
    assert not res.diverged and len(res.t) == 3001
    assert (np.abs(res.tau) <= model.effort_limit).all()
    assert (res.q <= model.upper + 1e-6).all() and (res.q >= model.lower - 1e-6).all()
    ratio = np.abs(res.qd) / model.velocity_limit
    assert ratio.max() <= 1.001, ratio.max()
    return ratio


def test_a_target_out_of_reach_gives_the_best_motion_within_the_limits() -> None:
    """1.6 m from the base (the Panda reaches 0.86 m): the run completes within every limit (the solver chain
    re-solves what ProxQP warm-started calls infeasible on this run, which stops a controller that trusts it),
    the arm ends stretched towards the target, and the pose task's residual reports how far the task is from
    met."""
    task, target = _reach((-0.62, 0.67, 0.42), 1.6, 400.0)
    ctrl, res, caught = _run(task)
    ratio = _check_limits(res)
    assert ratio.max() > 0.999  # joints run at their velocity limits on the way
    dyn = panda_dynamics()
    end = dyn.frame_pose(res.q[-1])[:3, 3]
    assert np.linalg.norm(end) > 0.8  # stretched out
    gap = np.linalg.norm(target[:3, 3] - end)
    assert gap > 0.6
    sol = ctrl.last_solution
    assert sol is not None
    # the residual J q̈ + J̇q̇ − ẍ* of the position rows: the arm at rest, ẍ* = kp·(target − tool position)
    np.testing.assert_allclose(np.linalg.norm(sol.residuals[task.name][:3]), 400.0 * gap, rtol=0.05)
    assert all(issubclass(w.category, SolverWarning) for w in caught) and len(caught) <= 1


def test_a_reachable_target_drives_a_joint_to_its_velocity_limit_and_the_limit_holds() -> None:
    """0.78 m from the base, kp 100: joint velocities ride their limits for hundreds of steps and stay within
    0.1 % of them (the bound (q̇_max − q̇)/Δt is exact for a q̈ held over the period; the plant holds τ), the
    run completes (ProxQP warm-started alone calls a QP of this run infeasible, at a velocity limit), and the arm
    comes to rest, its wrist at its position limit 12 cm short of the target, the pose task's residual reporting
    it: at rest J q̈ + J̇q̇ − ẍ* ≈ −kp (p_target − p) on the position rows (to 10 %: the q̈ the QP still asks for
    against the wrist's limit)."""
    task, target = _reach((-0.91, 0.15, 0.38), 0.78, 100.0)
    ctrl, res, _ = _run(task)
    ratio = _check_limits(res)
    assert (ratio > 0.999).sum() > 500
    assert np.abs(res.qd[-1]).max() < 0.01
    model = panda_dynamics().model
    assert min(model.upper[6] - res.q[-1, 6], res.q[-1, 6] - model.lower[6]) < 1e-6
    end = panda_dynamics().frame_pose(res.q[-1])[:3, 3]
    assert 0.05 < np.linalg.norm(target[:3, 3] - end) < 0.2
    sol = ctrl.last_solution
    assert sol is not None
    np.testing.assert_allclose(sol.residuals[task.name][:3], -100.0 * (target[:3, 3] - end), rtol=0.1, atol=0.1)


def test_a_lower_level_that_fails_is_not_diagnosed_in_the_loop_and_warns_once(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Pose task above a posture task, 2 s; the posture's level has no verified optimum on 8 steps (every QP sent
    to the solver chain, which is made to give up on every 250th QP of level 1): the run completes, those steps
    keep the pose level's solution (``level_status`` in the logs), the elastic diagnosis is not called once
    (counted), and one warning says on how many steps; the diagnosis is there on demand."""
    calls = []
    original = diagnose_module.conflicting_rows

    def counted(*args, **kwargs):  # type: ignore[no-untyped-def]
        calls.append(1)
        return original(*args, **kwargs)

    solve = SolverChain.solve
    level1 = []

    def gives_up(self, arrays, slot=0, problem=None):  # type: ignore[no-untyped-def]
        if slot == 1:
            level1.append(1)
            if len(level1) % 250 == 0:
                raise QPFailure([("warm", "made to fail")])
        return solve(self, arrays, slot, problem)

    monkeypatch.setattr(diagnose_module, "conflicting_rows", counted)
    monkeypatch.setattr(SolverChain, "solve", gives_up)
    # every QP to the chain: the optimum on the equality rows alone (taken without a solver) refused
    monkeypatch.setattr(contact_qp, "equality_optimum", lambda *args: None)
    monkeypatch.setattr(generated_cascade.GeneratedCascade, "step", lambda *args: None)
    dyn = panda_dynamics()
    task, _ = _reach((0.5, 0.3, 0.6), 0.7, 400.0)
    ctrl = OperationalSpaceQP(dyn, [task, PostureTask(7, kp=100.0, priority=1)])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = sim.simulate(dyn, ctrl, armctl.Reference(Q_HOME), 2.0, q0=Q_HOME)
    assert not res.diverged and len(res.t) == 2001
    assert calls == []
    kept = [s for s in res.logs["level_status"][:, 1] if s != "solved"]
    assert len(kept) == 8 and all(s.startswith("kept level 0") for s in kept)
    assert len(caught) == 1 and issubclass(caught[0].category, SolverWarning)
    assert "priority level 1 had no verified optimum on 8 steps" in str(caught[0].message)
    assert ctrl.last_solution is not None
    assert ctrl.last_solution.diagnose(1) == {}  # on demand: the level is feasible
    assert len(calls) == 1


@pytest.mark.parametrize(
    ("make", "name"),
    [
        (lambda: _reach((1.0, 0.0, 0.5), 1e300, 400.0)[0], "pose"),  # a target 1e300 m away
        (lambda: _reach((1.0, 0.0, 0.5), 1e7, 400.0)[0], "pose"),  # 10 000 km
        (lambda: _reach((1.0, 0.0, 0.5), 0.6, 1e12)[0], "pose"),  # kp 1e12
    ],
)
@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")  # NumPy's, on a 1e300 m target
def test_out_of_scale_targets_and_gains_are_refused_before_solving(make, name: str) -> None:  # type: ignore[no-untyped-def]
    """Targets or gains that put the task's desired acceleration beyond 1e9 are refused by name, with the
    task's error and gains, and no QP is solved; a target 10 m away (4000 m/s² asked) is still a QP."""

    class Counting(ProxQPSolver):
        calls = 0

        def solve_raw(self, arrays, slot=0, mode="warm"):  # type: ignore[no-untyped-def]
            Counting.calls += 1
            return super().solve_raw(arrays, slot, mode)

    dyn = panda_dynamics()
    for task in (make(), _reach((1.0, 0.0, 0.5), 10.0, 400.0)[0]):
        ctrl = OperationalSpaceQP(dyn, [task, PostureTask(7, weight=1e-3)], solver=Counting())
        Counting.calls = 0
        if np.linalg.norm(task.target.at(0.0)[0][:3, 3]) > 11.0 or float(np.abs(task.kp).max()) > 1e6:
            with pytest.raises(InvalidParameterError, match=rf"task '{name}\[tool\]' asks for .* its kp reaches"):
                ctrl(0.0, Q_HOME, np.zeros(7), armctl.Reference(Q_HOME))
            assert Counting.calls == 0 and ctrl.fallback_counts == {}
        else:
            tau = ctrl(0.0, Q_HOME, np.zeros(7), armctl.Reference(Q_HOME))
            assert (np.abs(tau) <= dyn.model.effort_limit).all() and sum(ctrl.fallback_counts.values()) == 1
