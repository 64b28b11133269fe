"""Strict priorities by cascaded QPs.

Level 0 is solved first. Every later level k is solved under the extra equality rows that keep what the
levels above achieved: with T_j the weighted task rows of level j and x_j its solution,

    T_j x = T_j x_{k−1}   for every j < k

(the optimal residual of a strictly convex least-squares level is unique, so these rows describe exactly the
optimal set of the level above). The rows are compressed to an orthonormal basis F of their span (an SVD of
the part of T_j outside the span so far, keeping singular values above ``rank_tol`` relative to the largest),
so that dependent rows (a pose task above a posture task, say) never make the equality rows rank-deficient.

Every level is solved by the controller's :class:`~armctl.controllers.osc.chain.SolverChain` (a verified
optimum, with fallbacks). A lower level for which no stage finds one (it can only be numerical: x_{k−1} is
feasible for it) keeps x_{k−1}, and the levels below it are solved with its residual frozen at that value
(T_k x = T_k x_{k−1}), so that they still cannot degrade it; its status is reported, nothing is hidden — and
nothing is diagnosed there: :meth:`OSCSolution.diagnose` looks for conflicting rows when asked.
"""

from __future__ import annotations

from functools import partial

import numpy as np
from scipy.linalg import lapack

from armctl._checks import FloatArray
from armctl.controllers.osc import diagnose as _diagnose
from armctl.controllers.osc.build import StepQP
from armctl.controllers.osc.chain import QPFailure, SolverChain
from armctl.controllers.osc.problem import QPArrays, QPProblem
from armctl.controllers.osc.solve import QPSolution
from armctl.errors import SolverError


class OSCSolution:
    """The result of one control step of :class:`~armctl.controllers.OperationalSpaceQP` (made by the controller:
    ``ctrl.last_solution``, or :meth:`~armctl.controllers.OperationalSpaceQP.solve`).

    Parameters
    ----------
    step : StepQP
        The QPs of the step.
    x : ndarray, shape (nx,)
        The solution's variables (without slacks).
    solutions : tuple of QPSolution or None
        The solver chain's result per level; None for a level that kept the one above.
    level_status : tuple of str
        Per level, ``"solved"`` or why it kept the level above's solution.
    slacks : dict of str to ndarray, or None
        Each task's slack with slacks on, else None.
    frozen : list of (ndarray, ndarray) or None
        Per level, the rows (F, φ) that kept the levels above (None for level 0).

    Attributes
    ----------
    qdd : ndarray, shape (n,)
        q̈ [rad/s²] (a view of ``x``).
    tau : ndarray, shape (n,)
        τ [N·m] (a view of ``x``), before the controller clips its output onto the torque limits.
    forces : dict of str to ndarray
        Each active contact's force f (3,) [N], world axes, exerted by the environment on the robot.
    iterations : int
        Solver iterations summed over the levels.

    Notes
    -----
    Strict priorities by cascaded QPs: level 0 is solved first, and every later level k under the extra
    equality rows T_j x = T_j x_{k−1} for every level j < k (T_j the weighted task rows of level j, x_{k−1} the
    solution of the level above), compressed to an orthonormal basis of their span. A lower level for which no
    stage of the solver chain finds a verified optimum (it can only be numerical: x_{k−1} is feasible for it)
    keeps x_{k−1}, and the levels below it are solved with its residual frozen at that value; its status is
    reported in ``level_status``, and :meth:`diagnose` looks for conflicting rows when asked.
    """

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
        # solver iterations summed over the levels
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
        """The QP that was solved for one level.

        Parameters
        ----------
        level : int, optional
            The level's index in priority order.

        Returns
        -------
        QPProblem
            Its QP, with the rows that kept the levels above (``priority[i]``).
        """
        return self.step.problem(level, self._frozen[level])

    @property
    def fallbacks(self) -> int:
        """Fallback stages the solver chain took in this step, summed over the levels."""
        return sum(s.fallbacks for s in self.solutions if s is not None)

    def diagnose(self, level: int = 0) -> dict[str, float] | None:
        """The rows of one level's QP that conflict, by :func:`~armctl.controllers.osc.conflicting_rows`. An
        elastic program of a few ms: run it when a level was kept (see ``level_status``), not in a loop.

        Parameters
        ----------
        level : int, optional
            As for :meth:`problem`.

        Returns
        -------
        dict of str to float, or None
            Row name → how much to relax it (0 for a row that binds the conflict without being relaxed); empty
            if the QP is feasible; None if the diagnosis itself failed.
        """
        return _diagnose.conflicting_rows(self.problem(level))


