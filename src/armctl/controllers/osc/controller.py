"""`OperationalSpaceQP`: operational-space control as one QP (or a cascade of QPs) per control period.

Every period, at the measured (q, q̇):

    min over x = [q̈, τ, f]   Σ_levels-in-order  ½ Σ_i ‖W_i^{1/2}(J_i x_i − b_i)‖²
    s.t.  M q̈ + C q̇ + g + τ_f − Σ_c J_cᵀ f_c = τ       (the controller's own model)
          contact kinematics, friction cones, torque / position (viability) / velocity limits

and τ goes to the arm. Task targets:

* frame tasks (:class:`FramePositionTask`, :class:`FrameOrientationTask`, :class:`FramePoseTask`) take a
  constant target through ``task.set_target(...)`` or a trajectory through ``task.set_trajectory(fn)``,
  ``fn(t) -> (value, velocity, acceleration)``; either may be changed between periods;
* :class:`PostureTask` follows the joint reference ``ref`` handed to the controller (unless fixed);
* :class:`ContactForceTask` takes a force vector or a callable of t.

Contacts are switched with ``contact.active``. The QP of a period can be looked at before (or instead of)
solving it: :meth:`OperationalSpaceQP.build` returns the :class:`~armctl.controllers.osc.build.StepQP`,
``.problem(k)`` the :class:`~armctl.controllers.osc.problem.QPProblem` (H, g, A, b, C, l, u) of level k.

Every QP is solved by a :class:`~armctl.controllers.osc.chain.SolverChain`: τ comes only from a solution verified
against the QP's optimality conditions (:mod:`~armctl.controllers.osc.optimality`). Its first stage is DAQP (a dual
active-set solver in C) started from the last step's active set; a QP whose answer fails the check goes on to the
primary solver (ProxQP: warm start, cold start, default settings) and a second solver. With one priority level and
no active contact the QP is solved on q̈ alone (:mod:`~armctl.controllers.osc.reduced`: the same optimum), and on
``Dynamics(model, compile=True)`` its data come from one call of generated C code
(:mod:`~armctl.controllers.osc.generated`) when its tasks and limits are built-in ones. Each step's fallbacks are
in ``last_log["qp_fallbacks"]``; :meth:`end_run` (which :func:`armctl.sim.simulate` calls) warns once with what
happened during the run and how often.
"""

from __future__ import annotations

import warnings
from collections import Counter
from collections.abc import Sequence
from typing import Any

import numpy as np

from armctl._checks import FloatArray, instances, scalar, vector
from armctl.controllers.base import Controller
from armctl.controllers.osc.build import QPBuilder, StepQP
from armctl.controllers.osc.chain import QPFailure, SolverChain
from armctl.controllers.osc.contact import Contact
from armctl.controllers.osc.diagnose import raise_unsolved
from armctl.controllers.osc.hierarchy import OSCSolution, solve_cascade
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
from armctl.controllers.osc.scale import check_level_scale
from armctl.controllers.osc.solve import make_second_solver, make_solver
from armctl.controllers.osc.state import ModelEvaluator
from armctl.controllers.osc.tasks.base import Task
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError, SolverWarning
from armctl.reference import Reference

#: the limits whose bounds read only q and q̇ of a step's state (the generated path gives them no more)
_PLAIN_LIMITS = (TorqueLimit, JointPositionLimit, JointVelocityLimit, AccelerationLimit)


def default_limits(dt: float = 1e-3) -> list[Limit]:
    """Torque limits, joint position limits (viability) and joint velocity limits, for control period dt [s]."""
    return [TorqueLimit(), JointPositionLimit(dt), JointVelocityLimit(dt)]


def _unique(items: Sequence[Any], kind: str) -> None:
    names = [it.name for it in items]
    dup = sorted({nm for nm in names if names.count(nm) > 1})
    if dup:
        raise InvalidParameterError(f"{kind} names must be unique; repeated: {dup} (give name=...)", value=dup)


