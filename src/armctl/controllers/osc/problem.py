"""`QPProblem`: one quadratic program, inspectable before it is solved (its formulation is given with the
class)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from armctl._checks import FloatArray


@dataclass(frozen=True, slots=True)
class QPArrays:
    """The arrays of one QP, without names: what the solvers and the optimality check take::

        minimise   ½ xᵀ H x + gᵀ x
        subject to A x = b,   l ≤ C x ≤ u

    (:class:`QPProblem` is the same QP with its variables and rows named; ``problem.arrays`` gives its arrays).

    Attributes
    ----------
    H : ndarray, shape (nx, nx)
        The cost's Hessian (symmetric positive definite).
    g : ndarray, shape (nx,)
        The cost's gradient at x = 0.
    A : ndarray, shape (me, nx)
        The equality rows.
    b : ndarray, shape (me,)
        Their right-hand side.
    C : ndarray, shape (mi, nx)
        The inequality rows.
    l, u : ndarray, shape (mi,)
        Their lower and upper bounds (±inf: no bound).
    """

    H: FloatArray
    g: FloatArray
    A: FloatArray
    b: FloatArray
    C: FloatArray
    l: FloatArray  # noqa: E741  (the name of the bound in the formulation)
    u: FloatArray

    @property
    def nx(self) -> int:
        """Number of decision variables."""
        return int(self.g.shape[0])

    @property
    def me(self) -> int:
        """Number of equality rows."""
        return int(self.b.shape[0])

    @property
    def mi(self) -> int:
        """Number of inequality rows."""
        return int(self.l.shape[0])


@dataclass(frozen=True)
class QPProblem(QPArrays):
    """The QP of one priority level at one control step, named row by row (its arrays are read-only)::

        minimise   ½ xᵀ H x + gᵀ x
        subject to A x = b,   l ≤ C x ≤ u

    with x = [q̈ (n); τ (n); f_1 (3); …; f_k (3); s (m, only with slacks)]: the arrays of :class:`QPArrays` with
    their variables and rows named.

    Attributes
    ----------
    H, g, A, b, C, l, u : ndarray
        As for :class:`QPArrays`. The equality rows A are the equation of motion [N·m], the contacts' rows and the
        rows that keep the levels above; the inequality rows C the limits and friction cones, their bounds l, u
        [rad/s², N·m or N, by row] ±inf where there is none.
    variables : dict of str to slice
        The blocks of x: ``"qdd"`` [rad/s²], ``"tau"`` [N·m], each active contact's name (its force [N]), and
        ``"slack"`` with slacks.
    eq_names : tuple of str
        The name of each row of A, e.g. ``dynamics[panda_joint4]``, ``priority[0]``.
    ineq_names : tuple of str
        The name of each row of C, e.g. ``torque_limit[panda_joint4]``.
    level : int
        The priority level.
    tasks : tuple of str
        The names of the level's tasks.
    info : dict
        Anything more a caller wants to attach.
    """

    variables: dict[str, slice]
    eq_names: tuple[str, ...]
    ineq_names: tuple[str, ...]
    level: int = 0
    tasks: tuple[str, ...] = ()
    info: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in ("H", "g", "A", "b", "C", "l", "u"):
            getattr(self, name).flags.writeable = False

    @property
    def arrays(self) -> QPArrays:
        """The QP's arrays without the names (read-only, shared with this problem)."""
        return QPArrays(self.H, self.g, self.A, self.b, self.C, self.l, self.u)

    def block(self, x: FloatArray, name: str) -> FloatArray:
        """The part of a solution that is one variable block.

        Parameters
        ----------
        x : ndarray, shape (nx,)
            A point of the problem.
        name : str
            The block: ``"qdd"``, ``"tau"``, a contact's name or ``"slack"`` (see ``variables``).

        Returns
        -------
        ndarray
            A view of ``x``'s entries of that block.

        Raises
        ------
        KeyError
            The problem has no block of that name.
        """
        return x[self.variables[name]]

    def objective(self, x: FloatArray) -> float:
        """The cost at a point.

        Parameters
        ----------
        x : ndarray, shape (nx,)
            A point of the problem.

        Returns
        -------
        float
            ½ xᵀ H x + gᵀ x.
        """
        return float(0.5 * x @ self.H @ x + self.g @ x)

    def violations(self, x: FloatArray, tol: float = 1e-6) -> dict[str, float]:
        """The rows that a point violates.

        Parameters
        ----------
        x : ndarray, shape (nx,)
            A point of the problem.
        tol : float, optional
            The violation tolerated [the row's units: N·m, rad/s², N].

        Returns
        -------
        dict of str to float
            Row name → violation (|A_i x − b_i|, or how far C_i x is outside [l_i, u_i]), for every row violated by
            more than ``tol``; empty if none is.
        """
        out: dict[str, float] = {}
        r = self.A @ x - self.b
        for i in np.flatnonzero(np.abs(r) > tol):
            out[self.eq_names[i]] = float(abs(r[i]))
        cx = self.C @ x
        over = np.maximum(cx - self.u, self.l - cx)
        for i in np.flatnonzero(over > tol):
            out[self.ineq_names[i]] = float(over[i])
        return out

    def to_qpsolvers(self) -> Any:
        """This problem in qpsolvers' form, to solve it with any solver of qpsolvers.

        Returns
        -------
        qpsolvers.Problem
            (P, q, G, h, A, b) = (H, g, G, h, A, b): each finite bound of l ≤ C x ≤ u becomes one row of G x ≤ h;
            None in place of empty G, h, A, b.
        """
        import qpsolvers

        up = np.isfinite(self.u)
        lo = np.isfinite(self.l)
        G = np.vstack([self.C[up], -self.C[lo]])
        h = np.concatenate([self.u[up], -self.l[lo]])
        return qpsolvers.Problem(
            np.array(self.H),
            np.array(self.g),
            G if len(h) else None,
            h if len(h) else None,
            np.array(self.A) if len(self.b) else None,
            np.array(self.b) if len(self.b) else None,
        )