#: the reciprocal condition number (LAPACK's estimate, 1-norm) of P Pᵀ above which :func:`extend_basis` takes
#: the Cholesky basis: its rows are then independent by a margin of about 1e5 over the SVD's rank test
WELL_CONDITIONED = 1e-6


def extend_basis(F: FloatArray, T: FloatArray, rank_tol: float = 1e-9) -> FloatArray:
    """Orthonormal rows spanning rows(F) + rows(T): F and a basis of P, the part of T outside rows(F).

    When P Pᵀ is well conditioned (:data:`WELL_CONDITIONED`, the usual case: a level's task rows independent of
    each other and of the levels above), the basis is L⁻¹P with L the Cholesky factor of P Pᵀ (orthonormal:
    L⁻¹ P Pᵀ L⁻ᵀ = I), which costs a factorisation of a matrix of the level's size and one triangular solve.
    Otherwise the SVD of P decides the rank: its right singular vectors whose singular values exceed
    ``rank_tol`` times T's largest entry. Rows of P shorter than that are left out first (a task direction of
    zero weight). Either way the span is that of the rows kept, so the QP of the level below has the same
    feasible set and the same optimum."""
    if T.shape[0] == 0:
        return F
    P = T - (T @ F.T) @ F if F.shape[0] else T
    scale = max(float(np.abs(T).max()), 1e-300)
    G = P.dot(P.T)
    rows = np.diag(G) > (rank_tol * scale) ** 2  # rows of no weight (a task direction switched off) span nothing
    if not rows.all():
        P, G = P[rows], G[np.ix_(rows, rows)]
    if 0 < P.shape[0] <= P.shape[1]:
        c, info = lapack.dpotrf(G, lower=1, clean=1)
        if info == 0:
            rcond, info = lapack.dpocon(c, float(np.abs(G).sum(axis=0).max()), uplo="L")
            if info == 0 and rcond > WELL_CONDITIONED:
                basis, info = lapack.dtrtrs(c, P, lower=1)
                if info == 0:
                    return np.vstack([F, basis]) if F.shape[0] else basis
    if not P.shape[0]:
        return F
    _, s, vt = np.linalg.svd(P, full_matrices=False)
    keep = s > rank_tol * scale
    return np.vstack([F, vt[keep]]) if keep.any() else F


def solve_cascade(step: StepQP, chain: SolverChain, rank_tol: float = 1e-9) -> OSCSolution:
    """Solve the levels of ``step`` in priority order with ``chain``. Raises
    :class:`~armctl.controllers.osc.chain.QPFailure` if level 0 has no verified optimum."""
    nx = step.layout.nx
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
        if step.slacks:
            p = step.problem(k, frozen)
            arrays: QPArrays = p.arrays
        else:
            arrays = step.arrays(k, frozen)
        try:
            sol = chain.solve(arrays, k, partial(step.problem, k, frozen))
        except QPFailure as err:
            if x is None:
                raise
            sols.append(None)
            status.append(f"kept level {k - 1}: no verified optimum ({err.attempts[-1][1] if err.attempts else ''})")
            if k < last:  # the levels below keep this level's residual at x_{k−1}: it gives way to none of them
                F = extend_basis(F, lev.T, rank_tol)
            continue
        sols.append(sol)
        status.append("solved")
        x = sol.x[:nx]
        if slacks is not None:
            s = sol.x[nx:]
            slacks.update({name: s[sl] for name, sl in lev.slices.items()})
        if k < last:
            F = extend_basis(F, lev.T, rank_tol)
    if x is None:
        raise SolverError("the controller has no priority level to solve", value=step)
    return OSCSolution(step, x, tuple(sols), tuple(status), slacks, frozen_rows)
