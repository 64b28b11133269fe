"""The chain's first stage (DAQP from an active set) against an independent solver (quadprog, through qpsolvers),
and its check (kkt_ok) against the reference computation of the same KKT residuals."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import armctl
from armctl.controllers.osc import FramePoseTask, OperationalSpaceQP, PostureTask, QPArrays, SolverChain, TorqueLimit
from armctl.controllers.osc.daqp_solver import DaqpSolver
from armctl.controllers.osc.optimality import kkt_ok, residuals
from armctl.controllers.osc.solve import ProxQPSolver, QPSolution
from armctl.errors import SolverError
from tests.controllers.osc.helpers import quadprog_solvers

from .conftest import Q_HOME, panda_dynamics

qpsolvers = quadprog_solvers()


def _random_qp(rng: np.random.Generator) -> QPArrays:
    """A strictly convex QP with equalities, two-sided, one-sided and equal bounds."""
    n, me, mi = int(rng.integers(2, 10)), int(rng.integers(0, 3)), int(rng.integers(0, 12))
    B = rng.normal(size=(n + 2, n))
    H, g = B.T @ B + 1e-6 * np.eye(n), 5.0 * rng.normal(size=n)
    A, b = rng.normal(size=(me, n)), rng.normal(size=me)
    C, lower = rng.normal(size=(mi, n)), rng.normal(size=mi) - 1.0
    upper = lower + rng.uniform(0.0, 2.0, mi)
    lower[rng.random(mi) < 0.3], upper[rng.random(mi) < 0.3] = -np.inf, np.inf
    return QPArrays(H, g, A, b, C, lower, upper)


def _quadprog(qp: QPArrays) -> np.ndarray | None:
    up, lo = np.isfinite(qp.u), np.isfinite(qp.l)
    G, h = np.vstack([qp.C[up], -qp.C[lo]]), np.concatenate([qp.u[up], -qp.l[lo]])
    me = len(qp.b)
    return qpsolvers.solve_qp(  # type: ignore[no-any-return]
        qp.H,
        qp.g,
        G if len(h) else None,
        h if len(h) else None,
        qp.A if me else None,
        qp.b if me else None,
        solver="quadprog",
    )


def test_daqp_gives_quadprogs_optimum_with_multipliers_that_pass_the_check_from_any_start() -> None:
    """Random strictly convex QPs: from no active row, from the optimum's own active set and from a wrong one
    (random rows at their finite bounds), DAQP's x is quadprog's (relative 1e-8), its multipliers satisfy
    H x + g + Aᵀy + Cᵀz = 0 with z > 0 at upper bounds (the controller's convention), and the check passes; a QP
    with no feasible point is a SolverError."""
    rng = np.random.default_rng(3)
    solver = DaqpSolver()
    solved = infeasible = 0
    for _ in range(200):
        arrays = _random_qp(rng)
        ref = _quadprog(arrays)
        if ref is None:
            with pytest.raises(SolverError, match="daqp: infeasible"):
                solver.solve_from(arrays, None)
            infeasible += 1
            continue
        first = solver.solve_from(arrays, None)
        wrong = rng.integers(-1, 2, arrays.l.shape[0]).astype(np.int8)
        wrong[((wrong > 0) & ~np.isfinite(arrays.u)) | ((wrong < 0) & ~np.isfinite(arrays.l))] = 0
        for sol in (first, solver.solve_from(arrays, first.active), solver.solve_from(arrays, wrong)):
            np.testing.assert_allclose(sol.x, ref, atol=1e-8 * (1 + np.abs(ref).max()))
            assert kkt_ok(arrays, sol.x, sol.y, sol.z)
            assert residuals(arrays, sol.x, sol.y, sol.z).ok(1e-8, 1e-8)
            u_active, l_active = sol.active > 0, sol.active < 0
            np.testing.assert_allclose((arrays.C @ sol.x)[u_active], arrays.u[u_active], atol=1e-8)
            np.testing.assert_allclose((arrays.C @ sol.x)[l_active], arrays.l[l_active], atol=1e-8)
        solved += 1
    assert solved > 100 and infeasible > 10


def test_daqp_takes_read_only_arrays() -> None:
    """The layouts' constant rows are read-only arrays: DAQP (which takes writable buffers) gets copies."""
    H, g = np.eye(2), np.array([-2.0, -2.0])
    C, lower, upper = np.eye(2), np.full(2, -np.inf), np.array([1.0, 5.0])
    for a in (H, C, upper):
        a.flags.writeable = False
    sol = DaqpSolver().solve_from(QPArrays(H, g, np.zeros((0, 2)), np.zeros(0), C, lower, upper), None)
    np.testing.assert_allclose(sol.x, [1.0, 2.0], atol=1e-14)
    np.testing.assert_allclose(sol.z, [1.0, 0.0], atol=1e-14)
    assert sol.active.tolist() == [1, 0]


@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), shift=st.sampled_from([0.0, 1e-10, 1e-7, 1e-3, 1.0]))
def test_kkt_ok_is_the_residuals_check(seed: int, shift: float) -> None:
    """kkt_ok gives the verdict of residuals(...).ok(tolerances) on the optimum, on points moved off it, with
    multipliers moved onto inactive bounds, with NaN, and with infinite bounds."""
    rng = np.random.default_rng(seed)
    arrays = _random_qp(rng)
    try:
        sol = DaqpSolver().solve_from(arrays, None)
    except SolverError:
        x, y, z = rng.normal(size=arrays.nx), rng.normal(size=arrays.me), None
    else:
        x, y, z = sol.x + shift * rng.normal(size=sol.x.shape), sol.y, sol.z.copy()
        if z.size and rng.random() < 0.3:
            z[rng.integers(z.size)] += shift
    if rng.random() < 0.05:
        x = x.copy()
        x[0] = np.nan
    for tols in ((1e-8, 1e-8), (1e-6, 1e-6)):
        assert kkt_ok(arrays, x, y, z, *tols) == residuals(arrays, x, y, z).ok(*tols)


