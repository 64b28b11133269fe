"""Every step's torque is the optimum of the QP it builds: checked against an independent solver (quadprog, an
active-set method in Fortran, through qpsolvers), with each fallback of the solver chain forced in turn."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import armctl
from armctl.controllers.osc import (
    FramePoseTask,
    OperationalSpaceQP,
    PostureTask,
    ProxQPSolver,
    QPArrays,
    QPProblem,
    TorqueLimit,
)
from armctl.controllers.osc.active_set import dual_active_set
from armctl.controllers.osc.optimality import accept, residuals, solve_on_active_set
from armctl.errors import InfeasibleError, SolverError, SolverWarning
from tests.controllers.osc.helpers import Q_HOME, panda_dynamics, quadprog_solvers

qpsolvers = quadprog_solvers()


def _cold_optimum(p: QPProblem) -> np.ndarray:
    """The optimum of ``p`` from quadprog, from scratch."""
    sol = qpsolvers.solve_problem(p.to_qpsolvers(), "quadprog")
    assert sol.found
    return np.asarray(sol.x)


def _controller(dyn: armctl.Dynamics, **options: object) -> OperationalSpaceQP:
    """Pose task (kp 400, tool frame, target 11 cm from the ready pose's) + posture (kp 100, weight 1e-3, same
    level) + the URDF's torque limits."""
    pose = FramePoseTask(kp=400.0)
    target = dyn.frame_pose(Q_HOME)
    target[:3, 3] += [0.1, 0.0, -0.05]
    pose.set_target(target)
    return OperationalSpaceQP(dyn, [pose, PostureTask(7, kp=100.0, weight=1e-3)], limits=[TorqueLimit()], **options)


def _random_states(count: int, seed: int = 0) -> list[tuple[np.ndarray, np.ndarray]]:
    """q = ready + N(0, 0.1 rad), q̇ = N(0, 0.3 rad/s)."""
    rng = np.random.default_rng(seed)
    return [(Q_HOME + rng.normal(0.0, 0.1, 7), rng.normal(0.0, 0.3, 7)) for _ in range(count)]


def test_warm_started_torques_are_the_cold_optimum_of_an_independent_solver() -> None:
    """400 unrelated states through one controller (warm-started from each previous, unrelated one, as a loop
    would): τ equals quadprog's optimum of the very QP the controller shows, solved cold, within 1e-4 N·m on
    every state. The states bind the torque limits on most states and not on others, so both cases are checked.
    (ProxQP warm-started alone reports SOLVED on 42 of these states with τ up to 119 N·m off: residuals below
    1e-6, but multipliers on torque bounds that are not active.)"""
    dyn = panda_dynamics()
    ctrl = _controller(dyn)
    ref = armctl.Reference(Q_HOME)
    errors, binding = [], 0
    for q, qd in _random_states(400):
        tau = ctrl(0.0, q, qd, ref)
        p = ctrl.build(0.0, q, qd, ref).problem(0)
        best = _cold_optimum(p)[p.variables["tau"]]
        errors.append(float(np.abs(tau - best).max()))
        binding += bool((np.abs(np.abs(best) - dyn.model.effort_limit) < 1e-6).any())
    assert 50 < binding < 400
    assert max(errors) <= 1e-4, (int(np.argmax(errors)), max(errors))
    assert ctrl.fallback_counts.get("failed", 0) == 0


def test_the_solution_shown_satisfies_the_public_problems_kkt_conditions() -> None:
    """The solution the controller reports (x = [q̈; τ] and multipliers, from the QP on q̈ alone) satisfies the
    optimality conditions of the public problem (H, g, A, b, C, l, u) on [q̈; τ], computed here from its
    arrays; and a multiplier moved onto an inactive bound is caught by the duality gap."""
    dyn = panda_dynamics()
    ctrl = _controller(dyn)
    ref = armctl.Reference(Q_HOME)
    for q, qd in _random_states(20, seed=3):
        sol = ctrl.solve(0.0, q, qd, ref)
        p = sol.problem(0)
        qp = sol.solutions[0]
        assert qp is not None and qp.y is not None and qp.z is not None
        stationarity = p.H @ sol.x + p.g + p.A.T @ qp.y + p.C.T @ qp.z
        assert np.abs(stationarity).max() <= 1e-7 * (1 + np.abs(p.g).max())
        assert np.abs(p.A @ sol.x - p.b).max() <= 1e-9
        cx = p.C @ sol.x
        assert (cx <= p.u + 1e-8).all() and (cx >= p.l - 1e-8).all()
        assert (qp.z[cx < p.u - 1e-6] <= 1e-9).all() and (qp.z[cx > p.l + 1e-6] >= -1e-9).all()  # complementarity
        assert residuals(p.arrays, sol.x, qp.y, qp.z).ok()
        assert ctrl.verify_last_step()
        free = np.flatnonzero((cx < p.u - 1.0) & (cx > p.l + 1.0))
        spurious = qp.z.copy()
        spurious[free[0]] = 10.0  # a multiplier on a bound 1 N·m away
        r = residuals(p.arrays, sol.x, qp.y, spurious)
        assert not r.ok() and r.gap > 1.0


