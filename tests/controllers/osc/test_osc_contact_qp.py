"""With active contacts the controller solves its QPs on [q̈; f] (τ eliminated): the torque is the optimum of the
public problem on [q̈; τ; f] as an independent solver (quadprog) finds it, level by level, and the solution the
controller reports satisfies the public problem's optimality conditions."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

import armctl
from armctl.controllers.osc import (
    Contact,
    ContactForceTask,
    FramePoseTask,
    OperationalSpaceQP,
    PostureTask,
    QpsolversSolver,
    TorqueLimit,
    default_limits,
)
from armctl.controllers.osc.hierarchy import extend_basis
from armctl.controllers.osc.optimality import residuals

from .helpers import Q_HOME, panda_dynamics, quadprog_solvers

qpsolvers = quadprog_solvers()


def _fixed(friction: bool = False, compile: bool | str = "auto", solver: object = "proxsuite") -> OperationalSpaceQP:
    """A fixed point contact (μ 0.3, 4 facets) with a force target (0, 0, 10) N, a pose task and a posture task
    in the same level, torque limits."""
    dyn = panda_dynamics(friction=friction)
    pose = FramePoseTask(kp=400.0)
    pose.set_target(dyn.frame_pose(Q_HOME))
    contact = Contact(mu=0.3, facets=4)
    tasks = [pose, PostureTask(7, kp=100.0, weight=1e-3), ContactForceTask(contact, (0.0, 0.0, 10.0))]
    return OperationalSpaceQP(dyn, tasks, limits=[TorqueLimit()], contacts=[contact], compile=compile, solver=solver)


def _sliding(friction: bool = True) -> OperationalSpaceQP:
    """A sliding contact with a normal force target, the pose task with its normal direction off, the posture at
    a lower priority, and the default torque, position and velocity limits."""
    dyn = panda_dynamics(friction=friction)
    pose = FramePoseTask(kp=400.0, weight=[1, 1, 0, 1, 1, 1])
    target = dyn.frame_pose(Q_HOME)
    target[0, 3] += 0.02
    pose.set_target(target)
    contact = Contact(mode="sliding", mu=0.3, kd=100.0)
    tasks = [pose, ContactForceTask(contact, 8.0, weight=1.0), PostureTask(7, kp=25.0, priority=1)]
    return OperationalSpaceQP(dyn, tasks, limits=default_limits(), contacts=[contact])


def _states(count: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(seed)
    return [(Q_HOME + rng.normal(0.0, 0.1, 7), rng.normal(0.0, 0.3, 7)) for _ in range(count)]


def _clipped(p: armctl.controllers.osc.QPProblem, tau: np.ndarray) -> np.ndarray:
    """τ clipped onto the bounds of the problem's torque-limit rows (as the controller's output is)."""
    rows = [i for i, name in enumerate(p.ineq_names) if name.startswith("torque_limit[")]
    return np.clip(tau, p.l[rows], p.u[rows])


def _quadprog_x(p: armctl.controllers.osc.QPProblem) -> np.ndarray:
    x = qpsolvers.solve_problem(p.to_qpsolvers(), "quadprog").x
    assert x is not None
    return np.asarray(x)


def _reduced_quadprog_x(p: armctl.controllers.osc.QPProblem) -> np.ndarray:
    """The optimum of ``p`` by quadprog on its equality rows eliminated (x = x₀ + N w, N a basis of their null
    space by SciPy), the inequality rows relaxed by 1e-10: rows that keep a level above hold to rounding only
    and, with bounds active at the same point, make quadprog refuse the problem as inconsistent."""
    x0 = np.linalg.lstsq(p.A, p.b, rcond=None)[0]
    N = scipy.linalg.null_space(p.A)
    up, lo = np.isfinite(p.u), np.isfinite(p.l)
    G = np.vstack([p.C[up] @ N, -p.C[lo] @ N])
    h = np.concatenate([p.u[up] - p.C[up] @ x0, -(p.l[lo] - p.C[lo] @ x0)])
    w = qpsolvers.solve_qp(N.T @ p.H @ N, N.T @ (p.H @ x0 + p.g), G, h + 1e-10, solver="quadprog")
    assert w is not None
    return x0 + N @ w


@pytest.mark.parametrize("friction", [False, True])
def test_fixed_contact_torque_is_the_public_problems_optimum(friction: bool) -> None:
    """τ of each step is quadprog's optimum of the public QP on [q̈; τ; f] (built and solved without the
    controller's solvers), the contact force with it; the reported solution is that point."""
    ctrl = _fixed(friction)
    ref = armctl.Reference(Q_HOME)
    for q, qd in _states(15, seed=1):
        tau = ctrl(0.0, q, qd, ref)
        p = ctrl.build(0.0, q, qd, ref).problem(0)
        x = _quadprog_x(p)
        scale = 1.0 + np.abs(x).max()
        np.testing.assert_allclose(tau, _clipped(p, x[p.variables["tau"]]), atol=1e-6 * scale)
        np.testing.assert_allclose(
            ctrl.last_log["force[contact[tool]]"], x[p.variables["contact[tool]"]], atol=1e-6 * scale
        )
        sol = ctrl.last_solution
        assert sol is not None
        np.testing.assert_allclose(sol.x, x, atol=1e-6 * scale)


