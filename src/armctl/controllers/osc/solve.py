"""Solvers of the controller's QPs: proxsuite's dense ProxQP, warm-started from the previous control period,
or any solver of qpsolvers.

Inside a control step the controller calls ``solve_raw(arrays, slot, mode)`` on the
:class:`~armctl.controllers.osc.problem.QPArrays` (H, g, A, b, C, l, u) of a QP; it returns a :class:`QPSolution`
with the multipliers, or raises :class:`~armctl.errors.SolverError` with the solver's status — nothing more:
whether the solution is the optimum is checked by the controller (:mod:`~armctl.controllers.osc.optimality`),
which also decides what to try next (:mod:`~armctl.controllers.osc.chain`). ``solve(problem)``, for a user's own
call on a :class:`~armctl.controllers.osc.problem.QPProblem`, diagnoses a failure instead: a problem with no
feasible point raises :class:`~armctl.errors.InfeasibleError` naming the rows that conflict. Never a ``None``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any

import numpy as np

from armctl._checks import FloatArray, scalar
from armctl.controllers.osc.diagnose import raise_failure
from armctl.controllers.osc.problem import QPArrays, QPProblem
from armctl.errors import InfeasibleError, SolverError, UnknownNameError

#: the ways ``solve_raw`` can start: from the slot's previous solution, from scratch with the solver's own
#: settings, or from scratch with the solver's default settings
MODES = ("warm", "cold", "defaults")


@dataclass(slots=True)
class QPSolution:
    """A solver's solution of one QP, min ½ xᵀH x + gᵀx s.t. A x = b, l ≤ C x ≤ u.

    Attributes
    ----------
    x : ndarray, shape (nx,)
        The primal solution.
    status : str
        The solver's status (``"solved"``).
    iterations : int
        The solver's iterations (−1 where the solver does not say).
    solver : str
        The solver's name.
    y : ndarray, shape (me,), or None
        The multipliers of A x = b, where the solver gives them.
    z : ndarray, shape (mi,), or None
        The multipliers of l ≤ C x ≤ u, where the solver gives them: in the convention H x + g + Aᵀy + Cᵀz = 0,
        z > 0 at an upper bound, < 0 at a lower one.
    stage : str
        How the controller's solver chain got it: ``"active set"``, ``"warm"``, ``"cold"``, ``"defaults"`` or
        ``"second"`` (see :class:`~armctl.controllers.osc.SolverChain`); empty from a solver called directly.
    fallbacks : int
        The fallback stages the chain took for it.
    active : ndarray of int8, shape (mi,), or None
        The active set of a verified optimum: per inequality row +1 at its upper bound, −1 at its lower one, 0
        free.
    """

    x: FloatArray
    status: str
    iterations: int
    solver: str
    y: FloatArray | None = None
    z: FloatArray | None = None
    # how the controller's chain of solvers got it ("active set", "warm", "cold", "defaults", "second"; see
    # :mod:`~armctl.controllers.osc.chain`), and the fallbacks it took
    stage: str = ""
    fallbacks: int = 0
    # the active set of a verified optimum (int8 per inequality row: +1 upper bound, −1 lower, 0 free)
    active: np.ndarray | None = None


class QPSolver(ABC):
    """The base of the controller's QP solvers: the interface its :class:`~armctl.controllers.osc.SolverChain`
    calls (:meth:`solve_raw`, :meth:`reset`) and, on it, :meth:`solve` for a user's own call on a named problem.

    A solver of one's own derives from it and implements :meth:`solve_raw` (and :meth:`reset` if it keeps warm
    starts); any object with ``solve_raw`` and ``reset`` serves the chain as well, without :meth:`solve`.

    Attributes
    ----------
    name : str
        The solver's name (in :class:`QPSolution` and in the errors).
    """

    name = "solver"

    def reset(self) -> None:
        """Forget the previous solutions (no warm start at the next solve); a solver that keeps none has nothing
        to forget."""
        return None

    @abstractmethod
    def solve_raw(self, arrays: QPArrays, slot: int = 0, mode: str = "warm") -> QPSolution:
        """Solve a QP given as its arrays (the solver interface of the controller's chain).

        Parameters
        ----------
        arrays : QPArrays
            The QP (H, g, A, b, C, l, u), H positive definite.
        slot : int, optional
            Its slot (one per priority level), for a solver that keeps warm starts; others ignore it.
        mode : {"warm", "cold", "defaults"}, optional
            ``"warm"``: from the slot's previous solution; ``"cold"``: from scratch with the solver's settings;
            ``"defaults"``: from scratch with its default settings. A solver that keeps no warm start and has no
            settings ignores it.

        Returns
        -------
        QPSolution
            x and the multipliers y, z (H x + g + Aᵀy + Cᵀz = 0, z > 0 at an upper bound, < 0 at a lower one),
            not checked against the optimality conditions.

        Raises
        ------
        SolverError
            The solver finds no solution (the error carries its status).
        """

    def solve(self, p: QPProblem, slot: int = 0) -> QPSolution:
        """Solve a named problem (:meth:`solve_raw` on its arrays), diagnosing a failure.

        Parameters
        ----------
        p : QPProblem
            The problem.
        slot : int, optional
            Its slot (one per priority level): a solver that keeps warm starts starts from the slot's last
            solution of the same shape.

        Returns
        -------
        QPSolution
            The solution, with its multipliers y, z where the solver gives them (not checked against the
            optimality conditions).

        Raises
        ------
        InfeasibleError
            ``p`` has no feasible point: the error names the conflicting rows and by how much to relax them.
        SolverError
            The solver failed on a feasible problem (or the diagnosis failed too).
        """
        try:
            return self.solve_raw(p.arrays, slot)
        except SolverError as err:
            raise_failure(p, self.name, str(err.value), err.result)
        except InfeasibleError:  # a solver that finds no feasible point itself: the diagnosis names the rows
            raise_failure(p, self.name, "infeasible", None)


class ProxQPSolver(QPSolver):
    """Dense ProxQP (proxsuite), with one QP object per (slot, problem shape), so that each priority level is
    warm-started from its own previous solution.

    Parameters
    ----------
    eps_abs : float, optional
        Absolute tolerance > 0 of the residuals (primal in each row's units, N·m and rad/s²; dual in the cost's
        units) and of the duality gap.
    max_iter : int, optional
        Iterations at most.
    rho : float, optional
        ProxQP's proximal parameter > 0 (small values converge faster on the degenerate QPs met near singular
        configurations).

    Raises
    ------
    InvalidParameterError, NonFiniteError
        ``eps_abs`` or ``rho`` not a positive number.

    Notes
    -----
    ProxQP stops only once its duality gap is within ``eps_abs`` too (``check_duality_gap``): its residuals alone
    can be small at a point that is not the optimum, with multipliers on bounds that are not active.

    Inside a control step the controller calls :meth:`solve_raw` on the arrays of a QP: a failure raises
    SolverError with ProxQP's status, and whether the solution is the optimum is checked by the controller's
    :class:`~armctl.controllers.osc.SolverChain`. :meth:`solve`, for a user's own call on a
    :class:`~armctl.controllers.osc.QPProblem`, diagnoses a failure instead. Never a ``None``.
    """

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

    def _new_qp(self, key: tuple[int, int, int, int], arrays: QPArrays, defaults: bool) -> Any:
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
        qp.init(arrays.H, arrays.g, arrays.A, arrays.b, arrays.C, arrays.l, arrays.u)
        return qp

    def solve_raw(self, arrays: QPArrays, slot: int = 0, mode: str = "warm") -> QPSolution:
        """Solve a QP given as its arrays (the solver interface of the controller's chain).

        Parameters
        ----------
        arrays : QPArrays
            The QP (H, g, A, b, C, l, u).
        slot : int, optional
            Its slot (one per priority level): the warm starts are kept per slot and problem shape.
        mode : {"warm", "cold", "defaults"}, optional
            ``"warm"``: from the slot's previous solution; ``"cold"``: from scratch with this solver's settings
            (the slot warm-starts from it afterwards); ``"defaults"``: from scratch with proxsuite's default
            settings but ``eps_abs`` and ``max_iter`` (kept apart from the slot's warm start).

        Returns
        -------
        QPSolution
            x and the multipliers y, z (H x + g + Aᵀy + Cᵀz = 0), not checked against the optimality conditions.

        Raises
        ------
        SolverError
            ProxQP does not report SOLVED (the error carries its status).
        """
        H, g, A, b, C, lb, ub = arrays.H, arrays.g, arrays.A, arrays.b, arrays.C, arrays.l, arrays.u
        key = (slot, H.shape[0], b.shape[0], lb.shape[0])
        qp = self._qps.get(key) if mode == "warm" else None
        if qp is None:
            qp = self._new_qp(key, arrays, defaults=mode == "defaults")
            qp.solve()
            if mode != "defaults":
                qp.settings.initial_guess = self._proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
                self._qps[key] = qp
                self._cl[key] = (C, lb, ub)
        else:
            prev = self._cl[key]
            if prev[0] is C and prev[1] is lb and prev[2] is ub:  # constant inequality rows (read-only arrays)
                qp.update(H, g, A, b, None, None, None)
            else:
                qp.update(H, g, A, b, C, lb, ub)
                self._cl[key] = (C, lb, ub)
            qp.solve()
        res = qp.results
        info = res.info
        if info.status != self._solved:
            if mode != "defaults":
                self._qps.pop(key, None)  # a failed solve is no starting point
            raise SolverError(f"{self.name} ({mode} start): {info.status}", value=str(info.status), result=info)
        return QPSolution(res.x.copy(), "solved", info.iter, self.name, res.y.copy(), res.z.copy())


class QpsolversSolver(QPSolver):
    """Any solver of qpsolvers, warm-started with the previous primal solution of the same slot where the solver
    takes one.

    Parameters
    ----------
    solver : str, optional
        A name of ``qpsolvers.available_solvers`` (the default: ``"proxqp"``).
    **options
        The solver's own settings, handed to ``qpsolvers.solve_problem`` (not in the ``"defaults"`` mode).

    Raises
    ------
    UnknownNameError
        ``solver`` is not installed (the error lists those that are).
    """

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
        """Forget the previous solutions (no warm start at the next solve)."""
        self._x.clear()

    def solve_raw(self, arrays: QPArrays, slot: int = 0, mode: str = "warm") -> QPSolution:
        """Solve a QP given as its arrays (the solver interface of the controller's chain).

        Parameters
        ----------
        arrays : QPArrays
            The QP (H, g, A, b, C, l, u); each finite bound of l ≤ C x ≤ u becomes a row of G x ≤ h.
        slot : int, optional
            Its slot (one per priority level): the warm starts are kept per slot and number of variables.
        mode : {"warm", "cold", "defaults"}, optional
            ``"warm"``: from the slot's previous solution; ``"cold"``: from none; ``"defaults"``: from none and
            without this object's options.

        Returns
        -------
        QPSolution
            x and the multipliers y, z (H x + g + Aᵀy + Cᵀz = 0; zeros where the solver gives none), not checked
            against the optimality conditions; ``iterations`` is −1.

        Raises
        ------
        SolverError
            The solver finds no solution, or a non-finite one.
        """
        H, g, A, b, C, lb, ub = arrays.H, arrays.g, arrays.A, arrays.b, arrays.C, arrays.l, arrays.u
        key = (slot, H.shape[0])
        up, lo = np.isfinite(ub), np.isfinite(lb)
        G = np.vstack([C[up], -C[lo]])
        h = np.concatenate([ub[up], -lb[lo]])
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
        z = np.zeros(len(lb))
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
