"""The optimality check of :func:`~armctl.controllers.osc.optimality.kkt_ok` as generated C code, for the QPs of
given sizes: the same conditions at the same tolerances, with the arrays read in one call instead of a dozen
NumPy calls and a loop over the rows in Python.

For min ½ xᵀH x + gᵀx s.t. A x = b, l ≤ C x ≤ u and a candidate (x, y, z), the code returns 1 exactly when

* every entry of x is finite,
* |(A x − b)_i| ≤ PRIMAL_TOL for every equality row and l_i − PRIMAL_TOL ≤ (C x)_i ≤ u_i + PRIMAL_TOL for every
  inequality row (an infinite bound always holds),
* every entry of r = H x + g + Aᵀy + Cᵀz is finite with |r_i| ≤ DUAL_TOL (1 + ‖g‖∞) (stationarity),
* the duality gap Σ_{z_i > 0} z_i |u_i − (C x)_i| + Σ_{z_i < 0} (−z_i) |(C x)_i − l_i| is ≤ DUAL_TOL (1 + ‖g‖∞)
  (dual feasibility and complementarity: a multiplier of the wrong sign, or on a row away from its bound, makes
  it positive; one on an infinite bound makes it infinite),

else 0 (a NaN fails every comparison). The sums are taken in another order than NumPy's, so that a candidate
within a rounding error (~1e-16 relative) of a tolerance can be judged differently: never one that violates a
condition by more. A multiplier vector left out (None) counts as zeros, as in ``kkt_ok``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from armctl._checks import FloatArray
from armctl.codegen import Fallback
from armctl.controllers.osc.optimality import DUAL_TOL, PRIMAL_TOL, kkt_ok
from armctl.controllers.osc.problem import QPArrays
from armctl.dynamics.casadi_buffer import buffer_of, view

if TYPE_CHECKING:
    import casadi as cs

_CODE_VERSION = 2
_NAME = "osc_kkt_check"
_HUGE = 1.7976931348623157e308  # the largest float: |v| ≤ it exactly when v is finite
Sizes = tuple[int, int, int]
#: what ``compile="auto"`` runs where the check cannot be built
FALLBACK = Fallback("the QP's compiled optimality check", "the same check in NumPy", "a few µs slower a QP")


def kkt_verdict(H: Any, g: Any, A: Any, b: Any, C: Any, lo: Any, up: Any, x: Any, y: Any, z: Any) -> Any:
    """The check of the module as a CasADi SX expression (1 or 0) of the QP's SX arrays and the candidate
    (A, b, y may be None: no equality row)."""
    import casadi as cs  # imported on use: a controller without generated code never needs it

    nx, mi = x.shape[0], lo.shape[0]
    ok = cs.SX(1)
    for i in range(nx):
        ok = cs.logic_and(ok, cs.le(cs.fabs(x[i]), _HUGE))
    r = H @ x + g
    if A is not None and A.shape[0]:
        r += A.T @ y
        e = A @ x - b
        for i in range(A.shape[0]):
            ok = cs.logic_and(ok, cs.logic_and(cs.le(e[i], PRIMAL_TOL), cs.ge(e[i], -PRIMAL_TOL)))
    gap = cs.SX(0)
    if mi:
        r += C.T @ z
        s = C @ x
        for i in range(mi):
            ok = cs.logic_and(ok, cs.logic_and(cs.le(lo[i] - PRIMAL_TOL, s[i]), cs.le(s[i], up[i] + PRIMAL_TOL)))
            upper = cs.if_else(cs.gt(z[i], 0), z[i] * cs.fabs(up[i] - s[i]), 0)  # a branch: 0 · ∞ never formed
            lower = cs.if_else(cs.lt(z[i], 0), -z[i] * cs.fabs(s[i] - lo[i]), 0)
            gap += upper + lower
    scale = cs.SX(0)
    for i in range(nx):
        scale = cs.fmax(scale, cs.fabs(g[i]))
    bound = DUAL_TOL * (1 + scale)
    for i in range(nx):
        ok = cs.logic_and(ok, cs.le(cs.fabs(r[i]), bound))
    return cs.logic_and(ok, cs.le(gap, bound))


def kkt_function(nx: int, me: int, mi: int) -> cs.Function:
    """The CasADi function ``f(data) -> ok`` of the module for QPs of ``nx`` variables, ``me`` equality and ``mi``
    inequality rows; ``data`` = [H (row by row); g; A (row by row); b; C (row by row); l; u; x; y; z]."""
    import casadi as cs  # imported on use: a controller without generated code never needs it

    data = cs.SX.sym("data", nx * nx + nx + me * nx + me + mi * nx + 2 * mi + nx + me + mi)
    pos = 0

    def take(rows: int, cols: int = 1) -> cs.SX:
        nonlocal pos
        block = data[pos : pos + rows * cols]
        pos += rows * cols
        return cs.reshape(block, cols, rows).T if cols > 1 else block  # row by row in

    H, g, A, b, C, lo, up = take(nx, nx), take(nx), take(me, nx), take(me), take(mi, nx), take(mi), take(mi)
    x, y, z = take(nx), take(me), take(mi)
    return cs.Function(_NAME, [data], [kkt_verdict(H, g, A, b, C, lo, up, x, y, z)])


class _Check:
    """The compiled function of one size, bound to an input buffer and an output of its own."""

    def __init__(self, sizes: Sizes, cache_dir: Any) -> None:
        from armctl.codegen import library as codegen  # CasADi, imported on use

        nx, me, mi = sizes
        tag = f"osc-kkt|v{_CODE_VERSION}|{nx}|{me}|{mi}|{PRIMAL_TOL!r}|{DUAL_TOL!r}"
        what = f"the optimality check of QPs of {nx} variables, {me} equality and {mi} inequality rows"
        fn = codegen.cached([_NAME], tag, lambda: [kkt_function(nx, me, mi)], cache_dir, what=what)[_NAME]
        self.data = np.zeros(fn.size1_in(0))
        self.ok = np.zeros(1)
        buf, self.run = buffer_of(fn)
        buf.set_arg(0, view(self.data))
        buf.set_res(0, view(self.ok))
        self._bound = buf  # reads data and writes ok: kept with them
        self.zeros_y, self.zeros_z = np.zeros(me), np.zeros(mi)


class CompiledKKT:
    """:func:`~armctl.controllers.osc.optimality.kkt_ok` as generated C code (module docstring) for the sizes
    :meth:`prepare` was given; ``kkt_ok`` itself for any other size.

    Parameters
    ----------
    cache_dir : str, path or None, optional
        Where the compiled code is kept (None: the default cache).
    """

    def __init__(self, cache_dir: Any = None) -> None:
        self.cache_dir = cache_dir
        self._checks: dict[Sizes, _Check] = {}

    def __reduce__(self) -> tuple[Any, ...]:
        # rebuilt (the libraries load from the cache): the buffers are this process's
        return (_rebuilt, (self.cache_dir, list(self._checks)))

    @property
    def sizes(self) -> list[Sizes]:
        """The sizes (variables, equality rows, inequality rows) checked by compiled code."""
        return list(self._checks)

    def prepare(self, sizes: Sizes) -> None:
        """Build (or load from the cache) the code for QPs of ``sizes`` = (variables, equality rows, inequality
        rows).

        Raises
        ------
        BackendError
            No C compiler, or one that fails.
        """
        if sizes not in self._checks:
            self._checks[sizes] = _Check(sizes, self.cache_dir)

    def __call__(self, qp: QPArrays, x: FloatArray, y: FloatArray | None, z: FloatArray | None) -> bool:
        """Whether (x, y, z) passes the check of ``kkt_ok(qp, x, y, z)`` (None: zero multipliers)."""
        check = self._checks.get((qp.g.shape[0], qp.b.shape[0], qp.l.shape[0]))
        if check is None or x.shape != qp.g.shape:
            return kkt_ok(qp, x, y, z)
        np.concatenate(
            (
                qp.H.ravel(),
                qp.g,
                qp.A.ravel(),
                qp.b,
                qp.C.ravel(),
                qp.l,
                qp.u,
                x,
                check.zeros_y if y is None else y,
                check.zeros_z if z is None else z,
            ),
            out=check.data,
        )
        check.run()
        return bool(check.ok[0] == 1.0)


def _rebuilt(cache_dir: Any, sizes: list[Sizes]) -> CompiledKKT:
    out = CompiledKKT(cache_dir)
    for s in sizes:
        out.prepare(s)
    return out
