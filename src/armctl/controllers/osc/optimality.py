"""Optimality of a QP solution: the KKT conditions, checked, and the exact solution on a given active set.

For the QP  min ½ xᵀH x + gᵀx  s.t.  A x = b,  l ≤ C x ≤ u  (H positive definite), a point x with multipliers
(y, z) is the optimum if and only if (Karush–Kuhn–Tucker)

* stationarity:             H x + g + Aᵀy + Cᵀz = 0
* primal feasibility:       A x = b,  l ≤ C x ≤ u
* dual feasibility:         z_i ≥ 0 where only the upper bound may bind, z_i ≤ 0 where only the lower one may
* complementarity:          z_i > 0 ⇒ (C x)_i = u_i,  z_i < 0 ⇒ (C x)_i = l_i

Dual feasibility and complementarity together are a zero duality gap,

    gap = Σ_i z_i⁺ (u_i − (C x)_i) + z_i⁻ ((C x)_i − l_i)     (z⁺ = max(z, 0), z⁻ = max(−z, 0))

which is what an iterative solver's early stop can leave large while its residuals are small (multipliers on
bounds that are not active: the primal point is then not the optimum).

:func:`residuals` measures all three for any (x, y, z); :func:`solve_on_active_set` gives the exact solution
once the active set is known — the rows taken as equalities — by one direct solve of the KKT system

    [H  Nᵀ] [x]   [−g]
    [N  0 ] [λ] = [ d]         N = [A; C_act],  d = [b; the active rows' bounds]

and :func:`accept` checks it: its stationarity and its active rows hold to the backward error of that solve
(a backward-stable LU or Cholesky factorisation, whose failure is reported), every other row of l ≤ C x ≤ u is
checked to :data:`PRIMAL_TOL`, every multiplier's sign to :data:`DUAL_TOL` (relative), and the gap is zero by
construction (z vanishes off the active set). A candidate that passes is the QP's optimum to those tolerances
— whatever solver proposed its active set. When no active set a solver points at passes, the solver's own
(x, y, z) may still be accepted, if :func:`residuals` finds its primal residual, stationarity residual and
duality gap all within :data:`KKT_TOL` (1e-6, the solvers' own tolerance; the last two relative to
1 + ‖g‖∞).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.linalg import lapack

from armctl._checks import FloatArray
from armctl.controllers.osc.problem import QPArrays

#: largest violation of a row accepted, in the row's own units (N·m for torque rows and the equation of
#: motion, rad/s² for acceleration bounds, N for force rows)
PRIMAL_TOL = 1e-8
#: largest multiplier of the wrong sign accepted, relative to 1 + ‖g‖∞ (the cost's gradient at x = 0)
DUAL_TOL = 1e-8
#: the tolerance of :meth:`Residuals.ok` for a solver's own point: primal residual (row units), stationarity
#: residual and duality gap (relative to 1 + ‖g‖∞)
KKT_TOL = 1e-6

_BIG = 1e300  # stands for an infinite slack in the gap (0 · ∞ would be NaN)


@dataclass(frozen=True, slots=True)
class Residuals:
    """The KKT residuals of (x, y, z): ``primal`` (largest row violation, row units), ``dual`` (‖H x + g + Aᵀy +
    Cᵀz‖∞) and ``gap`` (the duality gap above), the last two in the cost's units; ``scale`` = 1 + ‖g‖∞."""

    primal: float
    dual: float
    gap: float
    scale: float

    def ok(self, primal_tol: float = KKT_TOL, dual_tol: float = KKT_TOL) -> bool:
        """All three within tolerance: primal ≤ primal_tol, dual and gap ≤ dual_tol · scale."""
        return self.primal <= primal_tol and self.dual <= dual_tol * self.scale and self.gap <= dual_tol * self.scale


