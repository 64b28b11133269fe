"""Diagnosis of a QP that could not be solved: which rows conflict, and by how much (the elastic program is
described with :func:`conflicting_rows`).
"""

from __future__ import annotations

from typing import Any, NoReturn

import numpy as np

from armctl.controllers.osc.problem import QPProblem
from armctl.errors import InfeasibleError, SolverError

_EPS = 1e-7  # regularisation of the elastic program
_BIG = 1e20


def conflicting_rows(p: QPProblem, tol: float = 1e-6) -> dict[str, float] | None:
    """The rows of a QP that conflict, and by how much: the diagnosis of a QP without a feasible point.

    Parameters
    ----------
    p : QPProblem
        The QP (its equation-of-motion rows are those named ``dynamics[...]``).
    tol : float, optional
        A slack above ``tol`` [the row's units] counts as a relaxation.

    Returns
    -------
    dict of str to float, or None
        Row name → how much the row must be relaxed [the row's units] (0 for a row that binds the conflict
        without being relaxed itself); empty if ``p`` is feasible; None if the elastic program could not be
        solved either (no diagnosis).

    Notes
    -----
    The elastic program relaxes every constraint except the equation of motion (physics, which τ can always
    meet on its own) by non-negative slacks and minimises their sum::

        min  Σ (p + q + s_l + s_u) + ½ ε (‖x‖² + ‖s‖²)
        s.t. A_dyn x = b_dyn,   A_rest x + p − q = b_rest,   l − s_l ≤ C x ≤ u + s_u,   p, q, s_l, s_u ≥ 0

    It always has a solution. If the slacks are zero the QP was feasible (the failure was numerical: SolverError).
    Otherwise the conflicting rows are those that must be relaxed (slack > 0, with the amount) and those that
    bind the conflict (a multiplier above 1e-3 in magnitude in the elastic program: they are tight and pay for
    the slack).
    """
    from proxsuite import proxqp

    nx, me, mi = p.nx, p.b.shape[0], p.l.shape[0]
    dyn = np.array([nm.startswith("dynamics[") for nm in p.eq_names], dtype=bool)
    rel = np.flatnonzero(~dyn)
    mr = rel.size
    ns = 2 * mr + 2 * mi  # p, q, s_l, s_u
    nv = nx + ns
    H = np.eye(nv) * _EPS
    g = np.r_[np.zeros(nx), np.ones(ns)]
    A = np.zeros((me, nv))
    A[:, :nx] = p.A
    A[rel, nx + np.arange(mr)] = 1.0
    A[rel, nx + mr + np.arange(mr)] = -1.0
    o = nx + 2 * mr
    C = np.zeros((2 * mi + ns, nv))
    C[:mi, :nx] = p.C
    C[:mi, o : o + mi] = np.eye(mi)
    C[mi : 2 * mi, :nx] = p.C
    C[mi : 2 * mi, o + mi : o + 2 * mi] = -np.eye(mi)
    C[2 * mi :, nx:] = np.eye(ns)
    lo = np.r_[np.nan_to_num(p.l, neginf=-_BIG), np.full(mi, -_BIG), np.zeros(ns)]
    up = np.r_[np.full(mi, _BIG), np.nan_to_num(p.u, posinf=_BIG), np.full(ns, _BIG)]
    qp = proxqp.dense.QP(nv, me, C.shape[0])
    qp.settings.eps_abs = 1e-10
    qp.settings.eps_rel = 0.0
    qp.settings.max_iter = 20000
    qp.settings.default_rho = 1e-8
    qp.init(H, g, A, p.b, C, lo, up)
    qp.solve()
    if qp.results.info.status != proxqp.QPSolverOutput.PROXQP_SOLVED:
        return None
    x, y, z = qp.results.x, qp.results.y, qp.results.z
    out: dict[str, float] = {}
    s = x[nx:]
    for k, i in enumerate(rel.tolist()):
        amount = s[k] + s[mr + k]
        if amount > tol or abs(y[i]) > 1e-3:
            out[p.eq_names[i]] = float(amount) if amount > tol else 0.0
    for i in range(mi):
        amount = s[2 * mr + i] + s[2 * mr + mi + i]
        if amount > tol or abs(z[i]) > 1e-3 or abs(z[mi + i]) > 1e-3:
            out[p.ineq_names[i]] = float(amount) if amount > tol else 0.0
    if not any(v > 0 for v in out.values()):
        return {}
    return out


def _infeasible(p: QPProblem, rows: dict[str, float], how: str) -> InfeasibleError:
    """The error of ``p`` without a feasible point: the conflicting ``rows`` (:func:`conflicting_rows`) and how
    much to relax each; ``how``: what found it out, shown after "no feasible point"."""
    shown = ", ".join(f"{k} (relax by {v:.4g})" if v > 0 else k for k, v in rows.items())
    return InfeasibleError(
        f"the QP of priority level {p.level} has no feasible point{how}; conflicting rows (coupled through the "
        f"equation of motion): {shown}. Relax one of these limits or contacts.",
        value=rows,
        problem=p,
    )


def raise_failure(p: QPProblem, solver: str, status: str, result: Any) -> NoReturn:
    """Raise InfeasibleError (with the conflicting rows) or SolverError for a failed solve of ``p``."""
    rows = conflicting_rows(p)
    if rows is None:
        raise SolverError(
            f"{solver} failed on the QP of priority level {p.level} ({status}) and so did the "
            "elastic program that looks for conflicting rows; the problem is likely badly scaled "
            "(check gains, weights and limits)",
            value=status,
            problem=p,
            result=result,
        )
    if rows:
        raise _infeasible(p, rows, f" ({solver}: {status})")
    raise SolverError(
        f"{solver} failed on the QP of priority level {p.level} ({status}) although it is "
        "feasible; try a looser eps_abs or another solver (solver='qpsolvers:<name>')",
        value=status,
        problem=p,
        result=result,
    )


def raise_unsolved(p: QPProblem, attempts: list[tuple[str, str]]) -> NoReturn:
    """Raise InfeasibleError (with the conflicting rows) or SolverError for ``p``, which no stage of the
    controller's solver chain solved (``attempts``: what each stage did)."""
    tried = "; ".join(f"{stage}: {what}" for stage, what in attempts)
    rows = conflicting_rows(p)
    if rows:
        raise _infeasible(p, rows, "")
    feasible = "although it is feasible" if rows is not None else "and the search for conflicting rows failed too"
    raise SolverError(
        f"no solver found a verified optimum of the QP of priority level {p.level} {feasible} ({tried}); the "
        "problem is likely badly scaled: check the gains, weights and limits",
        value=attempts,
        problem=p,
    )
