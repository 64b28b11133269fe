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
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from armctl._checks import FloatArray, instances, scalar, vector
from armctl.controllers.base import Controller
from armctl.controllers.osc.build import QPBuilder, StepQP, level_cost
from armctl.controllers.osc.contact import Contact
from armctl.controllers.osc.hierarchy import OSCSolution, solve_cascade
from armctl.controllers.osc.limits import JointPositionLimit, JointVelocityLimit, Limit, TorqueLimit
from armctl.controllers.osc.solve import QPSolution, make_solver
from armctl.controllers.osc.state import ModelEvaluator
from armctl.controllers.osc.tasks.base import Task
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError
from armctl.reference import Reference


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
    "proxsuite" (dense ProxQP, warm-started), "qpsolvers:NAME", or an object with ``solve``/``reset``.
    regularization: ε of ½ε‖x‖² in every level. slacks: task rows as constraints with slack variables.
    dt: control period [s] for the default limits.
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
        self.builder = QPBuilder(
            dynamics.model, tasks, limits, contacts, scalar(regularization, "regularization", positive=True), slacks
        )
        torque = [lim for lim in limits if isinstance(lim, TorqueLimit)]
        self._tau_lo = np.max([-lim.limit for lim in torque], axis=0) if torque else None
        self._tau_up = np.min([lim.limit for lim in torque], axis=0) if torque else None
        self.last_solution = None
        # one priority level without slacks: the step goes straight from the task rows to the solver, and
        # last_solution is put together only when asked for (see _solve_single)
        self._single_level = len(self.builder.priorities) == 1 and not self.builder.slacks

    #: the last single-level step's parts (layout, A, b, l, u, task rows, solver result), until last_solution
    #: is asked for (class defaults: a controller pickled before these existed takes the generic path)
    _pending: tuple[Any, ...] | None = None
    _last_solution: OSCSolution | None = None
    _single_level = False

    @property
    def last_solution(self) -> OSCSolution | None:
        """The :class:`OSCSolution` of the last control step (None before the first or after reset)."""
        pending = self._pending
        if pending is not None:
            self._pending = None
            self._last_solution = self._single_solution(*pending)
        return self._last_solution

    @last_solution.setter
    def last_solution(self, sol: OSCSolution | None) -> None:
        self._pending = None
        self._last_solution = sol

    @staticmethod
    def _single_step(lay: Any, A: FloatArray, b: FloatArray, lo: FloatArray, up: FloatArray, lev: Any) -> StepQP:
        return StepQP(lay, A, b, lo, up, [lev], lay.regularization, False)

    def _single_solution(
        self, lay: Any, A: FloatArray, b: FloatArray, lo: FloatArray, up: FloatArray, lev: Any, sol: QPSolution
    ) -> OSCSolution:
        return OSCSolution(
            self._single_step(lay, A, b, lo, up, lev), sol.x[: lay.nx], (sol,), ("solved",), None, [None]
        )

    def _solve_single(
        self, t: float, q: FloatArray, qd: FloatArray, ref: Reference, raw: Any
    ) -> tuple[QPSolution, Any]:
        """One priority level, no slacks, a solver with ``solve_raw``: the same QP as :meth:`build` and
        :func:`solve_cascade` give, without their intermediate objects (which cost about a tenth of a step on the
        Panda); the parts are kept for :attr:`last_solution`. Returns the solver's result and the layout."""
        bld = self.builder
        state = self.evaluator.evaluate(q, qd)
        lay = bld.layout()
        A, b, lo, up = bld.constraints(lay, state)
        lev = bld.level(bld.plans(lay)[0], state, t, ref)
        H, g = level_cost(lev, lay.reg_matrix)
        sol = raw((H, g, A, b, lay.C, lo, up), 0, lambda: self._single_step(lay, A, b, lo, up, lev).problem(0))
        self._pending = (lay, A, b, lo, up, lev, sol)
        return sol, lay

    @property
    def priorities(self) -> list[int]:
        """The priority levels in solving order."""
        return list(self.builder.priorities)

    def build(self, t: float, q: Any, qd: Any, ref: Reference) -> StepQP:
        """The QPs of one control period at (q, q̇), not solved (``.problem(k)`` for level k)."""
        self.check_reference(ref)
        q, qd = vector(q, self.n, "q"), vector(qd, self.n, "qd")
        return self.builder.build(self.evaluator.evaluate(q, qd), scalar(t, "t"), ref)

    def solve(self, t: float, q: Any, qd: Any, ref: Reference) -> OSCSolution:
        """Build and solve one control period; raises InfeasibleError naming the conflicting rows."""
        self.check_reference(ref)
        q, qd = vector(q, self.n, "q"), vector(qd, self.n, "qd")
        return self._solve(scalar(t, "t"), q, qd, ref)

    def _solve(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> OSCSolution:
        raw = getattr(self.solver, "solve_raw", None) if self._single_level else None
        if raw is not None:
            self._solve_single(t, q, qd, ref, raw)
            return self.last_solution  # type: ignore[return-value]
        step = self.builder.build(self.evaluator.evaluate(q, qd), t, ref)
        sol = solve_cascade(step, self.solver)
        self.last_solution = sol
        return sol

    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        """τ = the τ block of the QP solution (clipped onto the torque limits, which it meets to the solver's
        tolerance)."""
        raw = getattr(self.solver, "solve_raw", None) if self._single_level else None
        if raw is not None:  # the common case, without the solution object (see _solve_single)
            qsol, lay = self._solve_single(t, q, qd, ref, raw)
            x, n = qsol.x, self.n
            tau = x[n : 2 * n].clip(self._tau_lo, self._tau_up) if self._tau_up is not None else x[n : 2 * n].copy()
            log: dict[str, Any] = {"qp_iterations": qsol.iterations}
            for c in lay.contacts:
                log[f"force[{c.name}]"] = x[lay.variables[c.name]]
            self.last_log = log
            return tau
        sol = self._solve(t, q, qd, ref)
        tau = sol.tau.clip(self._tau_lo, self._tau_up) if self._tau_up is not None else sol.tau.copy()
        log = {"qp_iterations": sol.iterations}
        for name, f in sol.forces.items():
            log[f"force[{name}]"] = f
        if len(sol.level_status) > 1:
            log["level_status"] = sol.level_status
        self.last_log = log
        return tau

    def reset(self) -> None:
        """Forget the warm start and the last solution."""
        super().reset()
        self.solver.reset()
        self.last_solution = None