def residuals(qp: QPArrays, x: FloatArray, y: FloatArray | None, z: FloatArray | None) -> Residuals:
    """The KKT residuals of the QP ``qp`` at (x, y, z) (None: zero multipliers)."""
    r = qp.H.dot(x) + qp.g
    primal = 0.0
    if qp.b.shape[0]:
        if y is not None:
            r += qp.A.T.dot(y)
        primal = float(np.abs(qp.A.dot(x) - qp.b).max())
    gap = 0.0
    if qp.l.shape[0]:
        s = qp.C.dot(x)
        du, dl = qp.u - s, s - qp.l
        primal = max(primal, float(-du.min()), float(-dl.min()), 0.0)
        if z is not None:
            r += qp.C.T.dot(z)
            zp, zm = np.maximum(z, 0.0), np.maximum(-z, 0.0)
            gap = float(zp.dot(np.fmin(np.abs(du), _BIG)) + zm.dot(np.fmin(np.abs(dl), _BIG)))
    return Residuals(primal, float(np.abs(r).max()), gap, 1.0 + float(np.abs(qp.g).max()))


def kkt_ok(
    qp: QPArrays,
    x: FloatArray,
    y: FloatArray | None,
    z: FloatArray | None,
    primal_tol: float = PRIMAL_TOL,
    dual_tol: float = DUAL_TOL,
) -> bool:
    """``residuals(qp, x, y, z).ok(primal_tol, dual_tol)`` — the same three conditions (primal residual,
    stationarity residual and duality gap within tolerance), with the row tests on Python floats. The stated
    default tolerances are those of an exact solve on an active set: :data:`PRIMAL_TOL` and :data:`DUAL_TOL`
    (relative to 1 + ‖g‖∞)."""
    if not math.isfinite(sum(x.tolist())):
        return False
    gl = qp.g.tolist()
    bound = dual_tol * (1.0 + max(max(gl), -min(gl))) if gl else dual_tol
    r = qp.H.dot(x)
    r += qp.g
    if qp.b.shape[0]:
        if y is not None:
            r += y.dot(qp.A)  # Aᵀy
        e = qp.A.dot(x)
        e -= qp.b
        el = e.tolist()
        if not (max(el) <= primal_tol and min(el) >= -primal_tol):
            return False
    gap = 0.0
    mi = qp.l.shape[0]
    if mi:
        C = qp.C
        if z is not None:
            r += z.dot(C)  # Cᵀz
        zl = z.tolist() if z is not None else [0.0] * mi
        for si, zi, li, ui in zip(C.dot(x).tolist(), zl, qp.l.tolist(), qp.u.tolist(), strict=True):
            if not li - primal_tol <= si <= ui + primal_tol:
                return False
            if zi > 0.0:
                gap += zi * abs(ui - si)
            elif zi < 0.0:
                gap -= zi * abs(si - li)
    rl = r.tolist()
    return math.isfinite(sum(rl)) and max(rl) <= bound and min(rl) >= -bound and gap <= bound


def verified(
    qp: QPArrays,
    x: FloatArray,
    y: FloatArray | None,
    z: FloatArray | None,
    check: Callable[[QPArrays, FloatArray, FloatArray | None, FloatArray | None], bool] | None = None,
) -> bool:
    """Whether (x, y, z) passes the check a control step accepts a solution on: :func:`kkt_ok` at the tolerances
    of an exact solve (:data:`PRIMAL_TOL`, :data:`DUAL_TOL`; or ``check``, the same conditions compiled), or, for
    a solver's own point, :func:`residuals` within :data:`KKT_TOL`."""
    return (kkt_ok if check is None else check)(qp, x, y, z) or residuals(qp, x, y, z).ok()