def test_the_reported_solution_meets_the_public_problems_kkt_conditions() -> None:
    """The multipliers mapped back from [q̈; f] (the equation of motion's: ε τ + Σ z_τ) make the reported x a
    KKT point of the public problem, to the tolerance of an exact solve; the check the step ran passes again."""
    ctrl = _fixed(friction=True)
    ref = armctl.Reference(Q_HOME)
    for q, qd in _states(10, seed=2):
        ctrl(0.0, q, qd, ref)
        assert ctrl.verify_last_step()
        sol = ctrl.last_solution
        assert sol is not None
        qs = sol.solutions[0]
        assert qs is not None
        r = residuals(sol.problem(0).arrays, sol.x, qs.y, qs.z)
        assert r.ok(1e-8, 1e-8), r


def test_levels_with_a_sliding_contact_and_state_limits_are_the_public_cascade() -> None:
    """Two levels, a sliding contact, torque, position and velocity limits: level 0's point is feasible and as
    good as quadprog's optimum of the public level-0 QP, level 1's x is quadprog's optimum of the public level-1
    QP with the rows that keep level 0's optimum (``priority[i]``), each a KKT point of its public QP; τ is the
    last level's."""
    ctrl = _sliding()
    ref = armctl.Reference(Q_HOME)
    for q, qd in _states(10, seed=3):
        tau = ctrl(0.0, q, qd, ref)
        sol = ctrl.last_solution
        assert sol is not None and sol.level_status == ("solved", "solved")
        assert any(name.startswith("priority[") for name in sol.problem(1).eq_names)
        for k in (0, 1):
            p = sol.problem(k)
            qs = sol.solutions[k]
            assert qs is not None
            x = _reduced_quadprog_x(p)
            assert not p.violations(qs.x, 1e-8)
            # level 0's cost is flat (ε·1e-4) along what its tasks do not see: its optimal value is the test there
            assert p.objective(qs.x) <= p.objective(x) + 1e-9 * (1.0 + abs(p.objective(x)))
            if k == 1:
                np.testing.assert_allclose(qs.x, x, atol=1e-6 * (1.0 + np.abs(x).max()))
            assert residuals(p.arrays, qs.x, qs.y, qs.z).ok(1e-8, 1e-8)
        np.testing.assert_allclose(tau, _clipped(sol.problem(1), sol.tau), atol=1e-12)
        assert ctrl.verify_last_step()