def _controller(first: object = "daqp") -> OperationalSpaceQP:
    dyn = panda_dynamics()
    pose = FramePoseTask(kp=400.0)
    target = dyn.frame_pose(Q_HOME)
    target[:3, 3] += [0.1, 0.0, -0.05]
    pose.set_target(target)
    # the NumPy path: every step whose unconstrained minimum breaks a row goes to the chain (the generated code
    # solves most of them itself)
    tasks = [pose, PostureTask(7, kp=100.0, weight=1e-3)]
    ctrl = OperationalSpaceQP(dyn, tasks, limits=[TorqueLimit()], compile=False)
    ctrl.chain = SolverChain(ProxQPSolver(), first=first)
    return ctrl


def test_a_wrong_first_stage_answer_is_refused_and_the_qp_goes_on_to_proxqp() -> None:
    """A first stage whose every answer is 0.01 rad/s² off DAQP's: the check refuses each, the chain goes on to
    ProxQP (warm) and τ is still quadprog's cold optimum of the QP the controller shows."""

    class Off(DaqpSolver):
        def solve_from(self, arrays, active):  # type: ignore[no-untyped-def]
            sol = super().solve_from(arrays, active)
            return QPSolution(sol.x + 0.01, sol.status, sol.iterations, sol.solver, sol.y, sol.z, active=sol.active)

    ctrl = _controller(Off())
    ref = armctl.Reference(Q_HOME)
    rng = np.random.default_rng(0)
    constrained = 0
    for _ in range(30):
        q, qd = Q_HOME + rng.normal(0.0, 0.1, 7), rng.normal(0.0, 0.3, 7)
        tau = ctrl(0.0, q, qd, ref)
        p = ctrl.build(0.0, q, qd, ref).problem(0)
        best = qpsolvers.solve_problem(p.to_qpsolvers(), "quadprog").x[p.variables["tau"]]
        np.testing.assert_allclose(tau, best, atol=1e-4)
        constrained += ctrl.last_solution.solutions[0].stage == "warm"  # type: ignore[union-attr]
    counts = ctrl.fallback_counts
    assert constrained == counts["warm"] > 5 and counts["active set"] == 30 - constrained


def test_a_start_that_misleads_daqp_is_dropped_for_a_start_from_no_row() -> None:
    """Starting DAQP with rows at infinite bounds makes it return points that are not the optimum (or NaN): the
    check refuses them and the chain's first stage solves again from no active row, still finding quadprog's
    optimum, counted as the first stage."""
    rng = np.random.default_rng(3)
    chain = SolverChain(ProxQPSolver())
    misled = 0
    for _ in range(200):
        arrays = _random_qp(rng)
        ref = _quadprog(arrays)
        start = np.where(~np.isfinite(arrays.u), 1, np.where(~np.isfinite(arrays.l), -1, 0)).astype(np.int8)
        if ref is None or not start.any():
            continue
        try:
            first = DaqpSolver().solve_from(arrays, start)
            misled += not kkt_ok(arrays, first.x, first.y, first.z)
        except SolverError:
            misled += 1
        chain.reset()
        sol = chain.solve(arrays, start=start)
        np.testing.assert_allclose(sol.x, ref, atol=1e-8 * (1 + np.abs(ref).max()))
        assert sol.stage == "active set"
    assert misled > 10 and chain.counts == {"active set": 1}
