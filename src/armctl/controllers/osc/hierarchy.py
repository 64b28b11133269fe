"""Strict priorities by cascaded QPs.

Level 0 is solved first. Every later level k is solved under the extra equality rows that keep what the
levels above achieved: with T_j the weighted task rows of level j and x_j its solution,

    T_j x = T_j x_{k−1}   for every j < k

(the optimal residual of a strictly convex least-squares level is unique, so these rows describe exactly the
optimal set of the level above). The rows are compressed to an orthonormal basis F of their span (an SVD of
the part of T_j outside the span so far, keeping singular values above ``rank_tol`` relative to the largest),
so that dependent rows (a pose task above a posture task, say) never make the equality rows rank-deficient.

A lower level whose solve fails (it can only be numerical: x_{k−1} is feasible for it) keeps x_{k−1}, and the
levels below it are solved with its residual frozen at that value (T_k x = T_k x_{k−1}), so that they still
cannot degrade it; its status is reported, nothing is hidden.
"""

from __future__ import annotations

import numpy as np

from armctl._checks import FloatArray
from armctl.controllers.osc.build import StepQP
from armctl.controllers.osc.problem import QPProblem
from armctl.controllers.osc.solve import QPSolution
from armctl.errors import InfeasibleError, SolverError


class OSCSolution:
    """Result of one control step: the variables ``x`` and their blocks (``qdd`` [rad/s²], ``tau`` [N·m],
    ``forces`` per active contact [N]), each task's unweighted residual J x − b (``residuals``), the slack of
    every task when slacks are on (``slacks``, else None), the solver's result per level (``solutions``; None
    for a level that kept the one above, see ``level_status``) and :meth:`problem` to look at the QP of a
    level."""

    __slots__ = ("_frozen", "forces", "iterations", "level_status", "qdd", "slacks", "solutions", "step", "tau", "x")

    def __init__(
        self,
        step: StepQP,
        x: FloatArray,
        solutions: tuple[QPSolution | None, ...],
        level_status: tuple[str, ...],
        slacks: dict[str, FloatArray] | None,
        frozen: list[tuple[FloatArray, FloatArray] | None],
    ) -> None:
        v = step.layout.variables
        self.step = step
        self.x = x
        self.qdd = x[v["qdd"]]
        self.tau = x[v["tau"]]
        self.forces = {c.name: x[v[c.name]] for c in step.layout.contacts} if step.layout.contacts else {}
        self.solutions = solutions
        #: solver iterations summed over the levels
        self.iterations = 0
        for s in solutions:
            if s is not None:
                self.iterations += s.iterations
        self.level_status = level_status
        self.slacks = slacks
        self._frozen = frozen

    @property
    def residuals(self) -> dict[str, FloatArray]:
        """Unweighted residual J_i x_i − b_i of every task (task name → (dim,))."""
        out: dict[str, FloatArray] = {}
        for lev in self.step.levels:
            out.update(lev.residuals(self.x))
        return out

    def problem(self, level: int = 0) -> QPProblem:
        """The QP that was solved for ``level`` (with its rows freezing the levels above)."""
        return self.step.problem(level, self._frozen[level])


def _extend_basis(F: FloatArray, T: FloatArray, rank_tol: float) -> FloatArray:
    """Orthonormal rows spanning rows(F) + rows(T)."""
    if T.shape[0] == 0:
        return F
    P = T - (T @ F.T) @ F if F.shape[0] else T
    _, s, vt = np.linalg.svd(P, full_matrices=False)
    scale = max(float(np.abs(T).max()), 1e-300)
    keep = s > rank_tol * scale
    return np.vstack([F, vt[keep]]) if keep.any() else F


def solve_cascade(step: StepQP, solver: object, rank_tol: float = 1e-9) -> OSCSolution:
    """Solve the levels of ``step`` in priority order with ``solver`` (an object with ``solve(problem, slot)``;
    ``solve_raw(arrays, slot, problem_factory)`` is used when present and there are no slacks)."""
    nx = step.layout.nx
    raw = getattr(solver, "solve_raw", None) if not step.slacks else None
    if raw is not None and len(step.levels) == 1:  # the common case, kept lean
        sol = raw(step.arrays(0), 0, lambda: step.problem(0))
        return OSCSolution(step, sol.x[:nx], (sol,), ("solved",), None, [None])
    F = np.zeros((0, nx))
    x: FloatArray | None = None
    sols: list[QPSolution | None] = []
    status: list[str] = []
    frozen_rows: list[tuple[FloatArray, FloatArray] | None] = []
    slacks: dict[str, FloatArray] | None = {} if step.slacks else None
    last = len(step.levels) - 1
    for k, lev in enumerate(step.levels):
        frozen = None if x is None else (F, F.dot(x))
        frozen_rows.append(frozen)
        try:
            if raw is not None:
                sol = raw(step.arrays(k, frozen), k, lambda k=k, fr=frozen: step.problem(k, fr))
            else:
                sol = solver.solve(step.problem(k, frozen), k)  # type: ignore[attr-defined]
        except (InfeasibleError, SolverError) as err:
            if x is None:
                raise
            sols.append(None)
            status.append(f"kept level {k - 1}: {type(err).__name__}")
            if k < last:  # the levels below keep this level's residual at x_{k−1}: it gives way to none of them
                F = _extend_basis(F, lev.T, rank_tol)
            continue
        sols.append(sol)
        status.append("solved")
        x = sol.x[:nx]
        if slacks is not None:
            s = sol.x[nx:]
            slacks.update({name: s[sl] for name, sl in lev.slices.items()})
        if k < last:
            F = _extend_basis(F, lev.T, rank_tol)
    if x is None:
        raise SolverError("the controller has no priority level to solve", value=step)
    return OSCSolution(step, x, tuple(sols), tuple(status), slacks, frozen_rows)
