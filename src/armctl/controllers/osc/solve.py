"""Solving a :class:`~armctl.controllers.osc.problem.QPProblem`: proxsuite's dense ProxQP, warm-started from
the previous control period, or any solver of qpsolvers (to compare).

A solve that does not succeed is diagnosed (:func:`~armctl.controllers.osc.diagnose.conflicting_rows`): a
problem with no feasible point raises :class:`~armctl.errors.InfeasibleError` naming the rows that conflict;
any other failure raises :class:`~armctl.errors.SolverError`. Never a ``None``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from armctl._checks import FloatArray, scalar
from armctl.controllers.osc.diagnose import raise_failure
from armctl.controllers.osc.problem import QPProblem
from armctl.errors import UnknownNameError


@dataclass(slots=True)
class QPSolution:
    """x (the primal solution), the solver's ``status`` string, ``iterations`` and the ``solver`` name."""

    x: FloatArray
    status: str
    iterations: int
    solver: str


class ProxQPSolver:
    """proxsuite.proxqp.dense, one QP object per (slot, problem shape) so that each priority level is
    warm-started from its own previous solution. ``eps_abs``: absolute tolerance of the residuals (primal in
    N·m and rad/s², dual in the cost's units); ``rho``: ProxQP's proximal parameter (small values converge
    faster on the degenerate QPs met near singular configurations)."""

    name = "proxsuite"

    def __init__(self, eps_abs: float = 1e-6, max_iter: int = 5000, rho: float = 1e-8) -> None:
        from proxsuite import proxqp

        self._proxqp = proxqp
        self.eps_abs = scalar(eps_abs, "eps_abs", positive=True)
        self.max_iter = int(max_iter)
        self.rho = scalar(rho, "rho", positive=True)
        self._qps: dict[tuple[int, int, int, int], Any] = {}
        self._cl: dict[tuple[int, int, int, int], tuple[FloatArray, FloatArray, FloatArray]] = {}
        # per QP, its primal solution as a view of the solver's result (which each solve rewrites in place):
        # fetching ``results.x`` costs ~0.7 µs a call; None where the binding hands out copies
        self._x: dict[tuple[int, int, int, int], FloatArray | None] = {}
        self._solved = proxqp.QPSolverOutput.PROXQP_SOLVED

    def __reduce__(self) -> tuple[Any, ...]:
        # the settings only: proxsuite's QP objects do not pickle; the copy starts cold, as after reset()
        return (ProxQPSolver, (self.eps_abs, self.max_iter, self.rho))

    def reset(self) -> None:
        """Forget the previous solutions (no warm start at the next solve)."""
        self._qps.clear()
        self._cl.clear()
        self._x.clear()

    def solve(self, p: QPProblem, slot: int = 0) -> QPSolution:
        """Solve ``p``, warm-started from the last solution of the same slot and shape."""
        return self.solve_raw((p.H, p.g, p.A, p.b, p.C, p.l, p.u), slot, lambda: p)

    def solve_raw(self, arrays: tuple[FloatArray, ...], slot: int, problem: Callable[[], QPProblem]) -> QPSolution:
        """Solve the QP (H, g, A, b, C, l, u); ``problem()`` gives the named problem for a diagnosis."""
        H, g, A, b, C, l, u = arrays  # noqa: E741
        key = (slot, H.shape[0], b.shape[0], l.shape[0])
        qp = self._qps.get(key)
        if qp is None:
            px = self._proxqp
            qp = px.dense.QP(key[1], key[2], key[3])
            qp.settings.eps_abs = self.eps_abs
            qp.settings.eps_rel = 0.0
            qp.settings.max_iter = self.max_iter
            qp.settings.default_rho = self.rho
            # the QPs are strictly convex (the builder's ε‖x‖²), so never unbounded: ProxQP's test for an
            # unbounded QP (‖H d‖ ≤ eps_dual_inf ‖d‖ along a descent direction d) must not fire on the ε-flat
            # directions, as it did at the default 1e-4 (a feasible priority level reported DUAL_INFEASIBLE)
            qp.settings.eps_dual_inf = 1e-20
            qp.settings.initial_guess = px.InitialGuess.EQUALITY_CONSTRAINED_INITIAL_GUESS
            qp.init(H, g, A, b, C, l, u)
            qp.solve()
            qp.settings.initial_guess = px.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
            self._qps[key] = qp
            self._cl[key] = (C, l, u)
            x = qp.results.x
            self._x[key] = x if np.shares_memory(x, qp.results.x) else None
        else:
            prev = self._cl[key]
            if prev[0] is C and prev[1] is l and prev[2] is u:  # constant inequality rows (read-only arrays)
                qp.update(H, g, A, b, None, None, None)
            else:
                qp.update(H, g, A, b, C, l, u)
                self._cl[key] = (C, l, u)
            qp.solve()
        res = qp.results
        info = res.info
        if info.status != self._solved:
            del self._qps[key]  # a failed solve is no starting point
            self._x.pop(key, None)
            raise_failure(problem(), self.name, str(info.status), info)
        x = self._x.get(key)
        return QPSolution((res.x if x is None else x).copy(), "solved", info.iter, self.name)


class QpsolversSolver:
    """Any solver of qpsolvers (``solver`` in ``qpsolvers.available_solvers``), warm-started with the previous
    primal solution where the solver takes one."""

    def __init__(self, solver: str = "proxqp", **options: Any) -> None:
        import qpsolvers

        if solver not in qpsolvers.available_solvers:
            raise UnknownNameError("qpsolvers solver", solver, list(qpsolvers.available_solvers))
        self._qpsolvers = qpsolvers
        self.name = f"qpsolvers:{solver}"
        self.solver = solver
        self.options = options
        self._x: dict[tuple[int, int], FloatArray] = {}

    def reset(self) -> None:
        self._x.clear()

    def solve(self, p: QPProblem, slot: int = 0) -> QPSolution:
        key = (slot, p.nx)
        sol = self._qpsolvers.solve_problem(p.to_qpsolvers(), self.solver, initvals=self._x.get(key), **self.options)
        if not sol.found or sol.x is None or not np.isfinite(sol.x).all():
            self._x.pop(key, None)
            raise_failure(p, self.name, "not found", sol)
        self._x[key] = sol.x
        return QPSolution(np.asarray(sol.x, dtype=float), "solved", -1, self.name)


def make_solver(solver: str | Any) -> Any:
    """ "proxsuite" (default), "qpsolvers:NAME" or an object with ``solve(problem, slot)`` and ``reset()``."""
    if not isinstance(solver, str):
        if not (callable(getattr(solver, "solve", None)) and callable(getattr(solver, "reset", None))):
            raise UnknownNameError("solver", solver, ["proxsuite", "qpsolvers:<name>"])
        return solver
    if solver == "proxsuite":
        return ProxQPSolver()
    if solver.startswith("qpsolvers:"):
        return QpsolversSolver(solver.split(":", 1)[1])
    raise UnknownNameError("solver", solver, ["proxsuite", "qpsolvers:<name>"])
