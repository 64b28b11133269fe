"""The optimum of a contact QP on its equality rows alone, and its verdict, as CasADi expressions for the
generated contact data (:mod:`~armctl.controllers.osc.generated_contact`): with no inequality row active, the
QP's optimum is the equality-constrained one, and the KKT conditions with z = 0 decide whether it is. Where it
is not, :func:`active_set_optimum` iterates on active sets from the rows it breaks, in the code too."""

from __future__ import annotations

import casadi as cs

from armctl.controllers.osc.kkt_code import kkt_verdict
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


#: the primal-dual active-set iterations written out in the code
ACTIVE_SET_ITERATIONS = 2


def next_active_set(
    upper: list[cs.SX], lower: list[cs.SX], s: cs.SX, z: cs.SX, lo: cs.SX, up: cs.SX, dual_tol: cs.SX
) -> tuple[list[cs.SX], list[cs.SX]]:
    """The next primal-dual active set (Hintermüller, Ito & Kunisch): the rows at their upper (lower) bound whose
    multiplier z has its sign (z ≥ −tol, z ≤ tol) and that the point s = C y does not leave the other way, and the
    rows that s breaks by more than PRIMAL_TOL. ``upper`` and ``lower`` are the rows' flags (SX 0/1) at each
    bound."""
    mi = len(upper)
    keep_up = [cs.logic_and(upper[i], cs.ge(z[i], -dual_tol)) for i in range(mi)]
    keep_lo = [cs.logic_and(lower[i], cs.le(z[i], dual_tol)) for i in range(mi)]
    over = [cs.gt(s[i], up[i] + PRIMAL_TOL) for i in range(mi)]
    under = [cs.lt(s[i], lo[i] - PRIMAL_TOL) for i in range(mi)]
    upper = [cs.logic_or(over[i], cs.logic_and(keep_up[i], cs.logic_not(under[i]))) for i in range(mi)]
    lower = [cs.logic_and(cs.logic_or(under[i], keep_lo[i]), cs.logic_not(upper[i])) for i in range(mi)]
    return upper, lower


def active_set_optimum(
    hess: cs.SX, grad: cs.SX, a: cs.SX, b: cs.SX, c: cs.SX, lo: cs.SX, up: cs.SX, start: cs.SX, in_scale: cs.SX
) -> list[cs.SX]:
    """(verdict, y, λ, z, active) of min ½yᵀHy + gᵀy s.t. A y = b, l ≤ C y ≤ u, from
    :data:`ACTIVE_SET_ITERATIONS` primal-dual active-set steps (Hintermüller, Ito & Kunisch, SIAM J. Optim. 13,
    2002; :meth:`~armctl.controllers.osc.optimality.ActiveSets.following`, written out) from the rows that
    ``start`` (the optimum on A y = b alone) breaks. Each step solves with the active rows as equalities, by the
    Schur complement on H's Cholesky factor, the rows off the active set masked out (z = 0 there):

        (D N H⁻¹ Nᵀ D + I − D) [λ; z] = D (N y₀ − d),   y = y₀ − H⁻¹ Nᵀ [λ; z],   N = [A; C],  y₀ = −H⁻¹ g,

    D selecting A's rows and the active rows of C, d their right-hand sides; then keeps the active rows whose
    multiplier has its sign and adds the rows the point breaks. The verdict is
    :func:`~armctl.controllers.osc.kkt_code.kkt_verdict` of the last step's (y, λ, z) with the level in scale:
    1 only for the QP's optimum, whatever the iterations did (dependent active rows give NaN, which fails it)."""
    me, mi = a.shape[0], c.shape[0]
    low = cholesky_factor(hess)
    y0 = -cholesky_substitute(low, grad)
    rows = cs.vertcat(a, c)
    w = cholesky_substitute(low, rows.T)  # H⁻¹ Nᵀ
    k = rows @ w
    r0 = rows @ y0
    dual_tol = DUAL_TOL * (1 + _largest(grad))
    s = c @ start
    upper = [cs.gt(s[i], up[i]) for i in range(mi)]
    lower = [cs.lt(s[i], lo[i]) for i in range(mi)]
    y, mult = start, cs.SX.zeros(me + mi)
    for _ in range(ACTIVE_SET_ITERATIONS):
        on = [cs.SX(1)] * me + [cs.logic_or(upper[i], lower[i]) for i in range(mi)]
        schur = cs.SX.zeros(me + mi, me + mi)
        rhs = cs.SX.zeros(me + mi)
        for i in range(me + mi):
            for j in range(me + mi):
                schur[i, j] = cs.if_else(cs.logic_and(on[i], on[j]), k[i, j], 1.0 if i == j else 0.0)
            if i < me:
                rhs[i] = r0[i] - b[i]
            else:
                m = i - me
                bound = cs.if_else(upper[m], up[m], lo[m])
                rhs[i] = cs.if_else(on[i], r0[i] - bound, 0.0)  # a branch: an infinite bound off D never enters
        mult = cholesky_solve(schur, rhs)
        y = y0 - w @ mult
        s = c @ y
        z = mult[me:]
        upper, lower = next_active_set(upper, lower, s, z, lo, up, dual_tol)
    lam, z = mult[:me], mult[me:]
    ok = cs.logic_and(in_scale, kkt_verdict(hess, grad, a, b, c, lo, up, y, lam, z))
    active = cs.vertcat(*[cs.if_else(cs.gt(z[i], 0), 1.0, cs.if_else(cs.lt(z[i], 0), -1.0, 0.0)) for i in range(mi)])
    return [ok, y, lam, z, active]


def _largest(v: cs.SX) -> cs.SX:
    """max_i |v_i| (NaN entries skipped: a NaN elsewhere fails the verdict anyway)."""
    out = cs.SX(0)
    for i in range(v.shape[0]):
        out = cs.fmax(out, cs.fabs(v[i]))
    return out