def test_the_exact_solve_on_an_active_set_is_accepted_only_if_it_is_the_optimum() -> None:
    """A QP written here: min ½‖x − (2, 2)‖² s.t. x₁ ≤ 1, x₂ ≤ 5. Its optimum (1, 2) has x₁'s bound active with
    multiplier 1; taking x₂'s bound active instead, or no row, gives a point that the check refuses."""
    H, g = np.eye(2), np.array([-2.0, -2.0])
    A, b = np.zeros((0, 2)), np.zeros(0)
    arrays = QPArrays(H, g, A, b, np.eye(2), np.full(2, -np.inf), np.array([1.0, 5.0]))
    for active, optimal in (([1, 0], True), ([0, 1], False), ([0, 0], False), ([1, 1], False)):
        act = np.array(active, dtype=np.int8)
        x, _, z = solve_on_active_set(arrays, act)  # type: ignore[misc]
        assert accept(arrays, x, z, act) is optimal, active
        if optimal:
            np.testing.assert_allclose(x, [1.0, 2.0], atol=1e-14)
            np.testing.assert_allclose(z, [1.0, 0.0], atol=1e-14)


def test_the_dual_active_set_solver_agrees_with_quadprog_and_detects_infeasibility() -> None:
    """Random strictly convex QPs with equalities, two-sided, one-sided and equal bounds: the same optimum as
    quadprog (relative 1e-8), KKT residuals within the controller's tolerances, and the same verdict on QPs
    with no feasible point."""
    rng = np.random.default_rng(1)
    solved = infeasible = 0
    for _ in range(200):
        n, me, mi = int(rng.integers(2, 10)), int(rng.integers(0, 3)), int(rng.integers(0, 12))
        B = rng.normal(size=(n + 2, n))
        H, g = B.T @ B + 1e-6 * np.eye(n), 5.0 * rng.normal(size=n)
        A, b = rng.normal(size=(me, n)), rng.normal(size=me)
        C, lower = rng.normal(size=(mi, n)), rng.normal(size=mi) - 1.0
        upper = lower + rng.uniform(0.0, 2.0, mi)
        lower[rng.random(mi) < 0.3], upper[rng.random(mi) < 0.3] = -np.inf, np.inf
        if mi and np.isfinite(upper[0]) and rng.random() < 0.2:
            lower[0] = upper[0]
        qp = QPArrays(H, g, A, b, C, lower, upper)
        up, lo = np.isfinite(upper), np.isfinite(lower)
        G, h = np.vstack([C[up], -C[lo]]), np.concatenate([upper[up], -lower[lo]])
        ref = qpsolvers.solve_qp(
            H, g, G if len(h) else None, h if len(h) else None, A if me else None, b if me else None, solver="quadprog"
        )
        if ref is None:
            with pytest.raises(InfeasibleError):
                dual_active_set(qp)
            infeasible += 1
            continue
        x, y, z, _ = dual_active_set(qp)
        np.testing.assert_allclose(x, ref, atol=1e-8 * (1 + np.abs(ref).max()))
        assert residuals(qp, x, y, z).ok(1e-8, 1e-6)
        solved += 1
    assert solved > 50 and infeasible > 20


class _Failing(ProxQPSolver):
    """ProxQP that fails (SolverError) in the modes listed, or, with ``wrong``, returns in those modes a NaN point
    (a false SOLVED)."""

    def __init__(self, modes: tuple[str, ...], wrong: bool = False) -> None:
        super().__init__()
        self.modes, self.wrong, self.calls = modes, wrong, []  # type: ignore[var-annotated]

    def solve_raw(self, arrays, slot=0, mode="warm"):  # type: ignore[no-untyped-def]
        self.calls.append(mode)
        if mode not in self.modes:
            return super().solve_raw(arrays, slot, mode)
        if not self.wrong:
            raise SolverError(f"made to fail ({mode})", value=mode)
        sol = super().solve_raw(arrays, slot, mode)
        sol.x = np.full_like(sol.x, np.nan)
        return sol


