"""`QPBuilder`: turns the model terms of one control step, the tasks, limits and contacts into QPs
(:class:`StepQP`); the variables, rows and costs are described with :class:`QPBuilder`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from armctl._checks import FloatArray
from armctl.controllers.osc.contact import Contact
from armctl.controllers.osc.docstrings import step_parameters
from armctl.controllers.osc.layout import UPPER_REGULARIZATION_FACTOR, Layout
from armctl.controllers.osc.levels import LevelPlan, LevelRows
from armctl.controllers.osc.limits.base import Limit
from armctl.controllers.osc.problem import QPArrays, QPProblem
from armctl.controllers.osc.state import ModelState
from armctl.controllers.osc.tasks.base import Task
from armctl.model.robot import RobotModel
from armctl.references import Reference


def level_cost(lev: LevelRows, reg_matrix: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(H, g) of a level's cost without slacks: H = TᵀT + ε I (``reg_matrix``), g = −Tᵀt."""
    Tn = lev.Tn
    G = Tn.T.dot(Tn)  # [TᵀT, −Tᵀt; −tᵀT, tᵀt]
    nx = lev.nx
    # g: G's last row, a contiguous view (G is symmetric: NumPy computes AᵀA so)
    return G[:nx, :nx] + reg_matrix, G[nx, :nx]


class StepQP:
    """Everything one control step solves: the constraints and, per priority level, the task rows (made by
    :meth:`QPBuilder.build`); :meth:`problem` gives the QP of a level.

    Parameters
    ----------
    layout : Layout
        The variable blocks and the constant rows for the contacts active at this step.
    A, b : ndarray
        The equality rows A x = b: the equation of motion [N·m] and the contacts' rows.
    l, u : ndarray
        The bounds l ≤ C x ≤ u of the limits and friction cones (C is the layout's).
    levels : list of LevelRows
        The stacked task rows of each priority level, in order.
    regularization : ndarray, shape (nx,)
        ε per variable, the last level's regularisation (the levels above get ε·1e-4).
    slacks : bool
        Whether task rows become constraints with slack variables.
    """

    def __init__(
        self,
        layout: Layout,
        A: FloatArray,
        b: FloatArray,
        l: FloatArray,  # noqa: E741
        u: FloatArray,
        levels: list[LevelRows],
        regularization: FloatArray,
        slacks: bool,
    ) -> None:
        self.layout = layout
        self.A, self.b, self.l, self.u = A, b, l, u
        self.levels = levels
        self.regularization = regularization
        self.slacks = slacks

    @property
    def variables(self) -> dict[str, slice]:
        """The variable blocks of x, name ("qdd", "tau", a contact's name) → slice."""
        return self.layout.variables

    def problem(self, k: int = 0, frozen: tuple[FloatArray, FloatArray] | None = None) -> QPProblem:
        """The QP of one level, named row by row.

        Parameters
        ----------
        k : int, optional
            The level's index in priority order (0: the most important).
        frozen : (ndarray, ndarray), optional
            (F, φ): the equality rows F x = φ (named ``priority[i]``) that keep the optimum of the levels above;
            None: none.

        Returns
        -------
        QPProblem
            H, g, A, b, C, l, u and the names of the variables and rows; with slacks, x gains the block
            ``"slack"`` and A the rows T x − s = t.
        """
        lay, lev = self.layout, self.levels[k]
        eq_names = lay.eq_names
        if frozen is not None and frozen[0].shape[0]:
            eq_names = eq_names + tuple(f"priority[{i}]" for i in range(frozen[0].shape[0]))
        names = tuple(t.name for t in lev.tasks)
        if not self.slacks:
            a = self.arrays(k, frozen)
            return QPProblem(a.H, a.g, a.A, a.b, a.C, a.l, a.u, lay.variables, eq_names, lay.ineq_names, k, names)
        A, b = self.A, self.b
        if frozen is not None and frozen[0].shape[0]:
            A = np.vstack([A, frozen[0]])
            b = np.concatenate([b, frozen[1]])
        m, nx = lev.T.shape[0], lay.nx
        reg = self.regularization if k == len(self.levels) - 1 else UPPER_REGULARIZATION_FACTOR * self.regularization
        H = np.diag(np.concatenate([reg, np.ones(m)]))
        A2 = np.zeros((A.shape[0] + m, nx + m))
        A2[: A.shape[0], :nx] = A
        A2[A.shape[0] :, :nx] = lev.T
        A2[A.shape[0] :, nx:] = -np.eye(m)
        C2 = np.hstack([lay.C, np.zeros((lay.C.shape[0], m))])
        variables = dict(lay.variables, slack=slice(nx, nx + m))
        slack_names = tuple(f"slack[{t.name}][{i}]" for t in lev.tasks for i in range(t.dim))
        return QPProblem(
            H,
            np.zeros(nx + m),
            A2,
            np.concatenate([b, lev.t]),
            C2,
            self.l,
            self.u,
            variables,
            eq_names + slack_names,
            lay.ineq_names,
            k,
            names,
        )

    def arrays(self, k: int = 0, frozen: tuple[FloatArray, FloatArray] | None = None) -> QPArrays:
        """The arrays of :meth:`problem` without the names, for a step without slacks.

        Parameters
        ----------
        k : int, optional
            The level's index in priority order.
        frozen : (ndarray, ndarray), optional
            (F, φ): the equality rows F x = φ that keep the optimum of the levels above; None: none.

        Returns
        -------
        QPArrays
            H, g, A, b, C, l, u of the QP of level ``k``.
        """
        lay = self.layout
        H, g = level_cost(self.levels[k], lay.reg_matrix if k == len(self.levels) - 1 else lay.reg_matrix_upper)
        A, b = self.A, self.b
        if frozen is not None and frozen[0].shape[0]:
            A = np.vstack([A, frozen[0]])
            b = np.concatenate([b, frozen[1]])
        return QPArrays(H, g, A, b, lay.C, self.l, self.u)


