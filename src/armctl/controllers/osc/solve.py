"""Solvers of the controller's QPs: proxsuite's dense ProxQP, warm-started from the previous control period,
or any solver of qpsolvers.

Inside a control step the controller calls ``solve_raw(arrays, slot, mode)`` on the arrays (H, g, A, b, C, l, u)
of a QP; it returns a :class:`QPSolution` with the multipliers, or raises :class:`~armctl.errors.SolverError`
with the solver's status — nothing more: whether the solution is the optimum is checked by the controller
(:mod:`~armctl.controllers.osc.optimality`), which also decides what to try next
(:mod:`~armctl.controllers.osc.chain`). ``solve(problem)``, for a user's own call on a
:class:`~armctl.controllers.osc.problem.QPProblem`, diagnoses a failure instead: a problem with no feasible
point raises :class:`~armctl.errors.InfeasibleError` naming the rows that conflict. Never a ``None``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from armctl._checks import FloatArray, scalar
from armctl.controllers.osc.diagnose import raise_failure
from armctl.controllers.osc.problem import Arrays, QPProblem
from armctl.errors import SolverError, UnknownNameError

#: the ways ``solve_raw`` can start: from the slot's previous solution, from scratch with the solver's own
#: settings, or from scratch with the solver's default settings
MODES = ("warm", "cold", "defaults")


@dataclass(slots=True)
class QPSolution:
    """x (the primal solution), the solver's ``status`` string, ``iterations`` and the ``solver`` name; the
    multipliers ``y`` (of A x = b) and ``z`` (of l ≤ C x ≤ u) where the solver gives them, in the convention
    H x + g + Aᵀy + Cᵀz = 0 (z > 0 at an upper bound, < 0 at a lower one)."""

    x: FloatArray
    status: str
    iterations: int
    solver: str
    y: FloatArray | None = None
    z: FloatArray | None = None
    #: how the controller's chain of solvers got it ("active set", "warm", "cold", "defaults", "second"; see
    #: :mod:`~armctl.controllers.osc.chain`), and the fallbacks it took
    stage: str = ""
    fallbacks: int = 0
    #: the active set of a verified optimum (int8 per inequality row: +1 upper bound, −1 lower, 0 free)
    active: np.ndarray | None = None


class ProxQPSolver:
    """proxsuite.proxqp.dense, one QP object per (slot, problem shape) so that each priority level is
    warm-started from its own previous solution. ``eps_abs``: absolute tolerance of the residuals (primal in
    N·m and rad/s², dual in the cost's units); ``rho``: ProxQP's proximal parameter (small values converge
    faster on the degenerate QPs met near singular configurations). ProxQP stops only once its duality gap is
    within ``eps_abs`` too (``check_duality_gap``): its residuals alone can be small at a point that is not the
    optimum, with multipliers on bounds that are not active."""

    name = "proxsuite"

    def __init__(self, eps_abs: float = 1e-6, max_iter: int = 5000, rho: float = 1e-8) -> None:
        from proxsuite import proxqp

        self._proxqp = proxqp
        self.eps_abs = scalar(eps_abs, "eps_abs", positive=True)
        self.max_iter = int(max_iter)
        self.rho = scalar(rho, "rho", positive=True)
        self._qps: dict[tuple[int, int, int, int], Any] = {}
        self._cl: dict[tuple[int, int, int, int], tuple[FloatArray, FloatArray, FloatArray]] = {}
        self._solved = proxqp.QPSolverOutput.PROXQP_SOLVED

    def __reduce__(self) -> tuple[Any, ...]:
        # the settings only: proxsuite's QP objects do not pickle; the copy starts cold, as after reset()
        return (ProxQPSolver, (self.eps_abs, self.max_iter, self.rho))

    def reset(self) -> None:
        """Forget the previous solutions (no warm start at the next solve)."""
        self._qps.clear()
        self._cl.clear()

    def solve(self, p: QPProblem, slot: int = 0) -> QPSolution:
        """Solve ``p``, warm-started from the last solution of the same slot and shape; a failure is diagnosed
        (InfeasibleError naming the conflicting rows, or SolverError)."""
        try:
            return self.solve_raw((p.H, p.g, p.A, p.b, p.C, p.l, p.u), slot)
        except SolverError as err:
            raise_failure(p, self.name, str(err.value), err.result)

    def _new_qp(self, key: tuple[int, int, int, int], arrays: Arrays, defaults: bool) -> Any:
        px = self._proxqp
        qp = px.dense.QP(key[1], key[2], key[3])
        qp.settings.eps_abs = self.eps_abs
        qp.settings.eps_rel = 0.0
        qp.settings.max_iter = self.max_iter
        if not defaults:
            qp.settings.default_rho = self.rho
            # the QPs are strictly convex (the builder's ε‖x‖²), so never unbounded: ProxQP's test for an
            # unbounded QP (‖H d‖ ≤ eps_dual_inf ‖d‖ along a descent direction d) must not fire on the ε-flat
            # directions, as it did at the default 1e-4 (a feasible priority level reported DUAL_INFEASIBLE)
            qp.settings.eps_dual_inf = 1e-20
            qp.settings.check_duality_gap = True
            qp.settings.eps_duality_gap_abs = self.eps_abs
            qp.settings.eps_duality_gap_rel = 0.0
            qp.settings.initial_guess = px.InitialGuess.EQUALITY_CONSTRAINED_INITIAL_GUESS
        H, g, A, b, C, l, u = arrays  # noqa: E741
        qp.init(H, g, A, b, C, l, u)
        return qp

    def solve_raw(self, arrays: Arrays, slot: int = 0, mode: str = "warm") -> QPSolution:
        """Solve the QP (H, g, A, b, C, l, u). ``mode``: "warm" (from the slot's previous solution), "cold"
        (from scratch, this solver's settings; the slot warm-starts from it afterwards) or "defaults" (from
        scratch with proxsuite's default settings but ``eps_abs`` and ``max_iter``; kept apart). Raises
        SolverError with ProxQP's status if it does not report SOLVED."""
        H, g, A, b, C, l, u = arrays  # noqa: E741
        key = (slot, H.shape[0], b.shape[0], l.shape[0])
        qp = self._qps.get(key) if mode == "warm" else None
        if qp is None:
            qp = self._new_qp(key, arrays, defaults=mode == "defaults")
            qp.solve()
            if mode != "defaults":
                qp.settings.initial_guess = self._proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
                self._qps[key] = qp
                self._cl[key] = (C, l, u)
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
            if mode != "defaults":
                self._qps.pop(key, None)  # a failed solve is no starting point
            raise SolverError(f"{self.name} ({mode} start): {info.status}", value=str(info.status), result=info)
        return QPSolution(res.x.copy(), "solved", info.iter, self.name, res.y.copy(), res.z.copy())


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
        """Solve ``p`` (warm-started where the solver takes an initial point); a failure is diagnosed."""
        try:
            return self.solve_raw((p.H, p.g, p.A, p.b, p.C, p.l, p.u), slot)
        except SolverError as err:
            raise_failure(p, self.name, str(err.value), err.result)

    def solve_raw(self, arrays: Arrays, slot: int = 0, mode: str = "warm") -> QPSolution:
        """Solve the QP (H, g, A, b, C, l, u); ``mode`` "warm" starts from the slot's previous solution, "cold"
        from none, "defaults" from none and without this object's options. Raises SolverError if the solver
        finds no solution."""
        H, g, A, b, C, l, u = arrays  # noqa: E741
        key = (slot, H.shape[0])
        up, lo = np.isfinite(u), np.isfinite(l)
        G = np.vstack([C[up], -C[lo]])
        h = np.concatenate([u[up], -l[lo]])
        problem = self._qpsolvers.Problem(
            np.array(H),
            np.array(g),
            G if len(h) else None,
            h if len(h) else None,
            np.array(A) if len(b) else None,
            np.array(b) if len(b) else None,
        )
        options = {} if mode == "defaults" else self.options
        init = self._x.get(key) if mode == "warm" else None
        sol = self._qpsolvers.solve_problem(problem, self.solver, initvals=init, **options)
        if not sol.found or sol.x is None or not np.isfinite(sol.x).all():
            self._x.pop(key, None)
            raise SolverError(f"{self.name} ({mode} start): no solution found", value="not found", result=sol)
        x = np.asarray(sol.x, dtype=float)
        if mode != "defaults":
            self._x[key] = x
        y = np.asarray(sol.y, dtype=float) if len(b) and sol.y is not None else np.zeros(len(b))
        z = np.zeros(len(l))
        if len(h) and sol.z is not None:
            k = int(up.sum())
            z[up] += sol.z[:k]
            z[lo] -= sol.z[k:]
        return QPSolution(x, "solved", -1, self.name, y, z)


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


def make_second_solver(solver: str | Any) -> Any:
    """The last stage of the controller's solver chain: "active-set" (the dual active-set method),
    "qpsolvers:NAME", an object with ``solve_raw`` and ``reset``, or None (none)."""
    from armctl.controllers.osc.active_set import DualActiveSetSolver

    valid = ["active-set", "qpsolvers:<name>", "None"]
    if solver is None:
        return None
    if isinstance(solver, str):
        if solver == "active-set":
            return DualActiveSetSolver()
        if solver.startswith("qpsolvers:"):
            return QpsolversSolver(solver.split(":", 1)[1])
        raise UnknownNameError("fallback solver", solver, valid)
    if not (callable(getattr(solver, "solve_raw", None)) and callable(getattr(solver, "reset", None))):
        raise UnknownNameError("fallback solver", solver, valid)
    return solver