@pytest.mark.parametrize(
    ("modes", "wrong", "stage", "fallbacks"),
    [
        (("warm",), False, "cold", 1),
        (("warm", "cold"), False, "defaults", 2),
        (("warm", "cold", "defaults"), False, "second", 3),
        (("warm", "cold"), True, "defaults", 2),  # a NaN point called solved
    ],
)
def test_each_fallback_gives_the_optimum_and_is_counted_and_summarised(
    modes: tuple[str, ...], wrong: bool, stage: str, fallbacks: int
) -> None:
    """The primary solver made to fail (or to return a wrong point it calls solved) in the first stages: the
    chain goes on to the next stage, τ is still quadprog's cold optimum, ``last_log["qp_fallbacks"]`` counts
    the fallbacks of the step, and :meth:`end_run` warns once with how many QPs each fallback solved. States
    whose optimum binds a torque limit, the chain's first stage (DAQP) switched off and the QP's data from NumPy
    (the generated code first solves on the rows its unconstrained minimum breaks), so that every QP past the
    unconstrained minimum reaches the solvers."""
    dyn = panda_dynamics()
    solver = _Failing(modes, wrong)
    ctrl = _controller(dyn, solver=solver, compile=False)
    ctrl.chain.first = None
    ref = armctl.Reference(Q_HOME)
    checked = 0
    for q, qd in _random_states(20, seed=7):
        p = ctrl.build(0.0, q, qd, ref).problem(0)
        best = _cold_optimum(p)[p.variables["tau"]]
        if not (np.abs(np.abs(best) - dyn.model.effort_limit) < 1e-6).any():
            continue
        ctrl.reset()  # no active set to start from
        tau = ctrl(0.0, q, qd, ref)
        np.testing.assert_allclose(tau, best, atol=1e-4)
        assert ctrl.last_log["qp_fallbacks"] == fallbacks
        assert ctrl.fallback_counts == {stage: 1}
        checked += 1
    assert checked >= 5
    assert solver.calls[: len(modes) + (stage != "second")] == [*modes, stage][: len(modes) + (stage != "second")]
    with pytest.warns(SolverWarning, match=r"over 1 control steps: .*re-solved 1 time: 1 by") as record:
        ctrl.end_run()
    assert len(record) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert ctrl.end_run() is None  # counted afresh: nothing more to say


def test_a_proposal_is_only_a_starting_point() -> None:
    """A primary solver whose every answer is wrong — 1 rad/s² off the optimum, with a multiplier on every
    bound — and called solved (the chain's first stage switched off, so that every QP past the unconstrained
    minimum reaches it): τ is still the optimum, because what is accepted is the exact solution on an active set
    that passed the check, never the proposal itself."""

    class Wrong(ProxQPSolver):
        def solve_raw(self, arrays, slot=0, mode="warm"):  # type: ignore[no-untyped-def]
            sol = super().solve_raw(arrays, slot, mode)
            sol.x = sol.x + 1.0
            sol.z = np.ones_like(sol.z)
            return sol

    dyn = panda_dynamics()
    ctrl = _controller(dyn, solver=Wrong())
    ctrl.chain.first = None
    ref = armctl.Reference(Q_HOME)
    for q, qd in _random_states(20, seed=11):
        tau = ctrl(0.0, q, qd, ref)
        p = ctrl.build(0.0, q, qd, ref).problem(0)
        np.testing.assert_allclose(tau, _cold_optimum(p)[p.variables["tau"]], atol=1e-4)


def test_a_qp_no_stage_solves_raises_with_what_each_stage_did() -> None:
    """Every stage failing on a feasible QP whose optimum binds a torque limit (the first stage switched off):
    SolverError saying so and listing the stages' outcomes (the elastic diagnosis finds the QP feasible), never a
    torque."""
    dyn = panda_dynamics()
    # the NumPy path: the step goes to the chain (the generated code would solve this QP itself)
    ctrl = _controller(dyn, solver=_Failing(("warm", "cold", "defaults")), fallback_solver=None, compile=False)
    ctrl.chain.first = None
    ref = armctl.Reference(Q_HOME)
    for q, qd in _random_states(20, seed=7):
        p = ctrl.build(0.0, q, qd, ref).problem(0)
        if (np.abs(np.abs(_cold_optimum(p)[p.variables["tau"]]) - dyn.model.effort_limit) < 1e-6).any():
            break
    with pytest.raises(SolverError, match=r"although it is feasible .*warm: .*cold: .*defaults: "):
        ctrl(0.0, q, qd, ref)
