"""`DaqpSolver`: DAQP, a dual active-set QP solver in C (Arnström, Bemporad & Axehill, "A dual active-set solver
for embedded quadratic programming using recursive LDLᵀ updates", IEEE Trans. Automatic Control 67(8), 2022),
started from a given active set: the first stage of the controller's solver chain.

For min ½ xᵀH x + gᵀx s.t. A x = b, l ≤ C x ≤ u (H positive definite) DAQP works on the dual: from the active
set it is given (the rows taken at a bound, the equalities always), it adds the most violated row or drops a
row whose multiplier has the wrong sign, each step an exact solve on the new active set by an update of an
LDLᵀ factorisation, until every row holds and every multiplier has its sign. From the active set of the last
control step's optimum (consecutive steps rarely change which limits bind) it usually ends in one step; from
scratch, a QP of a 7-joint arm takes a few. Its answer is the exact solution on its final active set — which
the controller still checks (:func:`~armctl.controllers.osc.optimality.kkt_ok`) before using it.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from armctl._checks import FloatArray
from armctl.controllers.osc.problem import Arrays
from armctl.controllers.osc.solve import QPSolution
from armctl.errors import SolverError

#: DAQP's marks of a row (its ``sense``): active at its upper bound, active at its lower bound, an equality
_UPPER, _LOWER, _EQUALITY = 1, 3, 5
#: the mark of an inequality row by its entry of an active set (int8: +1 upper, −1 lower, 0 free; index −1 is
#: the last entry)
_SENSE = np.array([0, _UPPER, _LOWER], dtype=np.intc)
#: what DAQP's exit flags mean
EXIT_FLAGS = {
    1: "optimal",
    2: "optimal with soft rows violated",
    -1: "infeasible",
    -2: "cycling",
    -3: "unbounded",
    -4: "iteration limit",
    -5: "non-convex",
    -6: "overdetermined initial active set",
    -7: "time limit",
    -8: "unsupported",
}


class DaqpSolver:
    """DAQP (module docstring) on the arrays (H, g, A, b, C, l, u) of a QP, started from an active set.
    ``primal_tol``: the largest row violation DAQP accepts [the row's units] (below the controller's check's
    :data:`~armctl.controllers.osc.optimality.PRIMAL_TOL`, so that what DAQP calls optimal passes it);
    ``iter_limit``: its iterations at most."""

    name = "daqp"

    def __init__(self, primal_tol: float = 1e-10, iter_limit: int = 1000) -> None:
        import daqp

        self._solve = daqp.solve
        self.primal_tol = float(primal_tol)
        self.iter_limit = int(iter_limit)

    def __reduce__(self) -> tuple[Any, ...]:
        return (DaqpSolver, (self.primal_tol, self.iter_limit))

    def reset(self) -> None:
        """Nothing to forget: the active set to start from is given at each solve."""

    def solve_from(self, arrays: Arrays, active: np.ndarray | None) -> QPSolution:
        """The optimum of the QP ``arrays`` from the active set ``active`` (int8 per row of C: +1 at its upper
        bound, −1 at its lower, 0 free; None: none), with its multipliers y, z (H x + g + Aᵀy + Cᵀz = 0, z > 0 at
        an upper bound) and its final active set. Raises SolverError with DAQP's exit flag if it finds no optimum.
        A start can mislead it (rows that depend on each other, a row taken at an infinite bound): what it returns
        is to be checked (:func:`~armctl.controllers.osc.optimality.kkt_ok`), as the chain does."""
        H, g, A, b, C, l, u = arrays  # noqa: E741
        me = b.shape[0]
        if me:
            rows: FloatArray = np.concatenate((A, C))
            upper, lower = np.concatenate((b, u)), np.concatenate((b, l))
            sense = np.empty(me + l.shape[0], dtype=np.intc)
            sense[:me] = _EQUALITY
            sense[me:] = 0 if active is None else _SENSE[active]
        else:
            rows, upper, lower = C, u, l
            sense = None if active is None else _SENSE[active]
        data = (H, g, rows, upper, lower)
        try:
            x, _, flag, info = self._solve(*data, sense, primal_tol=self.primal_tol, iter_limit=self.iter_limit)
        except ValueError:  # DAQP takes writable arrays only: read-only ones (a layout's constant rows) copied
            data = tuple(np.array(a) for a in data)  # type: ignore[assignment]
            x, _, flag, info = self._solve(*data, sense, primal_tol=self.primal_tol, iter_limit=self.iter_limit)
        if flag != 1:
            raise SolverError(f"daqp: {EXIT_FLAGS.get(flag, 'exit flag')} ({flag})", value=flag)
        lam = info["lam"]
        if not math.isfinite(sum(x.tolist()) + sum(lam.tolist())):
            raise SolverError("daqp: a non-finite solution called optimal", value=flag)
        z = lam[me:]
        return QPSolution(x, "solved", info["iterations"], self.name, lam[:me], z, active=np.sign(z).astype(np.int8))

    def solve_raw(self, arrays: Arrays, slot: int = 0, mode: str = "warm") -> QPSolution:
        """The optimum of the QP ``arrays`` from no active row (the solver interface of the controller's chain;
        ``slot`` and ``mode`` do not matter: DAQP keeps nothing between solves)."""
        return self.solve_from(arrays, None)