def equality_optimum_ok(qp: QPArrays, x: FloatArray, y: FloatArray, eq_res: FloatArray, stat: FloatArray) -> bool:
    """Whether (x, y), the optimum on the equality rows alone (no inequality row active, z = 0) with its
    residuals ``eq_res`` = A x − b and ``stat`` = H x + g + Aᵀy, is the optimum of ``qp``: the residuals within
    :data:`PRIMAL_TOL` and :data:`DUAL_TOL` (1 + ‖g‖∞) and every inequality row within its bounds exactly (no
    multiplier, no gap: the KKT conditions); False for NaN."""
    if not float(np.abs(eq_res).max(initial=0.0)) <= PRIMAL_TOL:  # (no equality row: none violated)
        return False
    if not float(np.abs(stat).max()) <= DUAL_TOL * (1.0 + float(np.abs(qp.g).max())):
        return False
    s = qp.C.dot(x)
    return bool((s >= qp.l).all() and (s <= qp.u).all())


def solve_on_active_set(qp: QPArrays, active: np.ndarray) -> tuple[FloatArray, FloatArray, FloatArray] | None:
    """(x, y, z) of the QP with the rows ``active`` as equalities (``active``: int8 per row of C, +1 at its
    upper bound, −1 at its lower, 0 free), by one direct solve of the KKT system (LU; if active rows depend on
    each other or on A, the least-squares solution with the smallest multipliers); None if the rows
    contradict each other."""
    n, me, mi = qp.g.shape[0], qp.b.shape[0], qp.l.shape[0]
    idx = np.flatnonzero(active)
    if me == 0 and idx.size == 0:  # the unconstrained minimum: Cholesky of H
        _, x, info = lapack.dposv(qp.H, qp.g)
        if info != 0:
            return None
        np.negative(x, out=x)
        return x, np.zeros(0), np.zeros(mi)
    k = me + idx.size
    K = np.zeros((n + k, n + k))
    K[:n, :n] = qp.H
    N = K[n:, :n]
    N[:me] = qp.A
    N[me:] = qp.C[idx]
    K[:n, n:] = N.T
    rhs = np.empty(n + k)
    np.negative(qp.g, out=rhs[:n])
    rhs[n : n + me] = qp.b
    rhs[n + me :] = np.where(active[idx] > 0, qp.u[idx], qp.l[idx])
    _, _, sol, info = lapack.dgesv(K, rhs)
    if info != 0:  # dependent active rows (a degenerate optimum): x is still unique, the multipliers are not
        sol = np.linalg.lstsq(K, rhs, rcond=None)[0]
        if np.abs(K.dot(sol) - rhs).max() > 1e-9 * (1.0 + float(np.abs(rhs).max())):
            return None
    z = np.zeros(mi)
    z[idx] = sol[n + me :]
    return sol[:n], sol[n : n + me], z


def accept(qp: QPArrays, x: FloatArray, z: FloatArray, active: np.ndarray) -> bool:
    """Whether (x, z) from :func:`solve_on_active_set` with ``active`` is the optimum (module docstring):
    every row within its bounds to :data:`PRIMAL_TOL` and every active row's multiplier of the right sign to
    :data:`DUAL_TOL` · (1 + ‖g‖∞)."""
    return ActiveSets(qp).following(x, z, active) is None


