"""`SolverChain`: one QP of a control step, solved until a verified optimum is found (its stages are described
with the class).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from typing import Any

import numpy as np

from armctl._checks import FloatArray
from armctl.controllers.osc.active_set import DualActiveSetSolver
from armctl.controllers.osc.daqp_solver import DaqpSolver
from armctl.controllers.osc.optimality import ActiveSets, active_set_of, kkt_ok, residuals
from armctl.controllers.osc.problem import QPArrays, QPProblem
from armctl.controllers.osc.solve import QPSolution
from armctl.errors import InfeasibleError, SolverError

#: the stages in order (see SolverChain); those after "warm" are fallbacks
STAGES = ("active set", "warm", "cold", "defaults", "second")
FALLBACKS = ("cold", "defaults", "second")


class QPFailure(SolverError):
    """No stage of the solver chain found a verified optimum.

    Parameters
    ----------
    attempts : list of (str, str)
        (stage, what happened) for each stage tried, in order; kept as ``attempts``.
    """

    def __init__(self, attempts: list[tuple[str, str]]) -> None:
        shown = "; ".join(f"{stage}: {what}" for stage, what in attempts)
        super().__init__(f"no verified optimum ({shown})", value=attempts)
        self.attempts = attempts


class SolverChain:
    """The QPs of a controller's steps, each solved until a verified optimum is found: stages of solvers, each
    answer checked against the QP's optimality conditions (see Notes).

    Parameters
    ----------
    primary : object
        The primary solver: an object with ``solve_raw(arrays, slot, mode)`` and ``reset()`` (as
        :class:`~armctl.controllers.osc.ProxQPSolver`), or a user's object with ``solve(problem, slot)`` and
        ``reset()``.
    second : object, str or None, optional
        The fifth stage's solver, an object with ``solve_raw`` and ``reset()``; ``"active-set"`` (the default):
        :class:`~armctl.controllers.osc.DualActiveSetSolver`; None: no fifth stage.
    first : object, str or None, optional
        The first stage's solver, an object with ``solve_from(arrays, active)`` and ``reset()``; ``"daqp"`` (the
        default): :class:`~armctl.controllers.osc.DaqpSolver`; None: no first stage.
    check : callable, optional
        ``check(arrays, x, y, z) -> bool``, the first stage's check: the conditions of
        :func:`~armctl.controllers.osc.optimality.kkt_ok` at its default tolerances (the default: ``kkt_ok``
        itself; a controller with generated code gives the same check compiled,
        :class:`~armctl.controllers.osc.kkt_code.CompiledKKT`). Kept as ``check``.

    Attributes
    ----------
    counts : collections.Counter
        Verified optima by the stage that found them, and ``"failed"`` for QPs no stage solved, since
        :meth:`reset` (or a controller's ``end_run``, which clears them).

    Notes
    -----
    Stages, in order, each ending in a check of the candidate against the QP's optimality conditions
    (:mod:`~armctl.controllers.osc.optimality`): every row holds, every multiplier has its sign, the stationarity
    residual and the duality gap vanish — the KKT conditions, to the stated tolerances.

    1. ``"active set"`` — DAQP (:class:`~armctl.controllers.osc.DaqpSolver`, a dual active-set method in C)
       started from the active set of the slot's last verified optimum (consecutive control steps rarely change
       which limits bind), or from a given one, and if that fails, from no active row; its answer, the exact
       solution on its final active set, is checked by :func:`~armctl.controllers.osc.optimality.kkt_ok` (or
       ``check``, the same conditions) to
       :data:`~armctl.controllers.osc.optimality.PRIMAL_TOL` (1e-8 in each row's units) and
       :data:`~armctl.controllers.osc.optimality.DUAL_TOL` (1e-8, relative to 1 + ‖g‖∞).
    2. ``"warm"`` — the primary solver (ProxQP), warm-started from the slot's previous solution.
    3. ``"cold"`` — the primary solver from scratch (a warm start from an unrelated state can stop at a point
       that is not the optimum, or report a feasible QP infeasible).
    4. ``"defaults"`` — the primary solver from scratch with its default settings.
    5. ``"second"`` — a second solver (by default :class:`~armctl.controllers.osc.DualActiveSetSolver`, an
       active-set method in NumPy).

    A candidate of stages 2–5 is a proposal: the active set it points at is solved exactly and accepted if it
    passes the check (or, failing that, the candidate itself if its KKT residuals are within the solvers' own
    tolerance, :data:`~armctl.controllers.osc.optimality.KKT_TOL`, 1e-6). Stages 3–5 are fallbacks: each one taken is
    counted (``counts``, and per step ``QPSolution.fallbacks``). If no stage gives a verified optimum,
    :class:`QPFailure` is raised with what each stage did; the controller decides what that means (a diagnosis for
    level 0, the level above's solution kept for a lower level).
    """

    def __init__(
        self,
        primary: Any,
        second: Any = "active-set",
        first: Any = "daqp",
        check: Callable[[QPArrays, FloatArray, FloatArray | None, FloatArray | None], bool] = kkt_ok,
    ) -> None:
        self.primary = primary
        self.check = check
        self.second = DualActiveSetSolver() if isinstance(second, str) and second == "active-set" else second
        self.first = DaqpSolver() if isinstance(first, str) and first == "daqp" else first
        self._raw = callable(getattr(primary, "solve_raw", None))
        #: the last verified optimum's active set, per (slot, n, equalities, inequalities)
        self._active: dict[tuple[int, int, int, int], np.ndarray] = {}
        # verified optima by the stage that found them, and QPs no stage solved ("failed"), since reset()
        self.counts: Counter[str] = Counter()

    def __reduce__(self) -> tuple[Any, ...]:
        return (SolverChain, (self.primary, self.second, self.first, self.check))  # starts cold, as after reset()

    def reset(self) -> None:
        """Forget the warm starts and the counts."""
        self.primary.reset()
        for solver in (self.second, self.first):
            if solver is not None:
                solver.reset()
        self._active.clear()
        self.counts.clear()

    def _call(self, solver: Any, arrays: QPArrays, slot: int, mode: str, problem: Callable[[], QPProblem]) -> Any:
        if solver is self.second or self._raw:
            return solver.solve_raw(arrays, slot, mode)
        if mode == "defaults":  # a user's solver has no notion of its defaults
            return None
        if mode == "cold":
            solver.reset()
        return solver.solve(problem(), slot)

    @staticmethod
    def key(arrays: QPArrays, slot: int) -> tuple[int, int, int, int]:
        """What the warm starts and active sets are kept by.

        Parameters
        ----------
        arrays : QPArrays
            The QP (H, g, A, b, C, l, u).
        slot : int
            Its slot (one per priority level).

        Returns
        -------
        tuple of int
            (slot, number of variables, of equality rows, of inequality rows).
        """
        return (slot, arrays.g.shape[0], arrays.b.shape[0], arrays.l.shape[0])

    def last_active(self, key: tuple[int, int, int, int]) -> np.ndarray | None:
        """The active set of the last verified optimum of a kind of QP.

        Parameters
        ----------
        key : tuple of int
            The QP's :meth:`key`.

        Returns
        -------
        ndarray of int8, or None
            Per inequality row: +1 at its upper bound, −1 at its lower one, 0 free; None before the first optimum
            (or after a QP of that key failed).
        """
        return self._active.get(key)

    def record(self, key: tuple[int, int, int, int], active: np.ndarray) -> None:
        """Record a verified optimum found by a caller's own first stage (counted as ``"active set"``): the next
        solve of the same key starts from its active set.

        Parameters
        ----------
        key : tuple of int
            The QP's :meth:`key`.
        active : ndarray of int8
            Its active set: per inequality row +1 at its upper bound, −1 at its lower one, 0 free.
        """
        self._active[key] = active
        self.counts["active set"] += 1

    def solve(
        self,
        arrays: QPArrays,
        slot: int = 0,
        problem: Callable[[], QPProblem] | None = None,
        start: np.ndarray | None = None,
        unconstrained: tuple[FloatArray, FloatArray] | None = None,
    ) -> QPSolution:
        """The verified optimum of a QP, from the first stage that finds one.

        Parameters
        ----------
        arrays : QPArrays
            The QP (H, g, A, b, C, l, u): min ½ xᵀH x + gᵀx s.t. A x = b, l ≤ C x ≤ u, H positive definite.
        slot : int, optional
            One per priority level: the warm starts and active sets are kept per slot.
        problem : callable, optional
            ``problem()`` gives the named :class:`~armctl.controllers.osc.QPProblem`, for a user's primary solver
            that takes one (without it, such a solver's stages fail).
        start : ndarray of int8, optional
            The active set to start the first stage from, instead of the last optimum's.
        unconstrained : (ndarray, ndarray), optional
            H's upper Cholesky factor (LAPACK's ``dposv``) and the unconstrained minimum −H⁻¹g, if the caller has
            them (without equality rows): the exact solves on active sets then start from them.

        Returns
        -------
        QPSolution
            x, the multipliers y, z (H x + g + Aᵀy + Cᵀz = 0), the active set, the ``stage`` that found it and the
            ``fallbacks`` taken.

        Raises
        ------
        QPFailure
            No stage found a verified optimum; ``attempts`` says what each did.
        """
        key = self.key(arrays, slot)
        attempts: list[tuple[str, str]] = []
        if self.first is not None:
            begin = self._active.get(key) if start is None else start
            for active in (begin, None) if begin is not None else (None,):  # a misleading start: from none
                try:
                    sol = self.first.solve_from(arrays, active)
                except (SolverError, InfeasibleError) as err:
                    attempts.append((STAGES[0], str(err)))
                    continue
                if self.check(arrays, sol.x, sol.y, sol.z):
                    if sol.active is not None:
                        self._active[key] = sol.active
                    self.counts[STAGES[0]] += 1
                    sol.stage = STAGES[0]
                    return sol
                attempts.append((STAGES[0], f"{self.first.name}: not the optimum"))
        sets = ActiveSets(arrays, unconstrained)
        fallbacks = 0
        for stage in STAGES[1:]:
            solver = self.second if stage == "second" else self.primary
            if solver is None:
                continue
            mode = "warm" if stage == "second" else stage
            if stage in FALLBACKS:
                fallbacks += 1
            try:
                sol = self._call(solver, arrays, slot, mode, problem or _no_problem)
            except (SolverError, InfeasibleError) as err:
                attempts.append((stage, str(err)))
                continue
            if sol is None:
                fallbacks -= 1
                continue
            found = self._verify(sets, sol)
            if found is None:
                attempts.append((stage, f"{getattr(solver, 'name', type(solver).__name__)}: not the optimum"))
                continue
            x, y, z, active = found
            self._active[key] = active
            self.counts[stage] += 1
            return QPSolution(x, "solved", sol.iterations, sol.solver, y, z, stage, fallbacks, active)
        self._active.pop(key, None)
        self.counts["failed"] += 1
        raise QPFailure(attempts)

    @staticmethod
    def _verify(sets: ActiveSets, sol: QPSolution) -> tuple[FloatArray, FloatArray, FloatArray, np.ndarray] | None:
        """The optimum that ``sol`` points at, verified: its active set solved exactly and accepted, or else
        ``sol`` itself if its KKT residuals (with its multipliers) are within the tolerances; None if neither."""
        arrays = sets.qp
        x = np.asarray(sol.x, dtype=float)[: arrays.g.shape[0]]
        if not np.isfinite(x).all():
            return None
        candidates = [active_set_of(arrays, x, sol.z)]
        if sol.z is not None:  # and the rows at their bounds, in case the multipliers mislead
            candidates.append(active_set_of(arrays, x, None))
        for active in candidates:
            exact = sets.solve(active)
            if exact is not None and sets.following(exact[0], exact[2], active) is None:
                return exact[0], exact[1], exact[2], active
        if sol.z is not None and (sol.y is not None or not arrays.b.shape[0]):
            if residuals(arrays, x, sol.y, sol.z).ok():
                return x, sol.y if sol.y is not None else np.zeros(0), sol.z, candidates[0]
        return None


def _no_problem() -> QPProblem:
    raise SolverError("this solver needs the named problem, which was not given")