class OperationalSpaceQP(Controller):
    """Operational-space QP controller.

    dynamics: the controller's model (pinocchio backend: one-pass model terms; any backend works).
    tasks: :class:`~armctl.controllers.osc.tasks.Task` objects; ``task.priority`` (0 first) orders levels
    strictly, ``task.weight`` trades tasks off inside a level. limits: :class:`~armctl.controllers.osc.limits.Limit`
    objects (default :func:`default_limits` with ``dt``). contacts: :class:`Contact` objects. solver:
    "proxsuite" (dense ProxQP, warm-started), "qpsolvers:NAME", or an object with ``solve``/``reset`` (and
    ``solve_raw``, see :mod:`~armctl.controllers.osc.solve`). fallback_solver: the last stage of the solver
    chain — "active-set" (:class:`~armctl.controllers.osc.active_set.DualActiveSetSolver`), "qpsolvers:NAME",
    an object with ``solve_raw`` and ``reset``, or None (no second solver). regularization: ε of ½ε‖x‖² in
    every level. slacks: task rows as constraints with slack variables. dt: control period [s] for the default
    limits.
    """

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
    ) -> None:
        if not isinstance(dynamics, Dynamics):
            raise InvalidParameterError(
                f"dynamics must be an armctl.Dynamics, got {type(dynamics).__name__}", value=dynamics
            )
        super().__init__(dynamics)
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
        self.limits = tuple(limits)
        self.contacts = contacts
        self.solver = make_solver(solver)
        self.chain = SolverChain(self.solver, make_second_solver(fallback_solver))
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
        if self._qdd_path and not self.contacts:  # made now: on compile=True its code is built or loaded here
            self._qdd_qp(self.builder.layout())
        self._pending: tuple[QddQP, QddStep] | None = None
        self._last_solution: OSCSolution | None = None
        self._steps = 0
        self._kept: Counter[int] = Counter()
        self._kept_reason: dict[int, str] = {}

    @property
    def last_solution(self) -> OSCSolution | None:
        """The :class:`OSCSolution` of the last control step (None before the first or after reset)."""
        pending = self._pending
        if pending is not None:
            self._pending = None
            qp, result = pending
            step, mapped = qp.public(result)
            self._last_solution = OSCSolution(step, mapped.x, (mapped,), ("solved",), None, [None])
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
        """QPs solved since :meth:`reset` by each stage of the solver chain ("active set", "warm", and the
        fallbacks "cold", "defaults", "second"); "failed" counts QPs none solved."""
        return dict(self.chain.counts)

    def build(self, t: float, q: Any, qd: Any, ref: Reference) -> StepQP:
        """The QPs of one control period at (q, q̇), not solved (``.problem(k)`` for level k)."""
        self.check_reference(ref)
        q, qd = vector(q, self.n, "q"), vector(qd, self.n, "qd")
        return self.builder.build(self.evaluator.evaluate(q, qd), scalar(t, "t"), ref)

    def solve(self, t: float, q: Any, qd: Any, ref: Reference) -> OSCSolution:
        """Build and solve one control period; raises InfeasibleError naming the conflicting rows."""
        self.check_reference(ref)
        q, qd = vector(q, self.n, "q"), vector(qd, self.n, "qd")
        self.compute(scalar(t, "t"), q, qd, ref)
        return self.last_solution  # type: ignore[return-value]

    def _qdd_qp(self, lay: Layout) -> QddQP:
        """The q̈-only QP of layout ``lay`` (made on first use), with its data from generated code on
        ``Dynamics(model, compile=True)`` when the tasks and limits are built-in ones (see generated)."""
        qp = self._qdd.get(lay)
        if qp is None:
            qp = QddQP(self.builder, lay)
            if getattr(self.dynamics, "compiled", False) and all(type(lim) in _PLAIN_LIMITS for lim in lay.limits):
                from armctl.controllers.osc.generated import GeneratedQddData, supported  # CasADi: on compile=True

                if supported(qp.plan.tasks):
                    qp.generated = GeneratedQddData(self.dynamics, qp.plan.tasks, self.builder.regularization)
            self._qdd[lay] = qp
        return qp

    def _qdd_step(self, lay: Layout, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        """One level without contact forces: the QP on q̈ alone (see reduced)."""
        qp = self._qdd.get(lay) or self._qdd_qp(lay)
        gen = qp.generated
        if gen is not None:
            result = qp.step_generated(gen, q, qd, t, ref, self.chain, self.evaluator.evaluate)
        else:
            result = qp.step(self.evaluator.evaluate(q, qd), t, ref, self.chain)
        self._pending = (qp, result)
        sol = result.solution
        tau = result.tau.copy()
        if sol is None:  # the unconstrained minimum, within every bound
            self.last_log = {"qp_iterations": 0, "qp_fallbacks": 0}
            return tau
        self.last_log = {"qp_iterations": sol.iterations, "qp_fallbacks": sol.fallbacks}
        if self._tau_up is not None:
            np.minimum(tau, self._tau_up, out=tau)
            np.maximum(tau, self._tau_lo, out=tau)
        return tau

    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        """τ of the verified optimum (clipped onto the torque limits, which it meets to the optimality check's
        tolerance)."""
        self._steps += 1
        self._pending = self._last_solution = None
        if self._qdd_path:
            lay = self.builder.layout()
            if not lay.contacts:
                return self._qdd_step(lay, t, q, qd, ref)
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
        if len(sol.level_status) > 1:
            log["level_status"] = sol.level_status
            for k, status in enumerate(sol.level_status):
                if status != "solved":
                    self._kept[k] += 1
                    self._kept_reason[k] = status
        self.last_log = log
        return tau

    def verify_last_step(self) -> bool:
        """Run the optimality check of the last step's solution again (every level): True if it passes, as it
        did when the step accepted it. For tests and for timing what the check costs; a step never needs it."""
        pending = self._pending
        if pending is not None:
            return pending[0].verify(pending[1])
        sol = self._last_solution
        if sol is None:
            raise InvalidParameterError("there is no last step to verify (call the controller first)")
        for k, qs in enumerate(sol.solutions):
            if qs is None:
                continue
            p = sol.problem(k)
            if not verified((p.H, p.g, p.A, p.b, p.C, p.l, p.u), qs.x[: p.nx], qs.y, qs.z):
                return False
        return True

    def run_summary(self) -> str | None:
        """What the solver chain had to do since :meth:`reset` (fallbacks by stage, lower levels kept from
        the level above), in words; None if every QP was verified at the first try of a stage before the
        fallbacks."""
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

    def end_run(self) -> str | None:
        """End of a run: warn once (:class:`~armctl.errors.SolverWarning`) with :meth:`run_summary` if there is
        anything to report, and start counting afresh; returns the summary. :func:`armctl.sim.simulate` calls
        it after the last step; call it after a loop of your own."""
        msg = self.run_summary()
        if msg is not None:
            warnings.warn(msg, SolverWarning, stacklevel=2)
        self.chain.counts.clear()
        self._kept.clear()
        self._kept_reason.clear()
        self._steps = 0
        return msg

    def reset(self) -> None:
        """Forget the warm starts, the last solution and the run's counts."""
        super().reset()
        self.chain.reset()
        self.last_solution = None
        self._kept.clear()
        self._kept_reason.clear()
        self._steps = 0