def test_a_solver_without_raw_arrays_takes_the_full_problem_and_finds_the_same_torque() -> None:
    """A primary solver given as qpsolvers' quadprog (through the named problem on [q̈; τ; f]) and the default
    chain on [q̈; f] give the same τ and forces."""
    ref = armctl.Reference(Q_HOME)
    fast = _fixed(friction=True)

    class Named:  # a user's solver: solve(problem, slot) and reset() only
        def __init__(self) -> None:
            self.inner = QpsolversSolver("quadprog")

        def solve(self, p, slot=0):  # type: ignore[no-untyped-def]
            return self.inner.solve(p, slot)

        def reset(self) -> None:
            self.inner.reset()

    full = _fixed(friction=True, solver=Named())
    for q, qd in _states(8, seed=4):
        np.testing.assert_allclose(fast(0.0, q, qd, ref), full(0.0, q, qd, ref), atol=1e-6)


@pytest.mark.parametrize("compile", ["auto", False])
def test_contact_steps_agree_on_both_paths(compile: bool | str) -> None:
    """The contact steps of a controller made with generated QP data for free space (compile="auto") and of one
    on NumPy alone agree to 1e-9 N·m, with a free-space step in between."""
    ref = armctl.Reference(Q_HOME)
    numpy_ctrl = _fixed(friction=True, compile=False)
    ctrl = _fixed(friction=True, compile=compile)
    for i, (q, qd) in enumerate(_states(8, seed=5)):
        for c in (ctrl, numpy_ctrl):
            c.contacts[0].active = i != 3
        np.testing.assert_allclose(ctrl(0.0, q, qd, ref), numpy_ctrl(0.0, q, qd, ref), atol=1e-9, rtol=0)


def test_extend_basis_spans_the_rows_and_is_orthonormal() -> None:
    """The basis of F + T is orthonormal and spans exactly the rows given: well-conditioned rows (the Cholesky
    basis), rows with a zero row among them, and dependent rows (the SVD's rank), checked against the rank and
    the projector computed here."""
    rng = np.random.default_rng(6)
    F = extend_basis(np.zeros((0, 10)), rng.normal(size=(4, 10)))
    for T in (rng.normal(size=(3, 10)), np.vstack([rng.normal(size=(2, 10)), np.zeros((1, 10))])):
        B = extend_basis(F, T)
        np.testing.assert_allclose(B @ B.T, np.eye(B.shape[0]), atol=1e-12)
        stacked = np.vstack([F, T])
        assert B.shape[0] == np.linalg.matrix_rank(stacked)
        np.testing.assert_allclose(stacked - stacked @ B.T @ B, 0.0, atol=1e-12)
    dependent = np.vstack([F[:2] * 3.0, F[0] + F[1]])  # inside rows(F): nothing to add
    assert extend_basis(F, dependent).shape == F.shape


def test_the_default_takes_generated_contact_data_with_the_numpy_paths_torque() -> None:
    """``compile="auto"`` on Pinocchio's dynamics: the contact QPs take their data from generated code (one level
    with a fixed contact, two levels with a sliding one and state limits), with the NumPy path's τ to 1e-9 N·m."""
    ref = armctl.Reference(Q_HOME)
    for make in (_fixed, _sliding):
        ctrl = make(friction=True)
        assert ctrl.uses_generated_code
        dyn = ctrl.dynamics
        numpy_ctrl = OperationalSpaceQP(dyn, ctrl.tasks, limits=ctrl.limits, contacts=ctrl.contacts, compile=False)
        assert not numpy_ctrl.uses_generated_code
        for q, qd in _states(8, seed=7):
            np.testing.assert_allclose(ctrl(0.0, q, qd, ref), numpy_ctrl(0.0, q, qd, ref), atol=1e-9, rtol=0)


def test_without_a_compiler_the_contact_path_warns_once_with_the_same_torque(monkeypatch, tmp_path) -> None:  # type: ignore[no-untyped-def]
    """No C compiler (``CC`` a missing program, an empty cache): the contact QPs take the NumPy path with one
    PerformanceWarning over several steps and controllers, and the torque of ``compile=False``."""
    import warnings

    from armctl.controllers.osc import controller
    from armctl.errors import PerformanceWarning

    monkeypatch.setenv("CC", "no-such-compiler-armctl")
    monkeypatch.setenv("ARMCTL_CACHE", str(tmp_path))
    controller.FALLBACK.reset()
    ref = armctl.Reference(Q_HOME)
    states = _states(4, seed=8)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ctrls = [_fixed(), _fixed()]
        taus = [[c(0.0, q, qd, ref) for q, qd in states] for c in ctrls]
    assert [w.category for w in caught] == [PerformanceWarning]
    assert not ctrls[0].uses_generated_code
    numpy_ctrl = _fixed(compile=False)
    for (q, qd), tau in zip(states, taus[0], strict=True):
        np.testing.assert_array_equal(tau, numpy_ctrl(0.0, q, qd, ref))


