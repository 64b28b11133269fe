"""The optimality check compiled (``CompiledKKT``) judges as ``kkt_ok`` does: on random QPs, at their optimum
from an independent solver (quadprog) and at candidates made to violate one condition by a known margin on either
side of its tolerance."""

from __future__ import annotations

import pickle
from dataclasses import replace

import numpy as np
import pytest

import armctl
from armctl.controllers.osc import QPArrays
from armctl.controllers.osc.kkt_code import CompiledKKT
from armctl.controllers.osc.optimality import DUAL_TOL, PRIMAL_TOL, kkt_ok, solve_on_active_set

from .helpers import quadprog_solvers

qpsolvers = quadprog_solvers()
if armctl.codegen.compiler() is None:  # pragma: no cover - the machines that run the tests have one
    pytest.skip("no C compiler: the check is not compiled", allow_module_level=True)

SIZES = [(6, 2, 5), (5, 0, 4), (4, 3, 0), (3, 0, 0)]


def _qp(rng: np.random.Generator, nx: int, me: int, mi: int) -> QPArrays:
    """A feasible QP whose unconstrained minimum breaks some of its rows; one lower bound infinite."""
    m = rng.normal(size=(nx, nx))
    H = m @ m.T + nx * np.eye(nx)
    g = rng.normal(size=nx) * 10.0
    x0 = rng.normal(size=nx) * 0.1  # a feasible point: every row holds there with some room
    A = rng.normal(size=(me, nx))
    b = A.dot(x0)
    C = rng.normal(size=(mi, nx))
    s0 = C.dot(x0)
    lo, up = s0 - np.abs(rng.normal(size=mi)) * 0.5 - 0.01, s0 + np.abs(rng.normal(size=mi)) * 0.5 + 0.01
    if mi:
        lo[0] = -np.inf
    return QPArrays(H, g, A, b, C, lo, up)


def _optimum(qp: QPArrays) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, y, z) at quadprog's optimum, the multipliers from the exact solve on its active set."""
    nx, me, mi = qp.nx, qp.me, qp.mi
    G = np.vstack([qp.C, -qp.C]) if mi else None
    h = np.concatenate([qp.u, -qp.l]) if mi else None
    if G is not None:
        keep = np.isfinite(h)
        G, h = G[keep], h[keep]
    p = qpsolvers.Problem(qp.H, qp.g, G, h, qp.A if me else None, qp.b if me else None)
    sol = qpsolvers.solve_problem(p, "quadprog")
    assert sol.found
    s = qp.C.dot(sol.x)
    active = np.zeros(mi, dtype=np.int8)
    active[np.abs(s - qp.u) < 1e-9] = 1
    active[np.abs(s - qp.l) < 1e-9] = -1
    exact = solve_on_active_set(qp, active)
    assert exact is not None and np.abs(exact[0] - sol.x).max() < 1e-8
    assert nx == exact[0].shape[0]
    return exact


def _candidates(
    qp: QPArrays, x: np.ndarray, y: np.ndarray, z: np.ndarray
) -> list[tuple[str, QPArrays, tuple, bool | None]]:
    """(what, the QP, (x, y, z), the verdict it must get, or None where only the agreement is asserted): the
    optimum, and one condition at a time broken by half or k times its tolerance (the QP's g or bounds moved so
    that the others still hold exactly as at the optimum)."""
    out: list[tuple[str, QPArrays, tuple, bool | None]] = [
        ("optimum", qp, (x, y, z), True),
        ("no multipliers", qp, (x, None, None), None),
    ]
    gmax = int(np.argmax(np.abs(qp.g)))
    j = (gmax + 1) % qp.nx  # an entry of g other than its largest: the tolerance 1 + ‖g‖∞ stays as it is
    bound = DUAL_TOL * (1.0 + np.abs(qp.g).max())
    for k in (0.5, 2.0):
        g = qp.g.copy()
        g[j] += k * bound
        if j != gmax:
            out.append((f"stationarity x{k}", replace(qp, g=g), (x, y, z), k < 1.0))
    s = qp.C.dot(x)
    free = np.flatnonzero((z == 0.0) & np.isfinite(qp.u))
    if free.size:
        i = free[-1]
        for k in (0.5, 3.0):  # row i's upper bound moved below C_i x
            u = qp.u.copy()
            u[i] = s[i] - k * PRIMAL_TOL
            out.append((f"row violated x{k}", replace(qp, u=u), (x, y, z), k < 1.0))
        room = qp.u[i] - s[i]  # > 0: a multiplier there, stationarity kept by g, gives a gap of zi · room
        for k in (0.5, 2.0):
            zi = z.copy()
            zi[i] = k * bound / room
            # (g moves by ~1e-8: its tolerance 1 + ‖g‖∞ by a relative 1e-9, far inside the factor k)
            out.append((f"gap x{k}", replace(qp, g=qp.g - qp.C[i] * zi[i]), (x, y, zi), k < 1.0))
            zw = z.copy()
            zw[i] = -k * bound / room  # the wrong sign: a lower bound it is far from
            g = qp.g - qp.C[i] * zw[i]
            out.append((f"wrong sign x{k}", replace(qp, g=g), (x, y, zw), None))
    if qp.mi:
        zi = z.copy()
        zi[0] = -1.0  # a multiplier towards the row's infinite lower bound
        out.append(
            ("multiplier towards an infinite bound", replace(qp, g=qp.g - qp.C[0] * (zi[0] - z[0])), (x, y, zi), False)
        )
    xn = x.copy()
    xn[-1] = np.nan
    out.append(("NaN in x", qp, (xn, y, z), False))
    xi = x.copy()
    xi[0] = np.inf
    out.append(("inf in x", qp, (xi, y, z), False))
    return out


@pytest.mark.parametrize("sizes", SIZES)
def test_the_compiled_check_judges_as_kkt_ok(sizes: tuple[int, int, int]) -> None:
    """20 random QPs of each size: at the optimum both accept; at each candidate both give the same verdict, and
    the one stated where the margin makes it plain (half or twice a tolerance)."""
    check = CompiledKKT()
    check.prepare(sizes)
    rng = np.random.default_rng(sum(sizes))
    judged = 0
    for _ in range(20):
        qp = _qp(rng, *sizes)
        x, y, z = _optimum(qp)
        for what, case, cand, expected in _candidates(qp, x, y, z):
            verdict = check(case, *cand)
            assert verdict == kkt_ok(case, *cand), what
            if expected is not None:
                assert verdict == expected, what
            judged += 1
    assert judged >= 60


def test_other_sizes_and_a_pickled_copy_take_the_same_check() -> None:
    """A size not prepared is checked by kkt_ok itself; a pickled check keeps its compiled sizes."""
    check = CompiledKKT()
    check.prepare((5, 0, 4))
    rng = np.random.default_rng(3)
    qp = _qp(rng, 4, 1, 2)  # not prepared
    x, y, z = _optimum(qp)
    assert check(qp, x, y, z) and check.sizes == [(5, 0, 4)]
    copy = pickle.loads(pickle.dumps(check))
    assert copy.sizes == [(5, 0, 4)]
    qp5 = _qp(rng, 5, 0, 4)
    x5, y5, z5 = _optimum(qp5)
    assert copy(qp5, x5, y5, z5) and not copy(qp5, x5 + 1e-3, y5, z5)
