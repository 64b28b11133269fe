"""The optimum of a contact QP on its equality rows alone, and its verdict, as CasADi expressions for the
generated contact data (:mod:`~armctl.controllers.osc.generated_contact`): with no inequality row active, the
QP's optimum is the equality-constrained one, and the KKT conditions with z = 0 decide whether it is."""

from __future__ import annotations

import casadi as cs

from armctl.controllers.osc.optimality import DUAL_TOL, PRIMAL_TOL
from armctl.controllers.osc.scale import MAX_TASK_RHS
from armctl.dynamics.recursive import cholesky_factor, cholesky_solve, cholesky_substitute


def equality_optimum(hess: cs.SX, grad: cs.SX, a: cs.SX, b: cs.SX) -> list[cs.SX]:
    """(y*, λ, A y* − b, H y* + g + Aᵀλ): the optimum of ½yᵀHy + gᵀy subject to A y = b alone, by
    the Schur complement of H (Cholesky written out): y₀ = −H⁻¹g, W = H⁻¹Aᵀ, λ = (A W)⁻¹(A y₀ − b),
    y* = y₀ − W λ; and its residuals, which the step checks."""
    low = cholesky_factor(hess)  # once, for y₀ and every column of W
    y0 = -cholesky_substitute(low, grad)
    w = cholesky_substitute(low, a.T)
    lam = cholesky_solve(a @ w, a @ y0 - b)
    y = y0 - w @ lam
    return [y, lam, a @ y - b, hess @ y + grad + a.T @ lam]


def verdict(optimum: list[cs.SX], grad: cs.SX, c: cs.SX, values: cs.SX, lo: cs.SX, up: cs.SX) -> cs.SX:
    """1 if the optimum on the contact rows alone is the QP's, by the check of
    :func:`~armctl.controllers.osc.optimality.equality_optimum_ok` (its residuals within PRIMAL_TOL and DUAL_TOL
    (1 + ‖g‖∞), every inequality row's value within [l, u] exactly) with the level in scale (c ≤ MAX_TASK_RHS²);
    else 0 (NaN included: every comparison with NaN is false)."""
    _, _, eq_res, stat = optimum
    scale = 1.0 + cs.mmax(cs.fabs(grad))
    ok = cs.logic_and(cs.le(cs.mmax(cs.fabs(eq_res)), PRIMAL_TOL), cs.le(cs.mmax(cs.fabs(stat)), DUAL_TOL * scale))
    ok = cs.logic_and(ok, cs.le(c, MAX_TASK_RHS**2))
    for i in range(values.shape[0]):
        ok = cs.logic_and(ok, cs.logic_and(cs.le(lo[i], values[i]), cs.le(values[i], up[i])))
    return ok
