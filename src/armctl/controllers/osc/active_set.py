"""A dense dual active-set QP solver (Goldfarb & Idnani, "A numerically stable dual method for solving strictly
convex quadratic programs", Math. Programming 27, 1983): the method of quadprog and of TSID's eiquadprog, here
in NumPy for the small QPs of one control step, where it is the controller's second solver. The method is
described with :class:`DualActiveSetSolver`, its factorisation with :func:`dual_active_set`.

For min ½ xᵀH x + gᵀx s.t. A x = b, l ≤ C x ≤ u with H positive definite, every finite bound is written as a
row nᵀx ≥ h (a lower bound as C_i x ≥ l_i, an upper one as −C_i x ≥ −u_i). Written in NumPy, it is slower than
the compiled solvers (DAQP, ProxQP): which is why it comes last in the controller's chain of solvers.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import solve_triangular

from armctl._checks import FloatArray
from armctl.controllers.osc.problem import QPArrays
from armctl.controllers.osc.solve import QPSolution, QPSolver
from armctl.errors import InfeasibleError, SolverError

#: a row whose normal has a part outside the active rows' span below this fraction of its size (in H⁻¹'s
#: metric) is taken as dependent on them
DEPENDENT = 1e-10


def _givens(a: float, b: float) -> tuple[float, float]:
    """(c, s) of the rotation taking (a, b) to (√(a² + b²), 0): c a + s b = √(a² + b²), −s a + c b = 0."""
    h = math.hypot(a, b)
    if h == 0.0:
        return 1.0, 0.0
    return a / h, b / h


def dual_active_set(
    arrays: QPArrays, max_iter: int | None = None, tol: float = 1e-10
) -> tuple[FloatArray, FloatArray, FloatArray, int]:
    """(x, y, z, iterations) of the QP ``arrays``, multipliers in the convention
    H x + g + Aᵀy + Cᵀz = 0 (z > 0 at an upper bound, < 0 at a lower one). ``tol``: a row violated by less than
    ``tol`` (1 + |bound|) counts as met. Raises InfeasibleError if no point meets the rows, SolverError if H is
    not positive definite or the iterations run out (default 10 (n + rows) + 50).

    As in Goldfarb & Idnani's paper (and quadprog), the active rows' normals N are kept through an orthogonal
    factorisation, J = L⁻ᵀQ with H = L Lᵀ and JᵀN = [R; 0] (R upper triangular): the directions are
    z = J₂ d₂ and r = R⁻¹ d₁ with d = Jᵀ n_p, and a row joins or leaves by Givens rotations of J and R."""
    H, g, A, b, C, lb, ub = arrays.H, arrays.g, arrays.A, arrays.b, arrays.C, arrays.l, arrays.u
    n, me, mi = g.shape[0], b.shape[0], lb.shape[0]
    try:
        L = np.linalg.cholesky(H)
    except np.linalg.LinAlgError:
        raise SolverError("the QP's Hessian is not positive definite", value=H) from None
    J = solve_triangular(L, np.eye(n), lower=True).T  # L⁻ᵀ: Jᵀ H J = I
    x = -J.dot(J.T.dot(g))
    lo, up = np.flatnonzero(np.isfinite(lb)), np.flatnonzero(np.isfinite(ub))
    G = np.vstack([C[lo], -C[up]]) if mi else np.zeros((0, n))  # rows G x ≥ h
    h = np.concatenate([lb[lo], -ub[up]]) if mi else np.zeros(0)
    row = np.concatenate([lo, up])  # the row of C behind each row of G
    side = np.concatenate([-np.ones(lo.size), np.ones(up.size)])  # −1 lower bound, +1 upper
    slack_tol = tol * (1.0 + np.abs(h))
    R = np.zeros((n, n))
    ids: list[int] = []  # per active row: −1 − i for equality i, else its row of G
    signs: list[float] = []  # equality i joined as sign · A_i x ≥ sign · b_i
    mult: list[float] = []  # ≥ 0 for active inequalities
    budget = max_iter if max_iter is not None else 10 * (n + me + G.shape[0]) + 50
    iterations = 0

    def drop(k: int) -> None:
        """Active row k leaves: R loses column k, its triangle is restored by rotating rows k.., and J alike."""
        q = len(ids)
        R[:, k : q - 1] = R[:, k + 1 : q]
        R[:, q - 1] = 0.0
        for j in range(k, q - 1):
            c, s = _givens(R[j, j], R[j + 1, j])
            rj, rj1 = R[j, j:q].copy(), R[j + 1, j:q].copy()
            R[j, j:q], R[j + 1, j:q] = c * rj + s * rj1, -s * rj + c * rj1
            R[j + 1, j] = 0.0
            cj, cj1 = J[:, j].copy(), J[:, j + 1].copy()
            J[:, j], J[:, j + 1] = c * cj + s * cj1, -s * cj + c * cj1
        del ids[k], signs[k], mult[k]

    def join(d: FloatArray) -> None:
        """The row with d = Jᵀ n_p joins: rotate d's tail into its entry q, J alike; R gains column d[:q+1]."""
        q = len(ids)
        for j in range(n - 1, q, -1):
            c, s = _givens(d[j - 1], d[j])
            d[j - 1], d[j] = c * d[j - 1] + s * d[j], 0.0
            cj, cj1 = J[:, j - 1].copy(), J[:, j].copy()
            J[:, j - 1], J[:, j] = c * cj + s * cj1, -s * cj + c * cj1
        R[: q + 1, q] = d[: q + 1]

    def add(normal: FloatArray, rhs: float, ident: int, sign: float) -> None:
        """Move until the row ``normal·x ≥ rhs`` holds, dropping active inequalities on the way."""
        nonlocal x, iterations
        t_p = 0.0  # the new row's multiplier
        while True:
            iterations += 1
            if iterations > budget:
                raise SolverError(f"the dual active-set method did not finish in {budget} iterations", value=budget)
            q = len(ids)
            d = J.T.dot(normal)
            d2 = d[q:]
            dependent = float(d2.dot(d2)) <= (DEPENDENT**2) * float(d.dot(d))
            r = solve_triangular(R[:q, :q], d[:q], lower=False) if q else np.zeros(0)
            slack = float(normal.dot(x)) - rhs
            full = np.inf if dependent else -slack / float(d2.dot(d2))  # the step that meets the row
            partial, leave = np.inf, -1
            for j in range(q):
                if ids[j] >= 0 and r[j] > 0.0 and mult[j] / r[j] < partial:
                    partial, leave = mult[j] / r[j], j
            if full == np.inf and partial == np.inf:
                if ident < 0 and abs(slack) <= tol * (1.0 + abs(rhs)):
                    return  # an equality that the active ones already imply: redundant
                raise InfeasibleError("no point meets the QP's rows (dual active-set method)", value=ident)
            step = min(full, partial)
            if not dependent:
                x = x + step * J[:, q:].dot(d2)
            for j in range(q):
                mult[j] -= step * r[j]
            t_p += step
            if full <= partial:
                join(d)
                ids.append(ident)
                signs.append(sign)
                mult.append(t_p)
                return
            drop(leave)

    for i in range(me):
        sign = -1.0 if float(A[i].dot(x)) > b[i] else 1.0
        add(sign * A[i], sign * b[i], -1 - i, sign)
    while G.shape[0]:
        viol = G.dot(x) - h + slack_tol
        active_rows = [j for j in ids if j >= 0]
        if active_rows:
            viol[active_rows] = np.inf
        p = int(np.argmin(viol))
        if viol[p] >= 0.0:
            break
        add(G[p], float(h[p]), p, 1.0)
    y, z_out = np.zeros(me), np.zeros(mi)
    for j, ident in enumerate(ids):
        if ident < 0:
            y[-1 - ident] = -signs[j] * mult[j]
        else:
            z_out[row[ident]] += side[ident] * mult[j]
    return x, y, z_out, iterations


