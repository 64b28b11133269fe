"""`OperationalSpaceQP`: operational-space control as one QP (or a cascade of QPs) per control period.

The QP, the task targets, the solver chain and the q̈-only path are described with the class
(:class:`OperationalSpaceQP`, its Notes); :func:`default_limits` gives the usual limits.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from typing import Any

import numpy as np

from armctl._checks import FloatArray, instances, scalar, vector
from armctl.codegen import Fallback, compile_mode
from armctl.controllers.base import Controller
from armctl.controllers.osc.build import QPBuilder, StepQP
from armctl.controllers.osc.chain import QPFailure, SolverChain
from armctl.controllers.osc.contact import Contact
from armctl.controllers.osc.contact_public import ContactStep
from armctl.controllers.osc.contact_qp import ContactQP, applies
from armctl.controllers.osc.diagnose import raise_unsolved
from armctl.controllers.osc.hierarchy import OSCSolution, solve_cascade
from armctl.controllers.osc.kkt_code import FALLBACK as CHECK_FALLBACK
from armctl.controllers.osc.kkt_code import CompiledKKT
from armctl.controllers.osc.layout import Layout
from armctl.controllers.osc.limits import (
    AccelerationLimit,
    JointPositionLimit,
    JointVelocityLimit,
    Limit,
    TorqueLimit,
)
from armctl.controllers.osc.optimality import verified
from armctl.controllers.osc.reduced import QddQP, QddStep
from armctl.controllers.osc.run_report import RunReport
from armctl.controllers.osc.scale import check_level_scale
from armctl.controllers.osc.solve import make_second_solver, make_solver
from armctl.controllers.osc.state import ModelEvaluator
from armctl.controllers.osc.task_errors import FrameTaskLog
from armctl.controllers.osc.tasks.base import Task
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError, SolverWarning
from armctl.references import Reference

#: the limits whose bounds read only q and q̇ of a step's state (the generated path gives them no more)
_PLAIN_LIMITS = (TorqueLimit, JointPositionLimit, JointVelocityLimit, AccelerationLimit)
#: what ``compile="auto"`` runs where the QP's generated data cannot be built
FALLBACK = Fallback(
    "the operational-space QP's generated data", "the NumPy path (Pinocchio's terms)", "about twice as slow"
)


def default_limits(dt: float = 1e-3) -> list[Limit]:
    """The limits an :class:`OperationalSpaceQP` takes by default: torque, joint position (viability) and joint
    velocity limits, each at the model's own limits (applied when the controller binds them to its model).

    Parameters
    ----------
    dt : float, optional
        The control period Δt [s] that the position and velocity limits look one step ahead by.

    Returns
    -------
    list of Limit
        ``[TorqueLimit(), JointPositionLimit(dt), JointVelocityLimit(dt)]``.

    Raises
    ------
    InvalidParameterError, NonFiniteError
        ``dt`` is not a positive, finite number.
    """
    return [TorqueLimit(), JointPositionLimit(dt), JointVelocityLimit(dt)]


def _unique(items: Sequence[Any], kind: str) -> None:
    names = [it.name for it in items]
    dup = sorted({nm for nm in names if names.count(nm) > 1})
    if dup:
        raise InvalidParameterError(f"{kind} names must be unique; repeated: {dup} (give name=...)", value=dup)


class OperationalSpaceQP(RunReport, Controller):
    """Operational-space control as a QP: every control period, the torques of the joint accelerations that
    best serve the tasks, level by level in priority order, within the limits and the contacts' rows.

    Parameters
    ----------
    dynamics : Dynamics
        The controller's model: M(q), C(q, q̇) q̇ + g(q), τ_f(q̇) and the frames' kinematics. Any backend works
        (Pinocchio evaluates a step's terms in one pass); the QP of one level without contacts takes its data
        from generated code (see ``compile`` and Notes).
    tasks : sequence of Task
        At least one :class:`~armctl.controllers.osc.Task` (or a single one), with unique names.
        ``task.priority`` (0 first) orders the levels strictly; ``task.weight`` trades tasks off inside a level.
    limits : sequence of Limit, optional
        :class:`~armctl.controllers.osc.Limit` objects, bound to the model here; None (the default) gives
        :func:`default_limits` with ``dt``, an empty sequence no limit.
    contacts : sequence of Contact, optional
        Declared point contacts (:class:`~armctl.controllers.osc.Contact`, unique names), switched on and off
        between periods with ``contact.active``.
    solver : str or object, optional
        The primary solver of the chain: ``"proxsuite"`` (dense ProxQP, warm-started; the default),
        ``"qpsolvers:NAME"`` (a solver of qpsolvers), or an object with ``solve(problem, slot)`` and ``reset()``
        (and ``solve_raw(arrays, slot, mode)``, which the controller then calls on the QP's arrays, as on
        :class:`~armctl.controllers.osc.ProxQPSolver`).
    regularization : float, optional
        ε > 0 of the cost term ½ε‖x‖² of the last (lowest-priority) level [the cost's units per unit of x²]; the
        levels above it get ε·1e-4 (see :class:`~armctl.controllers.osc.QPBuilder`).
    slacks : bool, optional
        Task rows as equality constraints with slack variables (the same optimum; the slacks, in
        ``last_solution.slacks``, say how far each task is from being met). The q̈-only path is then not used.
    dt : float, optional
        Control period Δt [s] of the default limits; used only when ``limits`` is None.
    fallback_solver : str, object or None, optional
        The last stage of the chain: ``"active-set"``
        (:class:`~armctl.controllers.osc.DualActiveSetSolver`, the default), ``"qpsolvers:NAME"``, an object with
        ``solve_raw(arrays, slot, mode)`` and ``reset()``, or None (no second solver).
    compile : bool or "auto", optional
        Where the data of the q̈-only QP come from (see Notes): ``"auto"`` (the default) from generated C code
        on a Pinocchio-backed ``dynamics`` whenever it can be built (the first time for a model and tasks it is
        compiled, about a second, and cached on disk; without a C compiler the NumPy path is used, with one
        :class:`~armctl.errors.PerformanceWarning`); ``True`` from generated code on any backend, a failed build
        raising :class:`~armctl.errors.BackendError`; ``False`` from Pinocchio's terms and NumPy.

    Raises
    ------
    InvalidParameterError
        ``dynamics`` is not a Dynamics; no task; tasks, limits or contacts that are not of their class; repeated
        task or contact names; ``regularization`` or ``dt`` not > 0; a limit whose bounds leave no range;
        ``compile`` not True, False or ``"auto"``.
    BackendError
        ``compile=True`` and the generated code cannot be built (no C compiler, a failing one).
    UnknownNameError
        A task's or contact's frame that the model does not have; a
        :class:`~armctl.controllers.osc.ContactForceTask` on a contact that is not in ``contacts``; an unknown
        ``solver`` or ``fallback_solver``.
    ShapeError, NonFiniteError
        A posture task or a limit sized for another number of joints; a limit that is NaN.

    See Also
    --------
    ClosedFormOSC : Khatib's closed-form law, the baseline without limits.

    Notes
    -----
    Every period, at the measured (q, q̇)::

        min over x = [q̈, τ, f]   Σ_levels-in-order  ½ Σ_i ‖W_i^{1/2}(J_i x_i − b_i)‖²
        s.t.  M q̈ + C q̇ + g + τ_f − Σ_c J_cᵀ f_c = τ       (the controller's own model)
              contact kinematics, friction cones, torque / position (viability) / velocity limits

    and τ goes to the arm. Task targets:

    * frame tasks (:class:`~armctl.controllers.osc.FramePositionTask`,
      :class:`~armctl.controllers.osc.FrameOrientationTask`, :class:`~armctl.controllers.osc.FramePoseTask`)
      take a constant target through ``task.set_target(...)`` or a trajectory through
      ``task.set_trajectory(fn)``, ``fn(t) -> (value, velocity, acceleration)``; either may be changed between
      periods;
    * :class:`~armctl.controllers.osc.PostureTask` follows the joint reference ``ref`` handed to the controller
      (unless fixed);
    * :class:`~armctl.controllers.osc.ContactForceTask` takes a force vector or a callable of t.

    Contacts are switched with ``contact.active``. The QP of a period can be looked at before (or instead of)
    solving it: :meth:`build` returns the :class:`~armctl.controllers.osc.StepQP`, ``.problem(k)`` the
    :class:`~armctl.controllers.osc.QPProblem` (H, g, A, b, C, l, u) of level k.

    Every QP is solved by a :class:`~armctl.controllers.osc.SolverChain`: τ comes only from a solution verified
    against the QP's optimality conditions (the KKT conditions). Its first stage is DAQP (a dual active-set solver
    in C) started from the last step's active set; a QP whose answer fails the check goes on to the primary
    solver (ProxQP: warm start, cold start, default settings) and a second solver. With one priority level, no
    slacks and no active contact the QP is solved on q̈ alone (τ = M q̈ + C q̇ + g + τ_f substituted: the same
    optimum), and (``compile``) its data come from one call of generated C code when its
    tasks (:class:`~armctl.controllers.osc.FramePositionTask`, :class:`~armctl.controllers.osc.FrameOrientationTask`,
    :class:`~armctl.controllers.osc.FramePoseTask`, :class:`~armctl.controllers.osc.PostureTask`, not
    subclasses) and limits are built-in ones. With active contacts the QPs are solved on [q̈; f] (τ eliminated, every
    level; see :mod:`~armctl.controllers.osc.contact_qp`), their data likewise from generated code when the tasks
    are of those kinds or :class:`~armctl.controllers.osc.ContactForceTask`. Each step's fallbacks are in
    ``last_log["qp_fallbacks"]``;
    :meth:`end_run` (which :func:`armctl.sim.simulate` calls) warns once with what happened during the run and
    how often.

    ``last_log`` holds ``"qp_iterations"`` and ``"qp_fallbacks"`` (summed over the levels), ``"force[NAME]"``
    [N] per active contact (the force on the robot), with more than one level ``"level_status"``, and each frame
    task's target and weights, from which the run's result computes the task's errors (see
    :mod:`~armctl.controllers.osc.task_errors`).
    """

    dynamics: Dynamics  # given to __init__, never None
    run_warning = SolverWarning

    def __init__(
        self,
        dynamics: Dynamics,
        tasks: Sequence[Task],
        limits: Sequence[Limit] | None = None,
        contacts: Sequence[Contact] = (),
        solver: str | Any = "proxsuite",
        regularization: float = 1e-8,
        slacks: bool = False,
        dt: float = 1e-3,
        fallback_solver: str | Any = "active-set",
        compile: bool | str = "auto",
    ) -> None:
        if not isinstance(dynamics, Dynamics):
            raise InvalidParameterError(
                f"dynamics must be an armctl.Dynamics, got {type(dynamics).__name__}", value=dynamics
            )
        super().__init__(dynamics)
        self.compile = compile_mode(compile)
        tasks = instances(tasks, Task, "tasks", "Task", single=True)
        if not tasks:
            raise InvalidParameterError("OperationalSpaceQP needs at least one task", value=tasks)
        contacts = instances(contacts, Contact, "contacts", "Contact", single=True)
        _unique(tasks, "task")
        _unique(contacts, "contact")
        self.evaluator = ModelEvaluator(dynamics)
        for c in contacts:
            self.evaluator.check_frame(c.frame)
        cdims = {c.name: c.dim for c in contacts}
        for t in tasks:
            t.check(self.evaluator, self.n, cdims)
        limits = (
            default_limits(scalar(dt, "dt", positive=True))
            if limits is None
            else instances(limits, Limit, "limits", "Limit", single=True)
        )
        for lim in limits:
            lim.bind(dynamics.model)
        self.tasks = tasks
        self._task_log = FrameTaskLog(tasks)  # what each step logs of the frame tasks
        self.limits = tuple(limits)
        self.contacts = contacts
        self.solver = make_solver(solver)
        # the first stage's check compiled for the QPs whose data are generated (see _compiled_check)
        check = CompiledKKT(dynamics.options.get("cache_dir"))
        self.chain = SolverChain(self.solver, make_second_solver(fallback_solver), check=check)
        self.builder = QPBuilder(
            dynamics.model, tasks, limits, contacts, scalar(regularization, "regularization", positive=True), slacks
        )
        torque = [lim for lim in limits if isinstance(lim, TorqueLimit)]
        self._tau_lo = np.max([-lim.limit for lim in torque], axis=0) if torque else None
        self._tau_up = np.min([lim.limit for lim in torque], axis=0) if torque else None
        # one priority level without slacks: the QP on q̈ alone whenever no contact is active (see reduced)
        self._qdd_path = (
            len(self.builder.priorities) == 1
            and not self.builder.slacks
            and callable(getattr(self.solver, "solve_raw", None))
        )
        self._qdd: dict[Layout, QddQP] = {}
        # with active contacts or several levels: the QPs on [q̈; f] (see contact_qp)
        self._contact_path = callable(getattr(self.solver, "solve_raw", None)) and applies(self.builder)
        self._contact_qps: dict[Layout, ContactQP] = {}
        if self._qdd_path and not self.contacts:  # made now: its generated code is built or loaded here
            self._qdd_qp(self.builder.layout())
        elif self._contact_path and len(self.builder.priorities) > 1:  # likewise the first layout's, several levels
            self._contact_qp(self.builder.layout())
        self._pending: tuple[QddQP, QddStep] | tuple[ContactQP, ContactStep] | None = None
        self._last_solution: OSCSolution | None = None
        self._steps = 0
        self._kept: Counter[int] = Counter()
        self._kept_reason: dict[int, str] = {}

    @property
    def uses_generated_code(self) -> bool:
        """Whether the QP of the current layout (the tasks and contacts as they are) takes its data from generated
        code (see ``compile``): the q̈-only QP of one level without active contacts, the QPs on [q̈; f] with them
        or with several levels (with two levels, their optimum too where no inequality row is active)."""
        lay = self.builder.layout()
        if not lay.contacts and self._qdd_path:
            return self._qdd_qp(lay).generated is not None
        if self._contact_path:
            qp = self._contact_qp(lay)
            return qp.generated is not None and (qp.cascade is not None or len(qp.levels) != 2)
        return False

    def _contact_qp(self, lay: Layout) -> ContactQP:
        """The QPs on [q̈; f] of layout ``lay`` (made on first use, with their generated data where ``compile``
        asks for it)."""
        qp = self._contact_qps.get(lay)
        if qp is None:
            qp = self._contact_qps[lay] = ContactQP(self.builder, lay)
            qp.generated = self._generated_contact(qp, lay)
            if qp.generated is not None:
                self._compiled_check(qp.key)
                from armctl.controllers.osc import generated_cascade

                gen = qp.generated
                if generated_cascade.applies(qp):
                    make = lambda: generated_cascade.for_qp(qp, gen)  # noqa: E731
                    qp.cascade = FALLBACK.attempt(make, self.compile, stacklevel=3)
        return qp

    @property
    def last_solution(self) -> OSCSolution | None:
        """The :class:`OSCSolution` of the last control step (None before the first or after reset)."""
        pending = self._pending
        if pending is not None:
            self._pending = None
            self._last_solution = pending[0].solution(pending[1])  # type: ignore[arg-type]  # each QP its own step
        return self._last_solution

    @last_solution.setter
    def last_solution(self, sol: OSCSolution | None) -> None:
        self._pending = None
        self._last_solution = sol

    @property
    def priorities(self) -> list[int]:
        """The priority levels in solving order."""
        return list(self.builder.priorities)

    @property
    def fallback_counts(self) -> dict[str, int]:
        """QPs solved since :meth:`reset` (or the last :meth:`end_run`) by each stage of the solver chain
        ("active set", "warm", and the fallbacks "cold", "defaults", "second"); "failed" counts QPs none solved."""
        return dict(self.chain.counts)

    def build(self, t: float, q: Any, qd: Any, ref: Reference) -> StepQP:
        """The QPs of one control period at (q, q̇), built but not solved.

        Parameters
        ----------
        t : float
            Time [s].
        q, qd : array_like, shape (n,)
            Joint positions [rad] and velocities [rad/s] (m, m/s for a prismatic joint).
        ref : Reference
            The joint reference at t (what a :class:`~armctl.controllers.osc.PostureTask` follows).

        Returns
        -------
        StepQP
            The constraints and each level's task rows; ``.problem(k)`` is the
            :class:`~armctl.controllers.osc.QPProblem` of level k (without the rows that freeze the levels above,
            which depend on their solutions).

        Raises
        ------
        InvalidParameterError, ShapeError, NonFiniteError
            ``ref`` is not a Reference of n joints; q, q̇ or t is of the wrong size or not finite; a frame task has
            no target.
        """
        self.check_reference(ref)
        q, qd = vector(q, self.n, "q"), vector(qd, self.n, "qd")
        return self.builder.build(self.evaluator.evaluate(q, qd), scalar(t, "t"), ref)

    def solve(self, t: float, q: Any, qd: Any, ref: Reference) -> OSCSolution:
        """Build and solve one control period, as a call of the controller does.

        Parameters
        ----------
        t, q, qd, ref : float, array_like, array_like, Reference
            As for :meth:`build`.

        Returns
        -------
        OSCSolution
            The step's solution: x, q̈ [rad/s²], τ [N·m], contact forces [N], each task's residual and each
            level's QP (also ``last_solution`` afterwards).

        Raises
        ------
        InfeasibleError
            Level 0's QP has no feasible point: the error names the conflicting rows and by how much to relax them.
        SolverError
            No solver found a verified optimum of a feasible level-0 QP.
        InvalidParameterError, ShapeError, NonFiniteError
            Inputs as in :meth:`build`; a level whose weighted task targets ‖W^{1/2} b‖ exceed 1e9 (a target or gain
            out of scale).
        """
        self.check_reference(ref)
        q, qd = vector(q, self.n, "q"), vector(qd, self.n, "qd")
        self.compute(scalar(t, "t"), q, qd, ref)
        return self.last_solution  # type: ignore[return-value]  # compute() just set it

    def _qdd_qp(self, lay: Layout) -> QddQP:
        """The q̈-only QP of layout ``lay`` (made on first use), with its data from generated code where
        ``compile`` asks for it and the tasks and limits are built-in ones (see generated)."""
        qp = self._qdd.get(lay)
        if qp is None:
            qp = QddQP(self.builder, lay)
            qp.generated = self._generated_data(qp, lay)
            if qp.generated is not None:
                self._compiled_check(qp.key)
            self._qdd[lay] = qp
        return qp

    def _compiled_check(self, key: tuple[int, int, int, int]) -> None:
        """The chain's first-stage check compiled for the level-0 QPs of ``key`` (a QP's
        :meth:`SolverChain.key <armctl.controllers.osc.SolverChain.key>`), on the terms of ``compile``."""
        check = self.chain.check
        if isinstance(check, CompiledKKT):
            CHECK_FALLBACK.attempt(lambda: check.prepare(key[1:]), self.compile, stacklevel=5)

    def _generated_data(self, qp: QddQP, lay: Layout) -> Any:
        """The generated data of ``qp`` (a GeneratedQddData), or None: the NumPy path (``compile=False``, tasks or
        limits of the user's own, a backend whose model the generated code is not, a build that fails on
        ``"auto"``)."""
        mode = self.compile
        if mode is False or not all(type(lim) in _PLAIN_LIMITS for lim in lay.limits):
            return None
        from armctl.dynamics.pinocchio_backend import PinocchioDynamics

        # "auto" where the generated terms are the dynamics' own (Pinocchio's, rotors without gyroscopic coupling)
        if mode == "auto" and not isinstance(self.dynamics, PinocchioDynamics):
            return None
        from armctl.controllers.osc.generated import GeneratedQddData, supported  # CasADi, imported on use

        if not supported(qp.plan.tasks):
            return None
        variables = [lim.variable for lim in lay.limits]
        make = lambda: GeneratedQddData(  # noqa: E731
            self.dynamics, qp.plan.tasks, self.builder.regularization, variables, lay.constant_bounds
        )
        return FALLBACK.attempt(make, mode, stacklevel=4)

    def _generated_contact(self, qp: ContactQP, lay: Layout) -> Any:
        """The generated data of the contact QPs ``qp`` (a GeneratedContactData), or None: the NumPy path, on the
        terms of :meth:`_generated_data`."""
        mode = self.compile
        if mode is False or not all(type(lim) in _PLAIN_LIMITS for lim in lay.limits):
            return None
        from armctl.dynamics.pinocchio_backend import PinocchioDynamics

        if mode == "auto" and not isinstance(self.dynamics, PinocchioDynamics):
            return None
        from armctl.controllers.osc.generated_contact import GeneratedContactData, supported_contact

        levels = [plan.tasks for plan, _, _, _ in qp.levels]
        if not supported_contact(levels):
            return None
        variables = [lim.variable for lim in lay.limits]
        weights = [w for _, _, _, w in qp.levels]
        make = lambda: GeneratedContactData(  # noqa: E731
            self.dynamics, levels, lay.contacts, weights, variables, lay.constant_bounds
        )
        return FALLBACK.attempt(make, mode, stacklevel=4)

    def _qdd_step(self, lay: Layout, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        """One level without contact forces: the QP on q̈ alone (see reduced)."""
        qp = self._qdd.get(lay) or self._qdd_qp(lay)
        result = qp.run(q, qd, t, ref, self.chain, self.evaluator.evaluate)
        self._pending = (qp, result)
        sol = result.solution
        if sol is None:  # the unconstrained minimum, within every bound
            self.last_log = log = {"qp_iterations": 0, "qp_fallbacks": 0}
            self._task_log(log, t)
            return result.tau.copy()
        self.last_log = log = {"qp_iterations": sol.iterations, "qp_fallbacks": sol.fallbacks}
        self._task_log(log, t)
        up, lo = self._tau_up, self._tau_lo
        if up is None or lo is None:
            return result.tau.copy()
        tau = np.minimum(result.tau, up)  # a new array: the result's τ is the public solution's
        np.maximum(tau, lo, out=tau)
        return tau

    def _contact_step(self, lay: Layout, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        """The levels with active contacts, solved on [q̈; f] (see contact_qp)."""
        qp = self._contact_qps.get(lay) or self._contact_qp(lay)
        result = qp.run(q, qd, t, ref, self.chain, self.evaluator.evaluate)
        self._pending = (qp, result)
        if self._tau_up is not None and self._tau_lo is not None:
            tau = np.minimum(result.tau, self._tau_up)
            np.maximum(tau, self._tau_lo, out=tau)
        else:
            tau = result.tau.copy()
        iterations = fallbacks = 0
        for s in result.solutions:
            if s is not None:
                iterations += s.iterations
                fallbacks += s.fallbacks
        log: dict[str, Any] = {"qp_iterations": iterations, "qp_fallbacks": fallbacks}
        y = result.y
        for key, cy in qp.force_keys:
            log[key] = y[cy]
        status = result.status
        if len(status) > 1:
            log["level_status"] = tuple(status)
            for k, st in enumerate(status):
                if st != "solved":
                    self._kept[k] += 1
                    self._kept_reason[k] = st
        self._task_log(log, t)
        self.last_log = log
        return tau

    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        """τ of the verified optimum, clipped onto the torque limits (which it meets to the optimality check's
        tolerance).

        Parameters
        ----------
        t : float
            Time [s].
        q, qd : ndarray, shape (n,)
            Measured joint positions [rad] and velocities [rad/s], float64, finite (checked by ``__call__``).
        ref : Reference
            The joint reference at t.

        Returns
        -------
        ndarray, shape (n,)
            The joint torques τ [N·m] (N for a prismatic joint).

        Raises
        ------
        InfeasibleError, SolverError, InvalidParameterError
            As in :meth:`solve`. A lower priority level without a verified optimum raises nothing: it keeps the
            level above's solution, and ``last_log["level_status"]`` says so.
        """
        self._steps += 1
        self._pending = self._last_solution = None
        if self._qdd_path or self._contact_path:
            lay = self.builder.layout()
            if not lay.contacts and self._qdd_path:
                return self._qdd_step(lay, t, q, qd, ref)
            if self._contact_path:  # contacts, or several levels: the QPs on [q̈; f] (f of the active contacts)
                return self._contact_step(lay, t, q, qd, ref)
        state = self.evaluator.evaluate(q, qd)
        step = self.builder.build(state, t, ref)
        for lev in step.levels:
            check_level_scale(lev, state, t, ref)
        try:
            sol = solve_cascade(step, self.chain)
        except QPFailure as err:
            raise_unsolved(step.problem(0), err.attempts)
        self.last_solution = sol
        tau = sol.tau.clip(self._tau_lo, self._tau_up) if self._tau_up is not None else sol.tau.copy()
        log: dict[str, Any] = {"qp_iterations": sol.iterations, "qp_fallbacks": sol.fallbacks}
        for name, f in sol.forces.items():
            log[f"force[{name}]"] = f
        self._task_log(log, t)
        if len(sol.level_status) > 1:
            log["level_status"] = sol.level_status
            for k, status in enumerate(sol.level_status):
                if status != "solved":
                    self._kept[k] += 1
                    self._kept_reason[k] = status
        self.last_log = log
        return tau

    def verify_last_step(self) -> bool:
        """Run the optimality check of the last step's solution again, on every level. For tests and for timing
        what the check costs; a step never needs it.

        Returns
        -------
        bool
            True if it passes, as it did when the step accepted the solution.

        Raises
        ------
        InvalidParameterError
            There is no last step (before the first call, or after :meth:`reset`).
        """
        pending = self._pending
        if pending is not None:
            return pending[0].verify(pending[1], self.chain.check)  # type: ignore[arg-type]  # each QP its own step
        sol = self._last_solution
        if sol is None:
            raise InvalidParameterError("there is no last step to verify (call the controller first)")
        for k, qs in enumerate(sol.solutions):
            if qs is None:
                continue
            p = sol.problem(k)
            if not verified(p.arrays, qs.x[: p.nx], qs.y, qs.z):
                return False
        return True

    def run_summary(self) -> str | None:
        """What the solver chain had to do since :meth:`reset` (or the last :meth:`end_run`), in words.

        Returns
        -------
        str or None
            The fallbacks by stage and the lower levels that kept the level above's solution; None if every QP
            was verified by a stage before the fallbacks.
        """
        counts = self.chain.counts
        parts = []
        taken = {stage: counts[stage] for stage in ("cold", "defaults", "second") if counts[stage]}
        if taken:
            what = {"cold": "a cold start", "defaults": "the solver's default settings", "second": "the second solver"}
            shown = ", ".join(f"{n} by {what[stage]}" for stage, n in taken.items())
            total = sum(taken.values())
            parts.append(
                f"the warm-started solution failed the optimality check (or the solver failed) and the QP was "
                f"re-solved {total} time{'s' if total > 1 else ''}: {shown}"
            )
        for k, n in sorted(self._kept.items()):
            parts.append(
                f"priority level {k} had no verified optimum on {n} steps and kept the solution of the level above "
                f"(last: {self._kept_reason[k]}); OSCSolution.diagnose({k}) names conflicting rows"
            )
        if not parts:
            return None
        return f"OperationalSpaceQP over {self._steps} control steps: " + "; ".join(parts)

    def _forget_run(self) -> None:
        self.chain.counts.clear()
        self._kept.clear()
        self._kept_reason.clear()
        self._steps = 0

    def reset(self) -> None:
        """Forget the warm starts, the last solution and the run's counts."""
        super().reset()
        self.chain.reset()
        self.last_solution = None
        self._forget_run()
