"""`DaqpSolver`: DAQP, a dual active-set QP solver in C, started from a given active set: the first stage of the
controller's solver chain (the method is described with the class).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from armctl._checks import FloatArray
from armctl.controllers.osc.problem import QPArrays
from armctl.controllers.osc.solve import QPSolution, QPSolver
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


class DaqpSolver(QPSolver):
    """DAQP (Arnström, Bemporad & Axehill, "A dual active-set solver for embedded quadratic programming using
    recursive LDLᵀ updates", IEEE Trans. Automatic Control 67(8), 2022) on the arrays (H, g, A, b, C, l, u) of a
    QP, started from an active set.

    Parameters
    ----------
    primal_tol : float, optional
        The largest row violation DAQP accepts [the row's units]; below the controller's check's tolerance
        (1e-8), so that what DAQP calls optimal passes it.
    iter_limit : int, optional
        Its iterations at most.

    Notes
    -----
    For min ½ xᵀH x + gᵀx s.t. A x = b, l ≤ C x ≤ u (H positive definite) DAQP works on the dual: from the active
    set it is given (the rows taken at a bound, the equalities always), it adds the most violated row or drops a
    row whose multiplier has the wrong sign, each step an exact solve on the new active set by an update of an
    LDLᵀ factorisation, until every row holds and every multiplier has its sign. From the active set of the last
    control step's optimum (consecutive steps rarely change which limits bind) it usually ends in one step; from
    scratch, a QP of a 7-joint arm takes a few. Its answer is the exact solution on its final active set — which
    the controller still checks (:func:`~armctl.controllers.osc.optimality.kkt_ok`) before using it.

    :meth:`solve_raw` is :meth:`solve_from` with no active row (``slot`` and ``mode`` are not used: DAQP keeps
    nothing between solves).
    """

    name = "daqp"

    def __init__(self, primal_tol: float = 1e-10, iter_limit: int = 1000) -> None:
        import daqp

        self._solve = daqp.solve
        self.primal_tol = float(primal_tol)
        self.iter_limit = int(iter_limit)

    def __reduce__(self) -> tuple[Any, ...]:
        return (DaqpSolver, (self.primal_tol, self.iter_limit))

    def solve_from(self, arrays: QPArrays, active: np.ndarray | None) -> QPSolution:
        """The optimum of a QP, from a given active set.

        A start can mislead it (rows that depend on each other, a row taken at an infinite bound): what it returns
        is to be checked (:func:`~armctl.controllers.osc.optimality.kkt_ok`), as the chain does.

        Parameters
        ----------
        arrays : QPArrays
            The QP (H, g, A, b, C, l, u), H positive definite.
        active : ndarray of int8, shape (mi,), or None
            The active set to start from: per row of C, +1 at its upper bound, −1 at its lower one, 0 free;
            None: no active row.

        Returns
        -------
        QPSolution
            x, its multipliers y, z (H x + g + Aᵀy + Cᵀz = 0, z > 0 at an upper bound) and its final active set
            (``active``).

        Raises
        ------
        SolverError
            DAQP finds no optimum (the error gives its exit flag: infeasible, cycling, iteration limit, ...), or
            calls a non-finite point optimal.
        """
        H, g, b = arrays.H, arrays.g, arrays.b
        me = b.shape[0]
        if me:
            rows: FloatArray = np.concatenate((arrays.A, arrays.C))
            upper, lower = np.concatenate((b, arrays.u)), np.concatenate((b, arrays.l))
            both = np.empty(me + arrays.l.shape[0], dtype=np.intc)
            both[:me] = _EQUALITY
            both[me:] = 0 if active is None else _SENSE[active]
            sense: np.ndarray | None = both
        else:
            rows, upper, lower = arrays.C, arrays.u, arrays.l
            sense = None if active is None else _SENSE[active]
        if not (H.flags.c_contiguous and rows.flags.c_contiguous):  # DAQP reads the buffers as C-ordered
            H, rows = np.ascontiguousarray(H), np.ascontiguousarray(rows)
        data = (H, g, rows, upper, lower)
        try:
            x, _, flag, info = self._solve(*data, sense, primal_tol=self.primal_tol, iter_limit=self.iter_limit)
        except ValueError:  # DAQP takes writable arrays only: read-only ones (a layout's constant rows) copied
            data = (np.array(H), np.array(g), np.array(rows), np.array(upper), np.array(lower))
            x, _, flag, info = self._solve(*data, sense, primal_tol=self.primal_tol, iter_limit=self.iter_limit)
        if flag != 1:
            raise SolverError(f"daqp: {EXIT_FLAGS.get(flag, 'exit flag')} ({flag})", value=flag)
        lam = info["lam"]
        if not math.isfinite(sum(x.tolist()) + sum(lam.tolist())):
            raise SolverError("daqp: a non-finite solution called optimal", value=flag)
        z = lam[me:]
        return QPSolution(x, "solved", info["iterations"], self.name, lam[:me], z, active=np.sign(z).astype(np.int8))

    def solve_raw(self, arrays: QPArrays, slot: int = 0, mode: str = "warm") -> QPSolution:
        # (documented with QPSolver.solve_raw and the class)
        return self.solve_from(arrays, None)