def test_a_binding_torque_limit_refuses_the_contact_rows_optimum_and_the_chain_finds_the_bound() -> None:
    """One level: the optimum on the contact rows alone is taken only when every row holds. With joint 4's limit
    at half the torque that optimum asks for, the step's τ₄ sits on the limit, its row in the solution's active
    set (found past that optimum: by the generated code's active-set iterations, checked, or the solver chain),
    and τ is quadprog's optimum of the public problem."""
    ref = armctl.Reference(Q_HOME)
    (q, qd), *_ = _states(1, seed=9)
    free = _fixed(friction=True)
    tau_free = free(0.0, q, qd, ref)
    sol = free.last_solution
    assert sol is not None and sol.solutions[0] is not None and sol.solutions[0].iterations == 0  # no solver ran
    limit = np.array([87.0, 87.0, 87.0, 0.5 * abs(tau_free[3]), 12.0, 12.0, 12.0])
    dyn = free.dynamics
    bound = OperationalSpaceQP(dyn, free.tasks, limits=[TorqueLimit(limit)], contacts=free.contacts)
    tau = bound(0.0, q, qd, ref)
    assert abs(tau[3]) == pytest.approx(limit[3], abs=1e-9)
    sol = bound.last_solution
    first = sol.solutions[0] if sol is not None else None
    assert first is not None and first.active is not None and first.active[3] != 0
    p = bound.build(0.0, q, qd, ref).problem(0)
    x = _quadprog_x(p)
    np.testing.assert_allclose(tau, _clipped(p, x[p.variables["tau"]]), atol=1e-6 * (1.0 + np.abs(x).max()))


def test_two_contacts_fixed_and_sliding_on_both_paths_are_the_public_optimum() -> None:
    """A fixed contact at the tool and a sliding one on the elbow (another frame, another normal), each with a
    force task, in one level: the generated and NumPy paths agree to 1e-9 N·m and τ is quadprog's optimum of the
    public problem."""
    dyn = panda_dynamics(friction=True)

    def make(compile: bool | str) -> OperationalSpaceQP:
        pose = FramePoseTask(kp=400.0)
        pose.set_target(dyn.frame_pose(Q_HOME))
        tool = Contact(mu=0.3, facets=4)
        elbow = Contact(frame="panda_link5", mode="sliding", mu=0.2, normal=(0, 1, 0), name="elbow")
        tasks = [
            pose,
            PostureTask(7, kp=100.0, weight=1e-3),
            ContactForceTask(tool, (0.0, 0.0, 10.0)),
            ContactForceTask(elbow, 3.0, weight=1.0),
        ]
        return OperationalSpaceQP(dyn, tasks, limits=[TorqueLimit()], contacts=[tool, elbow], compile=compile)

    ctrl, numpy_ctrl = make("auto"), make(False)
    assert ctrl.uses_generated_code
    ref = armctl.Reference(Q_HOME)
    for q, qd in _states(8, seed=10):
        tau = ctrl(0.0, q, qd, ref)
        np.testing.assert_allclose(tau, numpy_ctrl(0.0, q, qd, ref), atol=1e-9, rtol=0)
        p = ctrl.build(0.0, q, qd, ref).problem(0)
        x = _quadprog_x(p)
        np.testing.assert_allclose(tau, _clipped(p, x[p.variables["tau"]]), atol=1e-6 * (1.0 + np.abs(x).max()))
        assert ctrl.verify_last_step()
