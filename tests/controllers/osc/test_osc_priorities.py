"""Weights inside a level and strict priorities across levels, against references written here:
the classic null-space recursion for unconstrained levels, weighted least squares inside a level, and
scipy's bounded least squares for a level under torque limits."""

from __future__ import annotations

import numpy as np
from scipy.optimize import lsq_linear
from scipy.spatial.transform import Rotation

import armctl
from armctl.controllers.osc import (
    FrameOrientationTask,
    FramePoseTask,
    FramePositionTask,
    OperationalSpaceQP,
    PostureTask,
    TorqueLimit,
)

from .conftest import Q_HOME

KP, KD = 100.0, 20.0


def _drift(dyn: armctl.Dynamics, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    h = 1e-7
    return (dyn.jacobian(q + h * qd) @ qd - dyn.jacobian(q - h * qd) @ qd) / (2 * h)


def _setup(dyn: armctl.Dynamics, q: np.ndarray, qd: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Targets for a position, an orientation and a posture task, and each task's (J, b) with
    J q̈ = b the wanted acceleration (PD law written out here)."""
    pose = dyn.frame_pose(q)
    J, drift, v = dyn.jacobian(q), _drift(dyn, q, qd), dyn.jacobian(q) @ qd
    p_ref = pose[:3, 3] + [0.03, -0.02, 0.04]
    r_ref = Rotation.from_rotvec([0.1, 0.05, -0.08]).as_matrix() @ pose[:3, :3]
    q_ref = q + 0.2
    e_o = Rotation.from_matrix(r_ref @ pose[:3, :3].T).as_rotvec()
    return {
        "position": (J[:3], KP * (p_ref - pose[:3, 3]) - KD * v[:3] - drift[:3], p_ref),
        "orientation": (J[3:], KP * e_o - KD * v[3:] - drift[3:], r_ref),
        "posture": (np.eye(7), KP * (q_ref - q) - KD * qd, q_ref),
    }


def _tasks(refs: dict, priorities: dict[str, int], weights: dict[str, float] | None = None) -> list:
    w = weights or {}
    pos = FramePositionTask(kp=KP, kd=KD, priority=priorities["position"], weight=w.get("position", 1.0))
    pos.set_target(refs["position"][2])
    ori = FrameOrientationTask(kp=KP, kd=KD, priority=priorities["orientation"], weight=w.get("orientation", 1.0))
    ori.set_target(refs["orientation"][2])
    post = PostureTask(7, kp=KP, kd=KD, priority=priorities["posture"], weight=w.get("posture", 1.0))
    post.set_target(refs["posture"][2])
    return [pos, ori, post]


def test_three_strict_levels_match_the_null_space_recursion(panda: armctl.Dynamics) -> None:
    q, qd = Q_HOME + 0.1, np.linspace(-0.3, 0.3, 7)
    refs = _setup(panda, q, qd)
    ctrl = OperationalSpaceQP(
        panda, _tasks(refs, {"position": 0, "orientation": 1, "posture": 2}), limits=[TorqueLimit()]
    )
    assert ctrl.priorities == [0, 1, 2]
    sol = ctrl.solve(0.0, q, qd, armctl.Reference(q))
    # reference: x₁ = J₁⁺b₁, then each level in the null space of those above
    x, N = np.zeros(7), np.eye(7)
    for name in ("position", "orientation", "posture"):
        J, b, _ = refs[name]
        JN = J @ N
        x = x + np.linalg.pinv(JN, rcond=1e-10) @ (b - J @ x)
        N = N - np.linalg.pinv(JN, rcond=1e-10) @ JN
    np.testing.assert_allclose(sol.qdd, x, atol=1e-4)
    assert sol.level_status == ("solved", "solved", "solved")
    assert ctrl.verify_last_step()  # every level's solution passes the optimality check again


def test_weights_inside_a_level_are_weighted_least_squares(panda: armctl.Dynamics) -> None:
    q, qd = Q_HOME - 0.1, np.zeros(7)
    refs = _setup(panda, q, qd)
    w = {"position": 4.0, "orientation": 1.0, "posture": 0.05}
    ctrl = OperationalSpaceQP(
        panda, _tasks(refs, {"position": 0, "orientation": 0, "posture": 0}, w), limits=[TorqueLimit()]
    )
    sol = ctrl.solve(0.0, q, qd, armctl.Reference(q))
    A = np.vstack([np.sqrt(w[k]) * refs[k][0] for k in ("position", "orientation", "posture")])
    b = np.concatenate([np.sqrt(w[k]) * refs[k][1] for k in ("position", "orientation", "posture")])
    np.testing.assert_allclose(sol.qdd, np.linalg.lstsq(A, b, rcond=None)[0], atol=1e-5)


def test_tight_torque_limits_lower_priority_gives_way_first(panda: armctl.Dynamics) -> None:
    """Shrinking the torque limits: the posture (priority 1) loses accuracy first while the position task
    (priority 0) is still met exactly; when it too is out of reach its residual is the optimum of bounded least
    squares over τ (scipy). τ saturates cleanly: within the limits, some at them."""
    q, qd = Q_HOME, np.zeros(7)
    refs = _setup(panda, q, qd)
    M, h = panda.mass_matrix(q), panda.inverse_dynamics(q, qd, np.zeros(7))
    J1, b1, _ = refs["position"]
    rows = []
    for scale in (1.0, 0.6, 0.4, 0.3, 0.2, 0.1):
        tasks = _tasks(refs, {"position": 0, "orientation": 1, "posture": 1})
        ctrl = OperationalSpaceQP(panda, tasks, limits=[TorqueLimit(scale=scale)])
        sol = ctrl.solve(0.0, q, qd, armctl.Reference(q))
        limit = scale * panda.model.effort_limit
        assert (np.abs(sol.tau) <= limit + 1e-6).all()
        # level 0 against bounded least squares in τ: q̈ = M⁻¹(τ − h)
        JMi = J1 @ np.linalg.inv(M)
        best = lsq_linear(JMi, b1 + JMi @ h, bounds=(-limit, limit), tol=1e-12, method="bvls")
        r1 = np.linalg.norm(sol.residuals["position[tool]"])
        assert abs(r1 - np.linalg.norm(best.fun)) < 1e-4 * (1 + r1)
        r2 = np.linalg.norm(np.r_[sol.residuals["orientation[tool]"], sol.residuals["posture"]])
        saturated = bool((np.abs(sol.tau) > limit - 1e-6).any())
        rows.append((scale, r1, r2, saturated))
    r1s, r2s = np.array([r[1] for r in rows]), np.array([r[2] for r in rows])
    first_posture = int(np.argmax(r2s > r2s[0] * 1.01))  # first scale at which the posture gave way
    first_position = int(np.argmax(r1s > 1e-4))
    assert 0 < first_posture < first_position, rows
    assert r1s[first_posture] < 1e-4 and rows[first_posture][3]  # saturated, position still exact
    assert rows[-1][3] and r1s[-1] > 1e-3  # at the tightest limits even the position gives way


def test_a_level_whose_solve_fails_still_outranks_the_levels_below(panda: armctl.Dynamics) -> None:
    """Level 1 fails (a solver made to fail there, in every mode, no first stage and no second solver): the
    controller keeps level 0's solution for it, and level 2 may not move level 1's residual away from what that
    solution gives it."""
    from armctl.controllers.osc.solve import ProxQPSolver
    from armctl.errors import SolverError

    class FailsOnLevel1(ProxQPSolver):
        def solve_raw(self, arrays, slot=0, mode="warm"):  # type: ignore[no-untyped-def]
            if slot == 1:
                raise SolverError("made to fail")
            return super().solve_raw(arrays, slot, mode)

    q, qd = Q_HOME + 0.1, np.linspace(-0.3, 0.3, 7)
    refs = _setup(panda, q, qd)
    priorities = {"position": 0, "orientation": 1, "posture": 2}
    ctrl = OperationalSpaceQP(
        panda,
        _tasks(refs, priorities),
        limits=[TorqueLimit()],
        solver=FailsOnLevel1(),
        fallback_solver=None,
        slacks=True,
    )
    ctrl.chain.first = None
    sol = ctrl.solve(0.0, q, qd, armctl.Reference(q))
    assert sol.level_status[0] == "solved" and sol.level_status[1].startswith("kept level 0")
    assert sol.level_status[2] == "solved"
    # level 2 may move only within what levels 0 and 1 leave free: J₀, J₁ at level 0's solution x₀
    J0, b0, _ = refs["position"]
    J1, _, _ = refs["orientation"]
    J2, b2, _ = refs["posture"]
    x0 = sol.solutions[0].x[sol.step.variables["qdd"]]
    np.testing.assert_allclose(J0 @ sol.qdd, b0, atol=1e-4)
    np.testing.assert_allclose(J1 @ sol.qdd, J1 @ x0, atol=1e-4)  # level 1's residual as level 0 left it
    # and within that, level 2 does its best (least squares in the null space of [J₀; J₁], written here)
    J01 = np.vstack([J0, J1])
    N = np.eye(7) - np.linalg.pinv(J01) @ J01
    best = x0 + np.linalg.pinv(J2 @ N, rcond=1e-10) @ (b2 - J2 @ x0)
    assert np.linalg.norm(J2 @ sol.qdd - b2) <= np.linalg.norm(J2 @ best - b2) * (1 + 1e-6) + 1e-6


def test_frozen_rows_are_an_orthonormal_basis_of_the_levels_above(panda: armctl.Dynamics) -> None:
    """A pose task (level 0) above a position task of the same frame (level 1), the posture below: the rows
    that freeze levels 0 and 1 in level 2's QP are orthonormal (hierarchy module docstring: dependent rows never
    make the equality rows rank-deficient), as many as the rank of [J_pose; J_position] (numpy), spanning
    exactly those Jacobians' rows, and hold at the solution the values of level 1's solution."""
    q, qd = Q_HOME, np.full(7, 0.1)
    target = panda.frame_pose(q)
    target[:3, 3] += [0.05, 0.0, 0.0]
    pose = FramePoseTask(priority=0)
    pose.set_target(target)
    position = FramePositionTask(priority=1)
    position.set_target(target[:3, 3] + [0.0, 0.02, 0.0])
    ctrl = OperationalSpaceQP(panda, [pose, position, PostureTask(7, priority=2)], limits=[TorqueLimit()])
    sol = ctrl.solve(0.0, q, qd, armctl.Reference(q))
    assert sol.level_status == ("solved", "solved", "solved")
    p = sol.problem(2)
    frozen = [i for i, name in enumerate(p.eq_names) if name.startswith("priority[")]
    F = p.A[frozen]
    J = panda.jacobian(q)
    rows = np.zeros((9, p.nx))  # [J_pose; J_position] on the q̈ block of x
    rows[:, p.variables["qdd"]] = np.vstack([J, J[:3]])
    assert len(frozen) == np.linalg.matrix_rank(rows) == 6
    np.testing.assert_allclose(F @ F.T, np.eye(6), atol=1e-12)
    np.testing.assert_allclose(rows @ F.T @ F, rows, atol=1e-10)  # same row space
    np.testing.assert_allclose(F @ sol.x, F @ sol.solutions[1].x[: p.nx], atol=1e-6)