class DualActiveSetSolver(QPSolver):
    """A dense dual active-set QP solver in NumPy (Goldfarb & Idnani, "A numerically stable dual method for
    solving strictly convex quadratic programs", Math. Programming 27, 1983; the method of quadprog and of TSID's
    eiquadprog), behind the solver interface of the controller's chain: its second solver, an algorithm unlike
    ProxQP's proximal augmented Lagrangian, with nothing to install.

    Notes
    -----
    For min ½ xᵀH x + gᵀx s.t. A x = b, l ≤ C x ≤ u with H positive definite, every finite bound is written as a
    row nᵀx ≥ h (a lower bound as C_i x ≥ l_i, an upper one as −C_i x ≥ −u_i). Starting from the unconstrained
    minimum x = −H⁻¹g (dually feasible with no active rows), each iteration takes the most violated row p and
    moves along::

        z = H⁻¹(I − N N*) n_p  (primal),   r = N* n_p  (dual),   N* = (Nᵀ H⁻¹ N)⁻¹ Nᵀ H⁻¹

    (N: the active rows' normals as columns) until row p holds (full step, p joins the active set) or an active
    row's multiplier reaches zero (partial step, that row leaves); the equalities join first and never leave.
    Every iterate stays dually feasible and the dual objective grows, so the method ends in finitely many steps:
    at the optimum, or with a row that no step can satisfy — then the QP has no feasible point. Written in NumPy,
    it is slower than the compiled solvers, which is why it comes last in the chain.

    Every :meth:`solve_raw` starts afresh from the unconstrained minimum (``slot`` and ``mode`` are not used); it
    raises InfeasibleError if no point meets the QP's rows, SolverError if H is not positive definite or the
    iterations run out (10 (n + rows) + 50).
    """

    name = "dual active set"

    def solve_raw(self, arrays: QPArrays, slot: int = 0, mode: str = "warm") -> QPSolution:
        # (documented with QPSolver.solve_raw and the class)
        x, y, z, iterations = dual_active_set(arrays)
        return QPSolution(x, "solved", iterations, self.name, y, z)