class QPBuilder:
    """Builds a :class:`StepQP` per control step for fixed tasks, limits and contacts (contacts may be switched
    on and off: one layout is kept per set of active contacts). :class:`~armctl.controllers.OperationalSpaceQP`
    makes one from its arguments, checked.

    Parameters
    ----------
    model : RobotModel
        The arm (its number of joints and joint names).
    tasks : sequence of Task
        The tasks; their priorities give the levels.
    limits : sequence of Limit
        The limits, already bound to ``model``.
    contacts : sequence of Contact
        The declared contacts, active or not.
    regularization : float, optional
        ε > 0 of the last level's ½ε‖x‖² (see Notes).
    slacks : bool, optional
        Task rows as constraints with slack variables (see Notes).

    Notes
    -----
    Decision variables x = [q̈ (n); τ (n); f_c (3) per active contact]. Rows, every one named:

    * equation of motion (n rows):  M q̈ − τ − Σ_c J_cᵀ f_c = −(C q̇ + g + τ_f)          ``dynamics[joint]``
    * contact kinematics (3 rows per active contact), see :class:`~armctl.controllers.osc.Contact`
    * limits l ≤ x_b ≤ u (one row per joint and limit) and the contacts' friction-cone rows.

    Each priority level k gets the cost  ½ Σ_{tasks i of level k} ‖W_i^{1/2} (J_i x_i − b_i)‖² + ½ ε_k ‖x‖²,
    i.e.  H_k = T_kᵀ T_k + ε_k I,  g_k = −T_kᵀ t_k  with T_k, t_k the weighted task rows stacked. ε (``regularization``)
    makes the last level's H positive definite and picks, among equally good solutions, the smallest; levels above
    it get ε·1e-4 only, because there a regularisation would trade the level's own accuracy for a smaller x (a bias
    of order ε‖x‖²) that the levels below resolve anyway. The solver resolves that choice only to its tolerance:
    along directions no task sees the cost's curvature is ε, so with ProxQP's default ``eps_abs = 1e-6`` the
    redundant (null-space) part of q̈ is not the smallest but whatever the warm start leaves (12 % of ‖q̈‖ off on the
    Panda with a position task alone). Give the redundancy a task (a posture task, as the examples do) or tighten
    ``eps_abs`` (``ProxQPSolver(eps_abs=1e-9)`` finds the minimum-norm q̈).

    With ``slacks=True`` the task rows become constraints with slack variables s: T_k x − s = t_k and the cost
    ½‖s‖² + ½ε‖x‖² — the same optimum, with s reporting how far each task is from being met.
    """

    def __init__(
        self,
        model: RobotModel,
        tasks: Sequence[Task],
        limits: Sequence[Limit],
        contacts: Sequence[Contact],
        regularization: float = 1e-8,
        slacks: bool = False,
    ) -> None:
        self.model = model
        self.n = model.n
        self.tasks = tuple(tasks)
        self.limits = tuple(limits)
        self.contacts = tuple(contacts)
        self.priorities = sorted({t.priority for t in self.tasks})
        self.regularization = float(regularization)
        self.slacks = bool(slacks)
        self._layouts: dict[tuple[str, ...], Layout] = {}
        # keyed by the layout itself, not its id(): a pickled builder's copies keep their pairing (pickle keeps
        # shared objects shared), where ids of the original's layouts could come back as other objects' ids
        self._level_plans: dict[Layout, list[LevelPlan]] = {}

    def layout(self) -> Layout:
        """The layout for the contacts active now (made on first use).

        Returns
        -------
        Layout
            The variable blocks, the constant rows C, the rows' names and the constant bounds.
        """
        if not self.contacts:
            lay = self._layouts.get(())
            if lay is not None:
                return lay
        active = tuple(c.name for c in self.contacts if c.active)
        lay = self._layouts.get(active)
        if lay is None:
            lay = self._layouts[active] = Layout(
                self.model, self.limits, [c for c in self.contacts if c.active], self.regularization
            )
        return lay

    @step_parameters
    def build(self, state: ModelState, t: float, ref: Reference) -> StepQP:
        """The QPs of one control step.

        (the Parameters section of a control step's state, t, ref)

        Returns
        -------
        StepQP
            The constraints and each level's task rows.
        """
        lay = self.layout()
        A, b, lo, up = self.constraints(lay, state)
        levels = [self.level(plan, state, t, ref) for plan in self.plans(lay)]
        return StepQP(lay, A, b, lo, up, levels, lay.regularization, self.slacks)

    def constraints(self, lay: Layout, state: ModelState) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """The constraints of one step: equation of motion, contact rows, bounds.

        Parameters
        ----------
        lay : Layout
            The layout of the active contacts (:meth:`layout`).
        state : ModelState
            The model terms at the measured (q, q̇).

        Returns
        -------
        A, b : ndarray
            The equality rows A x = b.
        l, u : ndarray
            The bounds l ≤ C x ≤ u (C: the layout's).
        """
        n = self.n
        if not lay.contacts:  # A = [M, −I], b = −(h + τ_f): the common case in as few array operations
            A = np.concatenate((state.mass, lay.A_rest), axis=1)
            if state.friction is None:
                b = np.negative(state.bias)
            else:
                b = np.add(state.bias, state.friction)
                np.negative(b, out=b)
        else:
            A = lay.A_template.copy()
            A[:n, :n] = state.mass
            b = np.empty(A.shape[0])
            np.negative(state.bias, out=b[:n])
            if state.friction is not None:
                b[:n] -= state.friction
        row = n
        for c in lay.contacts:
            gq, gf, rhs = c.equality_rows(state)
            cols = lay.variables[c.name]
            A[:n, cols] = -state.frame(c.frame).jacobian[:3].T
            A[row : row + 3, :n] = gq
            A[row : row + 3, cols] = gf
            b[row : row + 3] = rhs
            row += 3
        if lay.constant_bounds is not None:
            lo, up = lay.constant_bounds
        else:
            bounds = [lim.bounds(state) for lim in lay.limits]
            lo = np.concatenate([bd[0] for bd in bounds] + [lay.cone_l])
            up = np.concatenate([bd[1] for bd in bounds] + [lay.cone_u])
        return A, b, lo, up

    def plans(self, lay: Layout) -> list[LevelPlan]:
        """What stays fixed of each level's task rows for one layout (made on first use).

        Parameters
        ----------
        lay : Layout
            The layout of the active contacts.

        Returns
        -------
        list of LevelPlan
            One per priority level, in order (tasks on an inactive contact's force left out).
        """
        plans = self._level_plans.get(lay)
        if plans is None:
            plans = self._level_plans[lay] = [
                LevelPlan(tuple(tk for tk in self.tasks if tk.priority == k and tk.variable in lay.variables), lay)
                for k in self.priorities
            ]
        return plans

    @staticmethod
    def level(plan: LevelPlan, state: ModelState, t: float, ref: Reference) -> LevelRows:
        """The task rows of one level at this step.

        Parameters
        ----------
        plan : LevelPlan
            The level's plan (:meth:`plans`).
        state, t, ref
            As for :meth:`build`.

        Returns
        -------
        LevelRows
            The stacked rows [J | b] of the level's tasks and their weights.
        """
        jr = plan.template.copy()
        nx = plan.nx
        for tk, rows, cols in plan.entries:
            J, bb = tk.residual(state, t, ref)
            if J is not None:
                jr[rows, cols] = J
            jr[rows, nx] = bb
        return LevelRows(plan.tasks, jr, plan.scale(), plan.slices)
