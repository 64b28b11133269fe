"""`GeneratedCascade`: two priority levels of a contact step (:mod:`~armctl.controllers.osc.contact_qp`) solved
by generated C code when no inequality row is active at either level — the usual case in contact.

After the generated contact data (:mod:`~armctl.controllers.osc.generated_contact`) has given B = [M | −J_cᵀ],
h', the contact rows A y = b, the task rows and each level's H_k, g_k, one more call of code generated with CasADi
for the layout's sizes computes, from those outputs and the limits' bounds l, u:

* level 0's optimum on the contact rows alone, y₀ (:func:`~armctl.controllers.osc.generated_optimum.equality_optimum`);
* the basis of the rows that keep level 0's optimum, as
  :func:`~armctl.controllers.osc.hierarchy.extend_basis` takes it when they are well conditioned: with T₀ level 0's
  weighted task rows (rows of zero weight left out) and L the Cholesky factor of T₀T₀ᵀ, F = L⁻¹T₀ (orthonormal
  rows); and φ = F y₀;
* level 1's optimum on [A; F] y = [b; φ] alone, y₁, by the same Schur complement;
* both verdicts of :func:`~armctl.controllers.osc.optimality.equality_optimum_ok` (the residuals within
  PRIMAL_TOL and DUAL_TOL (1 + ‖g_k‖∞), every inequality row of the level within its bounds exactly), and
  τ = B y₁ + h'.

A row of zero weight is zero in T₀: the code puts 1 on its diagonal in T₀T₀ᵀ and in the Schur complement, which
leaves it out exactly (its row of F and its multiplier are zero). The code takes F only where
:func:`extend_basis` takes that basis too: its rank test (every kept row's squared norm above (10⁻⁹ max|T₀|)²),
and the reciprocal condition number of G = T₀T₀ᵀ (1-norm, its kept rows), 1 / (‖G‖₁ ‖G⁻¹‖₁), computed exactly
from the inverse, above :data:`~armctl.controllers.osc.hierarchy.WELL_CONDITIONED` by a relative margin of 10⁻⁶:
LAPACK's estimate that :func:`extend_basis` reads (``dpocon``) bounds ‖G⁻¹‖₁ from below (to rounding, far
inside the margin), so its figure is then above the threshold too. Where any of this fails the step solves the
levels as before (the solver chain, and :func:`extend_basis` itself); where it holds, the step's τ is that of the
verified optimum of both levels, the same QPs as the chain's, and its frozen rows are the chain path's F.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import casadi as cs
import numpy as np

from armctl._checks import FloatArray
from armctl.codegen import library as codegen
from armctl.controllers.osc.contact_public import ContactStep
from armctl.controllers.osc.generated_limits import limit_bounds, limit_params, limit_tag, supported_limits
from armctl.controllers.osc.generated_optimum import equality_optimum, verdict
from armctl.controllers.osc.hierarchy import WELL_CONDITIONED
from armctl.controllers.osc.limits.base import Limit
from armctl.controllers.osc.solve import QPSolution
from armctl.dynamics.casadi_buffer import buffer_of, view
from armctl.dynamics.recursive import cholesky_factor, cholesky_solve, cholesky_substitute

if TYPE_CHECKING:
    from armctl.controllers.osc.chain import SolverChain
    from armctl.controllers.osc.contact_qp import ContactQP
    from armctl.controllers.osc.generated_contact import GeneratedContactData

_CODE_VERSION = 3
_NAME = "osc_contact_cascade"
#: the rank test of extend_basis: a row is kept if its norm exceeds this times the largest entry of T₀
_RANK_TOL = 1e-9
#: the relative margin above WELL_CONDITIONED of the exact reciprocal condition number (module docstring)
_MARGIN = 1e-6


def cascade_function(
    n: int, ny: int, me: int, m: int, m0: int, tau_rows: Sequence[int], mi: int, limits: Sequence[Limit]
) -> cs.Function:
    """The CasADi function of the module for n joints, y of size ``ny``, ``me`` contact rows, ``m`` task rows of
    which level 0 has the first ``m0``, ``mi`` inequality rows (``limits``' rows, then the cones') of which
    ``tau_rows`` are torque rows: ``f(H0, g0, H1, g1, contact, rows, brows, c0, c1, q, qd, bounds, C, s0) ->
    (y0, λ0, y1, [λ1; φ], F, stats, τ, l, u)``, ``contact`` = [A | b], ``rows`` = the task rows [J | t] of all
    levels, ``brows`` = [B | −h'], c_k each level's scale, ``bounds`` the limits' parameters
    (:func:`~armctl.controllers.osc.generated_limits.limit_params`) and the cones' bounds, C the inequality rows
    on y (the torque rows' are B, given by ``brows``), s0 level 0's square-root weights; ``stats`` = [level 0's
    verdict, 1 if both levels' verdicts and the basis tests pass]; l, u the inequality rows' public bounds at (q,
    q̇)."""
    h0, h1 = cs.SX.sym("H0", ny, ny), cs.SX.sym("H1", ny, ny)
    g0, g1 = cs.SX.sym("g0", ny), cs.SX.sym("g1", ny)
    contact, rows, brows = cs.SX.sym("contact", me, ny + 1), cs.SX.sym("rows", m, ny + 1), cs.SX.sym("brows", n, ny + 1)
    c0, c1 = cs.SX.sym("c0"), cs.SX.sym("c1")
    q, qd = cs.SX.sym("q", n), cs.SX.sym("qd", n)
    lim_lo, lim_up, lim_p = limit_bounds(limits, n, q, qd)
    cone_lo, cone_up = cs.SX.sym("cone_lower", mi - lim_lo.shape[0]), cs.SX.sym("cone_upper", mi - lim_lo.shape[0])
    lower, upper = cs.vertcat(lim_lo, cone_lo), cs.vertcat(lim_up, cone_up)
    cmat, s0 = cs.SX.sym("C", mi, ny), cs.SX.sym("s0", m0)
    a, b = contact[:, :ny], contact[:, ny]
    bmat, hf = brows[:, :ny], -brows[:, ny]
    taus = set(tau_rows)
    # the inequality rows on y: B in the torque rows, their bounds shifted by −h' (as ContactQP.inequalities)
    crows = cs.vertcat(cs.SX(0, ny), *[bmat[i % n, :] if i in taus else cmat[i, :] for i in range(mi)])
    shift = cs.vertcat(*[hf[i % n] if i in taus else 0.0 for i in range(mi)])
    ly, uy = lower - shift, upper - shift
    if me:
        opt0 = equality_optimum(h0, g0, a, b)
    else:  # no contact: level 0's unconstrained minimum, its residuals (none on no row: 0)
        y00 = -cholesky_solve(h0, g0)
        opt0 = [y00, cs.SX.zeros(0), cs.SX.zeros(1), h0 @ y00 + g0]
    ok0 = verdict(opt0, g0, c0, crows @ opt0[0], ly, uy)
    # level 0's weighted rows; a row of zero weight is left out by a 1 on its diagonal
    dropped = cs.vertcat(*[cs.if_else(s0[i] == 0, 1.0, 0.0) for i in range(m0)])
    t0 = cs.repmat(s0, 1, ny) * rows[:m0, :ny]
    gram0 = t0 @ t0.T
    low = cholesky_factor(gram0 + cs.diag(dropped))
    fbasis = _forward(low, t0)  # L⁻¹T₀
    phi = fbasis @ opt0[0]
    nrows = cs.vertcat(a, fbasis)
    rhs = cs.vertcat(b, phi)
    fac = cholesky_factor(h1)
    y0 = -cholesky_substitute(fac, g1)
    w = cholesky_substitute(fac, nrows.T)
    schur = nrows @ w + cs.diag(cs.vertcat(cs.SX.zeros(me), dropped))
    lam = cholesky_solve(schur, nrows @ y0 - rhs)
    y1 = y0 - w @ lam
    opt1 = [y1, lam, nrows @ y1 - rhs, h1 @ y1 + g1 + nrows.T @ lam]
    ok1 = verdict(opt1, g1, c1, crows @ y1, ly, uy)
    scale = cs.fmax(cs.mmax(cs.fabs(t0)), 1e-300)
    rank_ok = cs.SX(1.0)
    for i in range(m0):
        rank_ok = cs.logic_and(rank_ok, cs.logic_or(dropped[i] == 1, gram0[i, i] > (_RANK_TOL * scale) ** 2))
    # 1 / (‖G‖₁ ‖G⁻¹‖₁) of the kept rows (G + the 1s is block diagonal: the kept columns' sums are G⁻¹'s)
    kept = 1.0 - dropped
    inv_norm = cs.mmax(kept * cs.sum1(cs.fabs(cholesky_substitute(low, cs.SX.eye(m0)))).T)
    anorm = cs.mmax(cs.sum1(cs.fabs(gram0)))
    well = cs.logic_and(cs.sum1(kept) >= 1.0, anorm * inv_norm * (WELL_CONDITIONED * (1.0 + _MARGIN)) < 1.0)
    stats = cs.vertcat(ok0, cs.logic_and(cs.logic_and(ok0, ok1), cs.logic_and(rank_ok, well)))
    bparams = cs.vertcat(lim_p, cone_lo, cone_up)
    inputs = [h0, g0, h1, g1, contact, rows, brows, c0, c1, q, qd, bparams, cmat, s0]
    outputs = [opt0[0], opt0[1], y1, cs.vertcat(lam, phi), fbasis, stats, bmat @ y1 + hf]
    outputs += [lower, upper]
    return cs.Function(_NAME, inputs, [cs.densify(o) for o in outputs])


def _forward(low: list[list[Any]], b: cs.SX) -> cs.SX:
    """X = L⁻¹B by forward substitution, L of :func:`~armctl.dynamics.recursive.cholesky_factor`."""
    k = len(low)
    out: list[Any] = []
    for i in range(k):
        r = b[i, :]
        for p in range(i):
            r = r - low[i][p] * out[p]
        out.append(r / low[i][i])
    return cs.vertcat(*out)


def for_qp(qp: ContactQP, gen: GeneratedContactData) -> GeneratedCascade:
    """The :class:`GeneratedCascade` of the contact QPs ``qp`` and their generated data ``gen``."""
    tau_rows = [i for r in qp.tau_rows for i in range(r.start, r.stop)]
    cones = (qp.layout.cone_l, qp.layout.cone_u)
    return GeneratedCascade(gen, qp.layout.limits, cones, qp.C_template, tau_rows, qp.levels[0][0].m)


def applies(qp: ContactQP) -> bool:
    """Whether :class:`GeneratedCascade` takes the contact QPs ``qp``: two levels, and limits that
    :func:`~armctl.controllers.osc.generated_limits.limit_bounds` takes."""
    return len(qp.levels) == 2 and supported_limits(qp.layout.limits)


class GeneratedCascade:
    """The generated function of the module for the two levels of a layout's QPs on y = [q̈; f], reading the
    outputs of their generated data ``gen`` in place (bound once). :meth:`step` gives the step, or None where the
    code's verdict or the basis test refuses it. Made by :func:`for_qp`. Not thread-safe.

    Parameters
    ----------
    gen : GeneratedContactData
        The layout's generated data (its outputs are this function's inputs), for two levels.
    limits : sequence of Limit
        The layout's limits (bound), in its order.
    cones : (ndarray, ndarray)
        The bounds of the cones' rows, after the limits' rows.
    c_template : ndarray, shape (mi, ny)
        The inequality rows on y (the torque rows' are filled from B).
    tau_rows : sequence of int
        The torque limits' rows of ``c_template``.
    m0 : int
        Level 0's task rows.
    """

    def __init__(
        self,
        gen: GeneratedContactData,
        limits: Sequence[Limit],
        cones: tuple[FloatArray, FloatArray],
        c_template: FloatArray,
        tau_rows: Sequence[int],
        m0: int,
    ) -> None:
        self._args = (gen, tuple(limits), cones, c_template, tuple(tau_rows), m0)
        n = gen.n
        ny = gen.H[0].shape[0]
        me, m, mi = gen.contact.shape[0], gen.rows.shape[0], c_template.shape[0]
        self.m0 = m0
        tag = f"osc-contact-cascade|v{_CODE_VERSION}|{n},{ny},{me},{m},{m0},{mi}|tau:{','.join(map(str, tau_rows))}"
        tag += f"|limits:{limit_tag(limits)}"
        fn = codegen.cached(
            [_NAME],
            tag,
            lambda: [cascade_function(n, ny, me, m, m0, tau_rows, mi, limits)],
            gen.dynamics.options.get("cache_dir"),
            flags=codegen.CFLAGS_FAST,  # a control loop's hot path: a slower build for faster code
            what="the operational-space QP's two-level contact step",
        )[_NAME]
        self._bparams = np.concatenate((limit_params(limits), *cones))
        self._s0 = np.zeros(m0)
        self._cmat_t = np.ascontiguousarray(c_template.T)  # column by column: C held as its transpose
        buf, self._run = buffer_of(fn)
        # matrices in, column by column: each (r × c) input is the (c × r) array of its transpose, row by row
        args = [gen.H[0], gen.g[0], gen.H[1], gen.g[1], gen.contact.T, gen.rows.T, gen.brows.T]
        # (q, q̇): the first entries of the generated data's input, [q; q̇; …]
        args += [gen.c[0], gen.c[1], gen.inp[:n], gen.inp[n : 2 * n], self._bparams, self._cmat_t, self._s0]
        for k, arr in enumerate(args):
            assert arr.flags.c_contiguous  # bound by its memory: a view of the array itself
            buf.set_arg(k, view(arr.reshape(-1)))
        # the outputs, one after the other in one buffer (a step copies it once): y0, λ0, y1, [λ1; φ] (level 1's
        # multipliers [contact rows; F's rows], then φ), F (m0 × ny, held as its transpose), stats, τ, l, u
        sizes = [ny, me, ny, me + 2 * m0, ny * m0, 2, n, mi, mi]
        ends = np.cumsum(sizes)
        self._spans = tuple(slice(int(e - s), int(e)) for s, e in zip(sizes, ends, strict=True))
        self._out = np.zeros(int(ends[-1]))
        results = [self._out[span] for span in self._spans]
        self.y0, self.lam0, self.y1, self._lam_phi, basis, self.stats, self.tau, self.lower, self.upper = results
        self._basis_t = basis.reshape(ny, m0)
        for k, res in enumerate(results):
            buf.set_res(k, view(res))
        self._bound = (buf, args, results)  # the buffer reads and writes these: keep them alive
        self._scale: FloatArray | None = None
        self._live: np.ndarray | None = None
        self._live_basis = np.zeros(0, dtype=np.intp)
        self._live_lam_phi = np.zeros(0, dtype=np.intp)
        self._me = me

    def __reduce__(self) -> tuple[Any, ...]:
        # rebuilt (the library loads from the cache): the buffer is this process's
        return (GeneratedCascade, self._args)

    def _weights(self, qp: ContactQP) -> np.ndarray | None:
        """Level 0's square-root weights into the function's input (when they changed); the rows of non-zero
        weight, None for all."""
        scale = qp.levels[0][0].scale()
        if scale is not self._scale:
            self._s0[:] = scale[: self.m0, 0]
            live = np.flatnonzero(self._s0)
            self._live = None if live.size == self.m0 else live
            m0, me, ny = self.m0, self._me, self._basis_t.shape[0]
            # the entries of the rows of non-zero weight: of F (in its transpose) and of [λ1; φ]
            self._live_basis = (live[:, None] + m0 * np.arange(ny)[None, :]).ravel()
            self._live_lam_phi = np.concatenate((np.arange(me), me + live, me + m0 + live))
            self._scale = scale
        return self._live

    def step(self, qp: ContactQP, gen: GeneratedContactData, chain: SolverChain) -> ContactStep | None:
        """The step of both levels' optimum on their equality rows alone, after ``gen.run`` (at the (q, q̇) it was
        given), if the code's verdict accepts both and level 0's rows take extend_basis's Cholesky basis (module
        docstring); else None."""
        ny = qp.ny
        live = self._weights(qp)
        self._run()
        if self.stats[1] != 1.0 or (live is not None and live.size > ny):
            return None
        # the outputs copied once each (the next run overwrites them), the step's arrays views of the copies; the
        # rows, contact rows and (H, g) read from the generated data's copy when asked for (step_arrays)
        res = ContactStep()
        res.outputs = (gen.out.copy(), gen)
        out = self._out.copy()
        y0s, lam0s, y1s, lam_phis, basis, _, taus, lower, upper = self._spans
        res.bounds = (out[lower], out[upper])
        m0, me = self.m0, self._me
        if live is None:
            k, F, lam_phi = m0, out[basis].reshape(ny, m0).T, out[lam_phis]
        else:  # the rows of non-zero weight (k of them): F's, their multipliers and φ's
            k = live.size
            F = self._basis_t.take(self._live_basis).reshape(k, ny)
            lam_phi = self._lam_phi.take(self._live_lam_phi)
        lam, phi = lam_phi[: me + k], lam_phi[me + k :]
        res.frozen += [None, (F, phi)]
        none, z = qp.no_active, qp.no_multipliers
        y1 = out[y1s]
        res.solutions += [
            QPSolution(out[y0s], "solved", 0, "active set", out[lam0s], z, "active set", 0, none),
            QPSolution(y1, "solved", 0, "active set", lam, z, "active set", 0, none),
        ]
        res.status += ["solved", "solved"]
        res.y = y1
        chain.record(qp.key, none)  # SolverChain.key of each level's QP
        chain.record((1, ny, me + k, z.shape[0]), none)
        res.tau = out[taus]
        return res