class ActiveSets:
    """Exact solves of one QP on active sets, and their check, with what they share computed once: the check's
    tolerances, and without equality rows H's Cholesky factor and the unconstrained minimum x₀ = −H⁻¹g, from
    which a solve on k active rows N is a k×k one (Schur complement):

        (N H⁻¹ Nᵀ) z_act = N x₀ − d,   x = x₀ − H⁻¹ Nᵀ z_act."""

    def __init__(self, qp: QPArrays, unconstrained: tuple[FloatArray, FloatArray] | None = None) -> None:
        """``unconstrained``: (H's upper Cholesky factor, x₀) if the caller has them (LAPACK's ``dposv``)."""
        self.qp = qp
        self.dual_tol = DUAL_TOL * (1.0 + float(np.abs(qp.g).max()))
        self.upper, self.lower = qp.u + PRIMAL_TOL, qp.l - PRIMAL_TOL
        # False: not computed yet
        self._factor: tuple[FloatArray, FloatArray] | bool | None = False if unconstrained is None else unconstrained

    def _unconstrained(self) -> tuple[FloatArray, FloatArray] | None:
        """(Cholesky factor of H, x₀), or None with equality rows or an H that is not positive definite."""
        if self._factor is False:
            qp = self.qp
            self._factor = None
            if not qp.b.shape[0]:
                c, info = lapack.dpotrf(qp.H, lower=0, clean=1)
                if info == 0:
                    x0, info = lapack.dpotrs(c, qp.g)
                    if info == 0:
                        np.negative(x0, out=x0)
                        self._factor = (c, x0)
        return self._factor  # type: ignore[return-value]  # set above when it was None

    def solve(self, active: np.ndarray) -> tuple[FloatArray, FloatArray, FloatArray] | None:
        """:func:`solve_on_active_set`, by the Schur complement where there are no equality rows."""
        un = self._unconstrained()
        if un is None:
            return solve_on_active_set(self.qp, active)
        c, x0 = un
        qp = self.qp
        idx = np.flatnonzero(active)
        z = np.zeros(qp.l.shape[0])
        if not idx.size:
            return x0.copy(), np.zeros(0), z
        N = qp.C[idx]
        W, info = lapack.dpotrs(c, N.T)  # H⁻¹ Nᵀ
        r = N.dot(x0)
        r -= np.where(active[idx] > 0, qp.u[idx], qp.l[idx])
        _, za, info = lapack.dposv(N.dot(W), r)
        if info != 0:  # dependent active rows: the general solve (least squares)
            return solve_on_active_set(self.qp, active)
        z[idx] = za
        return x0 - W.dot(za), np.zeros(0), z

    def following(self, x: FloatArray, z: FloatArray, active: np.ndarray) -> np.ndarray | None:
        """None if (x, z) from :meth:`solve` with ``active`` passes the check (:func:`accept`); else the active set
        of a primal-dual active-set step (Hintermüller, Ito & Kunisch, SIAM J. Optim. 13, 2002): the active rows
        whose multiplier has its sign, and the rows that x violates, at the bound they violate."""
        C = self.qp.C
        if not C.shape[0]:
            return None
        s = C.dot(x)
        over, under = s > self.upper, s < self.lower
        wrong = z * active < -self.dual_tol  # an active row's multiplier of the wrong sign
        if not (over | under | wrong).any():
            return None
        new = np.where(wrong, 0, active).astype(np.int8)
        new[over] = 1
        new[under] = -1
        return new


def active_set_of(qp: QPArrays, x: FloatArray, z: FloatArray | None, tol: float = 1e-6) -> np.ndarray:
    """The active set a solver's (x, z) points at: with multipliers, the rows whose multiplier is above ``tol``
    (1 + ‖g‖∞) with a bound on its side (a solver stopped early can leave the row short of its bound); without,
    the rows within ``tol`` (1 + |bound|) of a bound. The exact solve then decides: a row taken active wrongly
    comes out with a multiplier of the wrong sign, a row left out beyond its bound, and the check refuses it."""
    lo, up = qp.l, qp.u
    active = np.zeros(lo.shape[0], dtype=np.int8)
    if z is not None:
        big = tol * (1.0 + float(np.abs(qp.g).max()))
        active[(z > big) & np.isfinite(up)] = 1
        active[(z < -big) & np.isfinite(lo)] = -1
        return active
    s = qp.C.dot(x)
    with np.errstate(invalid="ignore"):  # (an infinite bound is never near)
        near_u = ((up - s) <= tol * (1.0 + np.abs(up))) & np.isfinite(up)
        near_l = ((s - lo) <= tol * (1.0 + np.abs(lo))) & np.isfinite(lo)
    active[near_u] = 1
    active[near_l & ~near_u] = -1
    return active
