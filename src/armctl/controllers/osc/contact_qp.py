"""`ContactQP`: the QPs of a step with active contacts, or with several priority levels, solved on y = [q̈; f]
(τ eliminated; f the active contacts' forces, none without contacts).

With contacts the equation of motion still gives τ outright, τ = M q̈ − Σ_c J_cᵀ f_c + h' with h' = C q̇ + g + τ_f,
so every level's QP over x = [q̈; τ; f] that :class:`~armctl.controllers.osc.build.StepQP` shows,

    min ½‖T x − t‖² + ½ε_k‖x‖²   s.t.   M q̈ − τ − Σ J_cᵀ f_c = −h',   contact rows,   l ≤ C x ≤ u,

is, with x = E y + e (E = [I 0; B; 0 I], B = [M | −J_1ᵀ … −J_kᵀ], e = [0; h'; 0]), the QP over y

    min ½‖T_y y − t‖² + ½ε_k(‖y‖² + ‖B y + h'‖²)
    s.t. contact rows (on q̈ and f),   l_τ − h' ≤ B y ≤ u_τ − h',   l_q̈ ≤ q̈ ≤ u_q̈,   the cones on f

whenever no task reads τ — the same optimum exactly (the same cost at every feasible point, the rows one for
one), with n fewer variables and n fewer equality rows. Its multipliers are the public problem's: those of the
contact rows, the limits and the cones are the same, the equation of motion's is ε_k τ + Σ z_τ (the τ block of
the public stationarity condition). The regularisation enters as rows below the task rows, √ε_k [I | 0] and
√ε_k [B | −h'], so that one Gram product of the stacked rows gives each level's H and g.

Levels below the first keep the optimum of those above through the rows F y = F y_{k−1}, F an orthonormal basis
of the weighted task rows of the levels above (:func:`~armctl.controllers.osc.hierarchy.extend_basis`): no task
reads τ, so these are the public problem's ``priority[i]`` rows with zero τ columns.

With several levels, each level's optimum on its equality rows alone (the contact rows and F,
:func:`~armctl.controllers.osc.equality_optimum.equality_optimum`) is taken where
:func:`~armctl.controllers.osc.optimality.equality_optimum_ok` finds it the QP's (no inequality row active: the
usual case), and the generated code of :mod:`~armctl.controllers.osc.generated_cascade` does both levels of a
two-level layout in one call; every other QP goes to the controller's
:class:`~armctl.controllers.osc.chain.SolverChain`. τ comes only from a verified optimum.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from armctl._checks import FloatArray
from armctl.controllers.osc.build import QPBuilder
from armctl.controllers.osc.chain import QPFailure, SolverChain
from armctl.controllers.osc.contact import Contact
from armctl.controllers.osc.contact_public import ContactStep, public_solution, step_arrays, taken_step
from armctl.controllers.osc.diagnose import raise_unsolved
from armctl.controllers.osc.eliminated import EliminatedQP
from armctl.controllers.osc.equality_optimum import equality_optimum
from armctl.controllers.osc.hierarchy import OSCSolution, extend_basis
from armctl.controllers.osc.layout import UPPER_REGULARIZATION_FACTOR, Layout
from armctl.controllers.osc.levels import LevelPlan
from armctl.controllers.osc.optimality import equality_optimum_ok, verified
from armctl.controllers.osc.problem import QPArrays
from armctl.controllers.osc.scale import MAX_TASK_RHS, refuse_scale
from armctl.controllers.osc.solve import QPSolution
from armctl.controllers.osc.state import ModelState
from armctl.references import Reference

if TYPE_CHECKING:
    from armctl.controllers.osc.generated_cascade import GeneratedCascade
    from armctl.controllers.osc.generated_contact import GeneratedContactData

_MAX_RHS2 = MAX_TASK_RHS**2


class _YLayout:
    """The variable blocks of y = [q̈; f] (what a LevelPlan reads of a layout)."""

    def __init__(self, nx: int, variables: dict[str, slice]) -> None:
        self.nx = nx
        self.variables = variables


def applies(builder: QPBuilder) -> bool:
    """Whether the QPs of ``builder`` can be solved on [q̈; f]: no slacks and no task on τ."""
    return not builder.slacks and all(tk.variable != "tau" for tk in builder.tasks)


class ContactQP(EliminatedQP["GeneratedContactData", ContactStep]):
    """Builds and solves the levels of one step on y = [q̈; f] (module docstring) for a layout with contacts, and
    maps the solution back onto the public problem (:meth:`solution`). Made once per layout."""

    def __init__(self, builder: QPBuilder, lay: Layout) -> None:
        #: the QPs' data from generated code (:mod:`~armctl.controllers.osc.generated_contact`), or None: NumPy
        self.generated: GeneratedContactData | None = None
        #: with two levels and generated data, their optimum when no inequality row is active, from generated code
        #: (:mod:`~armctl.controllers.osc.generated_cascade`), or None
        self.cascade: GeneratedCascade | None = None
        n = self.n = builder.n
        self.builder = builder
        self.layout = lay
        variables = {"qdd": slice(0, n)}
        col = n
        #: per contact: (contact, its columns in y, its columns in x, its equality rows)
        self.contacts: list[tuple[Contact, slice, slice, slice]] = []
        for k, c in enumerate(lay.contacts):
            variables[c.name] = slice(col, col + c.dim)
            self.contacts.append((c, variables[c.name], lay.variables[c.name], slice(3 * k, 3 * k + 3)))
            col += c.dim
        self.ny = ny = col
        #: per contact: the key of its force in a step's log and its columns in y
        self.force_keys = [(f"force[{c.name}]", cy) for c, cy, _, _ in self.contacts]
        self.variables = variables
        ylay = _YLayout(ny, variables)
        eps = builder.regularization
        plans_x = builder.plans(lay)
        last = len(plans_x) - 1
        self.levels: list[tuple[LevelPlan, LevelPlan, FloatArray, float]] = []
        for k, px in enumerate(plans_x):
            w = eps if k == last else UPPER_REGULARIZATION_FACTOR * eps
            plan = LevelPlan(px.tasks, ylay, extra_rows=ny + n, extra_weight=w)  # type: ignore[arg-type]  # _YLayout: the fields LevelPlan reads
            template = plan.template.copy()
            template[plan.m : plan.m + ny, :ny] = np.eye(ny)
            template.flags.writeable = False
            self.levels.append((plan, px, template, w))
        self.me = 3 * len(lay.contacts)
        # inequality rows on y: [I | 0] per q̈ limit, B per torque limit (filled each step), the cones on f
        blocks = []
        self.tau_rows: list[slice] = []
        for k, lim in enumerate(lay.limits):
            blk = np.zeros((n, ny))
            if lim.variable == "tau":
                self.tau_rows.append(slice(k * n, (k + 1) * n))
            else:
                blk[:, :n] = np.eye(n)
            blocks.append(blk)
        for c, cy, _, _ in self.contacts:
            cf = c.cone_rows()[0]
            blk = np.zeros((cf.shape[0], ny))
            blk[:, cy] = cf
            blocks.append(blk)
        self.C_template = np.vstack(blocks) if blocks else np.zeros((0, ny))
        self.C_template.flags.writeable = False
        self.A_template = np.zeros((self.me, ny))
        self.A_template.flags.writeable = False
        self.nx = lay.nx
        #: the active set with no inequality row active (read-only)
        self.no_active = np.zeros(self.C_template.shape[0], dtype=np.int8)
        self.no_active.flags.writeable = False
        #: the multipliers of the inequality rows with none active (read-only)
        self.no_multipliers = np.zeros(self.C_template.shape[0])
        self.no_multipliers.flags.writeable = False
        #: :meth:`SolverChain.key <armctl.controllers.osc.SolverChain.key>` of level 0's QP
        self.key = (0, ny, self.me, self.C_template.shape[0])
        #: per level: (the plan's weights it was made from, the rows of non-zero weight or None for all, weights)
        self._kept_rows: dict[int, tuple[FloatArray, np.ndarray | None, FloatArray]] = {}

    def step(self, state: ModelState, t: float, ref: Reference, chain: SolverChain) -> ContactStep:
        """The verified optimum of every level at ``state`` (the levels in priority order). Raises
        InvalidParameterError for a level out of scale (:mod:`~armctl.controllers.osc.scale`); if level 0 has no
        verified optimum, InfeasibleError naming the conflicting rows or SolverError."""
        n, ny = self.n, self.ny
        res = ContactStep()
        hf = state.bias if state.friction is None else state.bias + state.friction
        brows = np.empty((n, ny + 1))  # [B | −h']
        brows[:, :n] = state.mass
        np.negative(hf, out=brows[:, ny])
        A = self.A_template.copy()
        b = np.empty(self.me)
        for c, cy, _, rows in self.contacts:
            fk = state.frame(c.frame)
            np.negative(fk.jacobian[:3].T, out=brows[:, cy])
            gq, gf, rhs = c.equality_rows(state)
            A[rows, :n] = gq
            A[rows, cy] = gf
            b[rows] = rhs
        res.b_rows, res.contact = brows, (A, b)
        levels = []
        last = len(self.levels) - 1
        for k, (plan, _, template, _) in enumerate(self.levels):
            rows = template.copy()
            for tk, r, cols in plan.entries:
                J, bb = tk.residual(state, t, ref)
                if J is not None:
                    rows[r, cols] = J
                rows[r, ny] = bb
            m = plan.m
            rows[m + ny :] = brows
            res.rows.append(rows)
            tn = plan.scale() * rows
            G = tn.T.dot(tn)
            if not G[ny, ny] <= _MAX_RHS2:  # ‖W^{1/2} b‖² + ε_k‖h'‖² (NaN too)
                refuse_scale(plan.tasks, list(plan.slices.values()), rows, ny, state, t, ref)
            # H contiguous (DAQP reads the buffer)
            levels.append((G[:ny, :ny].copy(), G[ny, :ny], self._weighted_rows(k, rows) if k < last else None))
        return self._cascade(res, hf, self.bounds(state), levels, chain)

    def _from_generated(
        self, gen: GeneratedContactData, q: FloatArray, qd: FloatArray, chain: SolverChain
    ) -> ContactStep | None:
        """:meth:`step` from the outputs of the generated code ``gen`` at (q, q̇); None if a level's rows are out of
        scale."""
        if gen.accepted[0] == 1.0:  # one level, constant bounds: the code checked its optimum on the contact rows
            return taken_step(self, gen, chain)
        if gen.guess_out is not None and gen.run_guess():  # its active-set iterations' optimum, checked
            return taken_step(self, gen, chain, guessed=True)
        for c in gen.c:
            if not c[0] <= _MAX_RHS2:  # ‖W^{1/2} b‖² + ε_k‖h'‖² (NaN too)
                return None
        if self.cascade is not None:
            taken = self.cascade.step(self, gen, chain)
            if taken is not None:
                return taken
        n, ny = self.n, self.ny
        res = ContactStep()
        brows = gen.brows.copy()  # kept by the step (the code's outputs are overwritten by the next run)
        hf = -brows[:, ny]
        res.b_rows = brows
        contact = gen.contact.copy()  # one copy, then its two views
        res.contact = (contact[:, :ny], contact[:, ny])
        levels = []
        start = 0
        last = len(self.levels) - 1
        for k, (plan, _, _, _) in enumerate(self.levels):
            m = plan.m
            rows = gen.rows[start : start + m].copy()
            start += m
            res.rows.append(rows)
            levels.append((gen.H[k].copy(), gen.g[k].copy(), self._weighted_rows(k, rows) if k < last else None))
        # the built-in limits read q and q̇ only (see controller: the generated path takes no others)
        state = ModelState(None, q, qd, brows[:, :n], hf, None)  # type: ignore[arg-type]  # no evaluator: no frame read
        # where the code gave its verdict on the optimum on the contact rows alone (gen.accepted, the check of
        # equality_optimum_ok), it said no: that optimum is not offered again
        equality = gen.equality if gen.limits is None else None
        return self._cascade(res, hf, self.bounds(state), levels, chain, equality)

    def _weighted_rows(self, k: int, rows: FloatArray) -> FloatArray:
        """T_k: level k's task rows weighted (W^½ J on y), without the rows of zero weight (a task direction
        switched off spans nothing: :func:`~armctl.controllers.osc.hierarchy.extend_basis` then factors the rows
        without taking them out)."""
        plan = self.levels[k][0]
        scale = plan.scale()
        kept = self._kept_rows.get(k)
        if kept is None or kept[0] is not scale:  # the weights changed (a task's revision): the rows kept anew
            nonzero = np.flatnonzero(scale[: plan.m, 0])
            kept = (scale, None if nonzero.size == plan.m else nonzero, scale[: plan.m, : self.ny])
            self._kept_rows[k] = kept
        _, live, weights = kept
        if live is None:
            return weights * rows[: plan.m, : self.ny]
        return weights[live] * rows[live, : self.ny]

    def bounds(self, state: ModelState) -> tuple[FloatArray, FloatArray]:
        """The public bounds l, u of the limits and cones at ``state``."""
        lay = self.layout
        if lay.constant_bounds is not None:
            return lay.constant_bounds
        bounds = [lim.bounds(state) for lim in lay.limits]
        lo = np.concatenate([bd[0] for bd in bounds] + [lay.cone_l])
        up = np.concatenate([bd[1] for bd in bounds] + [lay.cone_u])
        return lo, up

    def _cascade(
        self,
        res: ContactStep,
        hf: FloatArray,
        bounds: tuple[FloatArray, FloatArray],
        levels: list[tuple[FloatArray, FloatArray, FloatArray | None]],
        chain: SolverChain,
        equality: tuple[FloatArray, ...] | None = None,
    ) -> ContactStep:
        """Solve the levels (H_k, g_k, the weighted task rows T_k, None for the last level, whose rows freeze
        nothing) in order under the step's rows (``res``).
        ``equality``: for one level, the generated optimum on the contact rows alone and its residuals (see
        generated_contact), taken if it passes :meth:`_accept_equality`."""
        ny = self.ny
        brows = res.b_rows
        A, b = res.contact
        res.bounds = bounds
        C, ly, uy = self.inequalities(brows, hf, bounds)
        F = np.zeros((0, ny))
        y: FloatArray | None = None
        last = len(levels) - 1
        for k, (H, g, T) in enumerate(levels):
            frozen = None if y is None else (F, F.dot(y))
            res.frozen.append(frozen)
            if frozen is not None and F.shape[0]:
                arrays = QPArrays(H, g, np.vstack((A, F)), np.concatenate((b, frozen[1])), C, ly, uy)
            else:
                arrays = QPArrays(H, g, A, b, C, ly, uy)
            res.arrays.append(arrays)
            if equality is not None and k == 0:
                if equality_optimum_ok(arrays, *equality):
                    res.y = y = self._take_equality(res, arrays, k, equality[0].copy(), equality[1].copy(), chain)
                    break
            elif last:  # several levels: the optimum on the equality rows alone, if it is the QP's
                opt = equality_optimum(H, g, arrays.A, arrays.b)
                if opt is not None and equality_optimum_ok(arrays, *opt):
                    y = self._take_equality(res, arrays, k, opt[0], opt[1], chain)
                    if k < last and T is not None:
                        F = extend_basis(F, T)
                    continue
            try:
                sol = chain.solve(arrays, k)
            except QPFailure as err:
                if y is None:
                    raise_unsolved(self.solution(res, partial=True).problem(0), err.attempts)
                res.solutions.append(None)
                res.status.append(
                    f"kept level {k - 1}: no verified optimum ({err.attempts[-1][1] if err.attempts else ''})"
                )
                if k < last and T is not None:  # (T is given for every level but the last)
                    F = extend_basis(F, T)
                continue
            res.solutions.append(sol)
            res.status.append("solved")
            y = sol.x
            if k < last and T is not None:
                F = extend_basis(F, T)
        assert y is not None  # level 0 raised otherwise
        res.y = y
        tau = brows[:, :ny].dot(y)
        tau += hf
        res.tau = tau
        return res

    def _take_equality(
        self, res: ContactStep, arrays: QPArrays, k: int, y: FloatArray, lam: FloatArray, chain: SolverChain
    ) -> FloatArray:
        """Level k's optimum on its equality rows alone (y, their multipliers λ; no inequality row active),
        verified, into ``res`` and the chain's record; returns y."""
        z = np.zeros(arrays.l.shape[0])
        sol = QPSolution(y, "solved", 0, "active set", lam, z, "active set", 0, self.no_active)
        chain.record(chain.key(arrays, k), self.no_active)
        res.solutions.append(sol)
        res.status.append("solved")
        return y

    def forces(self, res: ContactStep) -> dict[str, FloatArray]:
        """Each active contact's force f [N] of a step (views of its y)."""
        return {c.name: res.y[cy] for c, cy, _, _ in self.contacts}

    def inequalities(
        self, brows: FloatArray, hf: FloatArray, bounds: tuple[FloatArray, FloatArray]
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(C, l, u) on y: B in each torque limit's rows, its bounds shifted by −h'."""
        lo, up = bounds
        if not self.tau_rows:
            return self.C_template, lo, up
        C = self.C_template.copy()
        shift = np.zeros(lo.shape[0])  # h' in the torque rows (l − 0 is l exactly, ±inf included)
        for r in self.tau_rows:
            C[r] = brows[:, : self.ny]
            shift[r] = hf
        return C, lo - shift, up - shift

    def verify(self, res: ContactStep, check: Callable[..., bool] | None = None) -> bool:
        """The optimality check of every level's solution of ``res``, run again (what a step pays for it;
        ``check``: the chain's, see :func:`~armctl.controllers.osc.optimality.verified`)."""
        for arrays, sol in zip(step_arrays(self, res), res.solutions, strict=True):
            if sol is not None and not verified(arrays, sol.x, sol.y, sol.z, check):
                return False
        return True

    def solution(self, res: ContactStep, partial: bool = False) -> OSCSolution:
        """The public :class:`OSCSolution` of a step (:func:`~armctl.controllers.osc.contact_public.public_solution`;
        ``partial``: for a step that stopped at level 0, only its problem is read)."""
        return public_solution(self, res, partial)
