"""`QddQP`: the QP of one priority level without contact forces, solved on q̈ alone.

Without contact forces the equation of motion gives τ outright, τ = M q̈ + h' with h' = C q̇ + g + τ_f, so the
QP over x = [q̈; τ] that :class:`~armctl.controllers.osc.build.StepQP` shows,

    min ½‖W^{1/2}(J q̈ − b)‖² + ½ε(‖q̈‖² + ‖τ‖²)   s.t.   M q̈ − τ = −h',   l ≤ C [q̈; τ] ≤ u,

is, with τ substituted, the QP over q̈ alone (as in TSID)

    min ½‖W^{1/2}(J q̈ − b)‖² + ½ε‖q̈‖² + ½ε‖M q̈ + h'‖²
    s.t. l_τ − h' ≤ M q̈ ≤ u_τ − h'   (each torque limit's rows)
         l_q̈ ≤ q̈ ≤ u_q̈               (each acceleration, position or velocity limit's rows)

— the same optimum exactly (the same cost at every feasible point), with half the variables, no equality
rows, and inequality rows that are the public problem's one for one (their multipliers are the same). The
regularisation enters as 2n rows below the task rows, √ε [I | 0] and √ε [M | −h'], so that one Gram product
of the stacked rows gives H and g.

Each step first tries the unconstrained minimum (on most steps no limit binds): q̈ = −H⁻¹g by a Cholesky
solve, τ = M q̈ + h', accepted if every torque and q̈ bound holds (exactly, so that τ needs no clipping) — the
optimality check of :mod:`~armctl.controllers.osc.optimality` for an empty active set, with no multiplier and so
no gap. Otherwise the whole QP goes to the controller's :class:`~armctl.controllers.osc.chain.SolverChain`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from scipy.linalg import lapack

from armctl._checks import FloatArray
from armctl.controllers.osc.build import QPBuilder, StepQP
from armctl.controllers.osc.chain import QPFailure, SolverChain
from armctl.controllers.osc.diagnose import raise_unsolved
from armctl.controllers.osc.eliminated import EliminatedQP
from armctl.controllers.osc.hierarchy import OSCSolution
from armctl.controllers.osc.layout import Layout
from armctl.controllers.osc.levels import LevelPlan, LevelRows
from armctl.controllers.osc.optimality import verified
from armctl.controllers.osc.problem import QPArrays
from armctl.controllers.osc.scale import MAX_TASK_RHS, refuse_scale
from armctl.controllers.osc.solve import QPSolution
from armctl.controllers.osc.state import ModelState
from armctl.references import Reference

if TYPE_CHECKING:
    from armctl.controllers.osc.generated import GeneratedQddData

_MAX_RHS2 = MAX_TASK_RHS**2


class _QddLayout:
    """The variable blocks of the q̈-only QP (what a LevelPlan reads of a layout)."""

    def __init__(self, n: int) -> None:
        self.nx = n
        self.variables = {"qdd": slice(0, n)}


class QddTerms(NamedTuple):
    """The data of the q̈-only QP at one step, from NumPy (the generated data hold the same as attributes of the
    same names): the Hessian H (n×n) and gradient g (n,) of its cost, the mass matrix M (n×n) and
    h' = C q̇ + g + τ_f (n,) [N·m]."""

    H: FloatArray
    g: FloatArray
    M: FloatArray
    hf: FloatArray


class QddStep:
    """What one step of :class:`QddQP` leaves for :meth:`QddQP.public`: the bounds of every limit (l, u per
    limit), q̈, τ, and the QP ``arrays`` with the chain's ``solution`` (both None for the unconstrained
    minimum). With ``generated``, the rows, and q̈ and τ of the unconstrained minimum, are the code's outputs:
    valid until its next run."""

    __slots__ = ("arrays", "bounds", "generated", "qdd", "solution", "tau")

    def __init__(
        self,
        bounds: list[tuple[FloatArray, FloatArray]],
        qdd: FloatArray,
        tau: FloatArray,
        arrays: QPArrays | None = None,
        solution: QPSolution | None = None,
        generated: GeneratedQddData | None = None,
    ) -> None:
        self.bounds, self.qdd, self.tau, self.arrays, self.solution = bounds, qdd, tau, arrays, solution
        #: the generated code whose outputs hold this step's rows (None: they are in the workspace already)
        self.generated = generated


class QddQP(EliminatedQP["GeneratedQddData", QddStep]):
    """Builds and solves the q̈-only QP of the module docstring for a single-level builder and a layout without
    contacts, and maps its solution back to the public problem. Holds its stacked rows as a workspace: the
    rows of one step are valid until the next (:meth:`public` copies what it keeps)."""

    def __init__(self, builder: QPBuilder, lay: Layout, generated: GeneratedQddData | None = None) -> None:
        n = builder.n
        #: the QP's data from generated code (:mod:`~armctl.controllers.osc.generated`), or None: from NumPy
        self.generated = generated
        self.n = n
        self.layout = lay
        self.builder = builder
        eps = builder.regularization
        tasks = tuple(tk for tk in builder.tasks if tk.variable in lay.variables)
        self.plan = LevelPlan(tasks, _QddLayout(n), extra_rows=2 * n, extra_weight=eps)  # type: ignore[arg-type]  # _QddLayout: the layout's fields LevelPlan reads
        m = self.m = self.plan.m
        self.rows = self.plan.template.copy()  # [J | b] of the tasks; √ε-weighted [I | 0]; [M | −h']
        self.rows[m : m + n, :n] = np.eye(n)
        self.mass_rows = slice(m + n, m + 2 * n)
        self.weighted = np.empty_like(self.rows)
        self.tau_rows: list[slice] = []
        blocks = []
        for k, lim in enumerate(lay.limits):
            if lim.variable == "tau":
                self.tau_rows.append(slice(k * n, (k + 1) * n))
                blocks.append(np.zeros((n, n)))
            else:
                blocks.append(np.eye(n))
        self.C_template = np.vstack(blocks) if blocks else np.zeros((0, n))
        self.no_rows = np.zeros((0, n)), np.zeros(0)
        self.key = (0, n, 0, self.C_template.shape[0])  # SolverChain.key of the arrays, slot 0
        self.no_active = np.zeros(self.C_template.shape[0], dtype=np.int8)
        self.no_active.flags.writeable = False
        # the torque bounds, all torque limits together
        torque = [lim.bounds(None) for lim in lay.limits if lim.variable == "tau"]  # type: ignore[arg-type]  # constant: no state read
        self.tau_check = (
            (np.max([b[0] for b in torque], axis=0).tolist(), np.min([b[1] for b in torque], axis=0).tolist())
            if torque
            else None
        )
        self.qdd_limits = [k for k, lim in enumerate(lay.limits) if lim.variable != "tau"]
        self.torque_only = len(lay.limits) == 1 and not self.qdd_limits
        self.constant = (
            [lim.bounds(None) for lim in lay.limits]  # type: ignore[arg-type]  # constant limits read no state
            if lay.constant_bounds is not None
            else None
        )
        for a in (self.C_template, *self.no_rows):
            a.flags.writeable = False

    def step(self, state: ModelState, t: float, ref: Reference, chain: SolverChain) -> QddStep:
        """The verified optimum at ``state``: its q̈ and τ, and what :meth:`public` needs. Raises
        InvalidParameterError for rows out of scale (:mod:`~armctl.controllers.osc.scale`); if the chain finds
        no verified optimum, InfeasibleError naming the conflicting rows or SolverError."""
        n = self.n
        rows = self.rows
        for tk, r, cols in self.plan.entries:
            J, bb = tk.residual(state, t, ref)
            if J is not None:
                rows[r, cols] = J
            rows[r, n] = bb
        mass = state.mass
        hf = state.bias if state.friction is None else state.bias + state.friction
        mr = self.mass_rows
        rows[mr, :n] = mass
        np.negative(hf, out=rows[mr, n])
        tn = np.multiply(self.plan.scale(), rows, out=self.weighted)
        G = tn.T.dot(tn)
        if not G[n, n] <= _MAX_RHS2:  # ‖W^{1/2} b‖² + ε‖h'‖² (NaN too)
            plan = self.plan
            refuse_scale(plan.tasks, list(plan.slices.values()), rows, n, state, t, ref)
        H, g = G[:n, :n], G[n, :n]
        bounds = self.constant if self.constant is not None else [lim.bounds(state) for lim in self.layout.limits]
        unconstrained = None
        factor, x, info = lapack.dposv(H, g)
        if info == 0:
            np.negative(x, out=x)
            tau = mass.dot(x)
            tau += hf
            if self._holds(x, tau, bounds):
                chain.record(self.key, self.no_active)
                return QddStep(bounds, x, tau)
            unconstrained = (factor, x)
        return self._solve(QddTerms(H, g, mass, hf), bounds, chain, unconstrained, None)

    def _from_generated(
        self, gen: GeneratedQddData, q: FloatArray, qd: FloatArray, chain: SolverChain
    ) -> QddStep | None:
        """:meth:`step` from the outputs of the generated code ``gen`` (this QP's ``generated``) at (q, q̇); None if
        they are out of scale."""
        accepted, constant, guess = gen.accepted, self.constant, gen.guess
        if accepted is not None and constant is not None and guess is not None:
            if accepted[0] == 1.0:  # the code checked its minimum
                chain.record(self.key, self.no_active)
                return QddStep(constant, gen.qdd0, gen.tau0, generated=gen)
            if gen.run_guess():  # the code solved on the rows the minimum breaks, and checked that optimum
                return self._guessed(gen, guess, constant, chain)
        if not gen.c[0] <= _MAX_RHS2:  # ‖W^{1/2} b‖² + ε‖h'‖² (NaN too)
            return None
        if self.constant is not None:
            bounds = self.constant
        else:  # the built-in limits read q and q̇ only (see controller: the generated path takes no others)
            # no evaluator: the built-in limits read no frame
            state = ModelState(None, q, qd, gen.M, gen.hf, None)  # type: ignore[arg-type]
            bounds = [lim.bounds(state) for lim in self.layout.limits]
        x, tau = gen.qdd0, gen.tau0
        # (where the code gave its verdict, in scale, it said that the minimum breaks a row: not checked again)
        if accepted is None and self._holds(x, tau, bounds):
            chain.record(self.key, self.no_active)
            # q̈ and τ read from the code's outputs, as its rows are (valid until its next run; the controller
            # hands out a copy of τ, the public solution copies both)
            return QddStep(bounds, x, tau, generated=gen)
        return self._solve(gen, bounds, chain, None, gen)

    def _guessed(
        self,
        gen: GeneratedQddData,
        guess: tuple[FloatArray, ...],
        bounds: list[tuple[FloatArray, FloatArray]],
        chain: SolverChain,
    ) -> QddStep:
        """The step of the optimum that the generated code found on the rows its unconstrained minimum breaks and
        checked (``gen.guess``): q̈, τ and z read from the code's outputs, as its rows are (valid until its next
        run), the QP's arrays made when the check is run again."""
        _, x, tau, z, active = guess
        act = active.astype(np.int8)
        chain.record(self.key, act)
        sol = QPSolution(x, "solved", 0, "active set", self.no_rows[1], z, "active set", 0, act)
        return QddStep(bounds, x, tau, None, sol, gen)

    def _solve(
        self,
        terms: QddTerms | GeneratedQddData,
        bounds: list[tuple[FloatArray, FloatArray]],
        chain: SolverChain,
        unconstrained: tuple[FloatArray, FloatArray] | None,
        generated: GeneratedQddData | None,
    ) -> QddStep:
        """The verified optimum of the QP of ``terms`` from the solver chain (past the unconstrained minimum)."""
        arrays = self.arrays(terms, bounds, copy=generated is None)
        try:
            sol = chain.solve(arrays, 0, unconstrained=unconstrained)
        except QPFailure as err:
            if generated is not None:
                self._fill_rows(generated)
            raise_unsolved(self.public_step(bounds).problem(0), err.attempts)
        tau = terms.M.dot(sol.x)
        tau += terms.hf
        return QddStep(bounds, sol.x, tau, arrays, sol, generated)

    def _fill_rows(self, gen: GeneratedQddData) -> None:
        """The workspace's rows from the generated code's outputs (as :meth:`step` would have left them)."""
        n, m, mr = self.n, self.m, self.mass_rows
        self.rows[:m] = gen.rows
        self.rows[mr, :n] = gen.M
        np.negative(gen.hf, out=self.rows[mr, n])

    def verify(self, result: QddStep, check: Callable[..., bool] | None = None) -> bool:
        """The optimality check of ``result``, run again (what a step pays for it): the bounds for the
        unconstrained minimum, :func:`~armctl.controllers.osc.optimality.verified` for a solution of the chain
        (``check``: the chain's)."""
        sol = result.solution
        if sol is None:
            return self._holds(result.qdd, result.tau, result.bounds)
        arrays = result.arrays
        if arrays is None:  # solved in the generated code: its QP from the code's outputs (this step's)
            gen = result.generated
            assert gen is not None  # only the generated code solves without the chain's arrays
            arrays = self.arrays(gen, result.bounds, copy=False)
        return verified(arrays, sol.x, sol.y, sol.z, check)

    def _holds(self, x: FloatArray, tau: FloatArray, bounds: list[tuple[FloatArray, FloatArray]]) -> bool:
        """Every torque and q̈ bound holds at (q̈, τ) (False for NaN); compared as Python floats."""
        check = self.tau_check
        if check is not None:
            for v, lo, up in zip(tau.tolist(), *check, strict=True):
                if not lo <= v <= up:
                    return False
        if self.qdd_limits:
            xs = x.tolist()
            for k in self.qdd_limits:
                lo, up = bounds[k]
                for v, a, b in zip(xs, lo.tolist(), up.tolist(), strict=True):
                    if not a <= v <= b:
                        return False
        return True

    def arrays(
        self, terms: QddTerms | GeneratedQddData, bounds: list[tuple[FloatArray, FloatArray]], copy: bool = True
    ) -> QPArrays:
        """The QP on q̈ of ``terms`` and ``bounds`` (its rows those of the public problem, torque rows shifted by
        h'); ``copy=False``: H, g and M taken as they are (the generated code's outputs, kept until its next run)."""
        H, g, mass, hf = terms.H, terms.g, terms.M, terms.hf
        A, b = self.no_rows
        if self.torque_only:  # one torque limit: C = M, bounds shifted by h'
            lo, up = bounds[0]
            if not copy:
                return QPArrays(H, g, A, b, mass, lo - hf, up - hf)
            return QPArrays(np.array(H), g.copy(), A, b, mass.copy(), lo - hf, up - hf)
        C = self.C_template.copy()
        lo = np.concatenate([b[0] for b in bounds]) if bounds else np.zeros(0)
        up = np.concatenate([b[1] for b in bounds]) if bounds else np.zeros(0)
        for r in self.tau_rows:
            C[r] = mass
            lo[r] -= hf
            up[r] -= hf
        return QPArrays(np.array(H), g.copy(), A, b, C, lo, up)

    def public(self, result: QddStep) -> tuple[StepQP, QPSolution]:
        """The public :class:`StepQP` of the last step (x = [q̈; τ]) and its solution mapped onto it: x = [q̈; τ],
        the multipliers y = ε τ + Σ z_τ of the equation of motion and z (the same rows)."""
        if result.generated is not None:
            self._fill_rows(result.generated)
        step = self.public_step(result.bounds)
        sol = result.solution
        z = np.zeros(self.C_template.shape[0]) if sol is None or sol.z is None else sol.z
        y = self.builder.regularization * result.tau
        for r in self.tau_rows:
            y = y + z[r]
        x = np.concatenate((result.qdd, result.tau))
        if sol is None:
            return step, QPSolution(x, "solved", 0, "active set", y, z, "active set", 0, np.zeros(z.shape[0], np.int8))
        return step, QPSolution(x, sol.status, sol.iterations, sol.solver, y, z, sol.stage, sol.fallbacks, sol.active)

    def solution(self, result: QddStep) -> OSCSolution:
        """The public :class:`OSCSolution` of a step (:meth:`public`)."""
        step, mapped = self.public(result)
        return OSCSolution(step, mapped.x, (mapped,), ("solved",), None, [None])

    def public_step(self, bounds: list[tuple[FloatArray, FloatArray]]) -> StepQP:
        """The public :class:`StepQP` of the rows in the workspace (those of the last step)."""
        n, m = self.n, self.m
        lay = self.layout
        mr = self.mass_rows
        mass, hf = self.rows[mr, :n], -self.rows[mr, n]
        A = np.concatenate((mass, lay.A_rest), axis=1)
        lo = np.concatenate([b[0] for b in bounds]) if bounds else np.zeros(0)
        up = np.concatenate([b[1] for b in bounds]) if bounds else np.zeros(0)
        plan = self.builder.plans(lay)[0]
        task_rows = np.zeros((m, lay.nx + 1))
        task_rows[:, :n] = self.rows[:m, :n]
        task_rows[:, lay.nx] = self.rows[:m, n]
        levels = [LevelRows(plan.tasks, task_rows, plan.scale(), plan.slices)]
        return StepQP(lay, A, -hf, lo, up, levels, lay.regularization, False)
