"""`ClosedFormOSC`: Khatib's operational-space controller in closed form, the baseline the QP is compared with.

With the task (J, J̇q̇, desired task acceleration ẍ*) of one :class:`MotionTask` and a posture acceleration
q̈₀ (PD on the joint reference, or zero):

    Λ = (J M⁻¹ Jᵀ)⁻¹                       task-space inertia
    J̄ = M⁻¹ Jᵀ Λ,   N = I − J̄ J            dynamically consistent inverse and null space
    τ = Jᵀ Λ (ẍ* − J̇ q̇) + Nᵀ M q̈₀ + C q̇ + g + τ_f
      = Jᵀ Λ (ẍ* − J̇ q̇ − J q̈₀) + M q̈₀ + C q̇ + g + τ_f

so that, with an exact model, J q̈ + J̇ q̇ = ẍ* and the posture acts only in the null space. No limits: near a
singularity Λ grows without bound and so does τ — which is what this baseline is here to show.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from armctl._checks import FloatArray
from armctl.controllers.base import Controller
from armctl.controllers.osc.state import ModelEvaluator
from armctl.controllers.osc.tasks.base import MotionTask
from armctl.controllers.osc.tasks.posture import PostureTask
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError
from armctl.references import Reference


class ClosedFormOSC(Controller):
    """Closed-form operational-space control of ``task`` (a frame task), with an optional ``posture`` task
    in the dynamically consistent null space. ``last_log``: the trace of Λ (an upper bound of its largest
    eigenvalue)."""

    dynamics: Dynamics  # given to __init__, never None

    def __init__(self, dynamics: Dynamics, task: MotionTask, posture: PostureTask | None = None) -> None:
        super().__init__(dynamics)
        if not isinstance(task, MotionTask) or isinstance(task, PostureTask):
            raise InvalidParameterError(f"task must be a frame MotionTask, got {type(task).__name__}", value=task)
        if posture is not None and not isinstance(posture, PostureTask):
            raise InvalidParameterError(f"posture must be a PostureTask, got {type(posture).__name__}", value=posture)
        self.evaluator = ModelEvaluator(dynamics)
        task.check(self.evaluator, self.n, {})
        if posture is not None:
            posture.check(self.evaluator, self.n, {})
        self.task = task
        self.posture = posture

    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        state = self.evaluator.evaluate(q, qd)
        M = state.mass
        J, drift, xdd = self.task.desired_acceleration(state, t, ref)
        if J is None:  # pragma: no cover - frame tasks always have a Jacobian
            raise InvalidParameterError("the task needs a Jacobian", value=self.task)
        try:
            minv_jt = np.linalg.solve(M, J.T)
        except np.linalg.LinAlgError:
            raise self.dynamics.kernel.nonfinite_error(q) from None  # names M
        lam_inv = J @ minv_jt
        try:
            lam = np.linalg.inv(lam_inv)
        except np.linalg.LinAlgError:  # exactly singular: the pseudo-inverse (still unbounded nearby)
            lam = np.linalg.pinv(lam_inv)
        qdd0 = np.zeros(self.n)
        if self.posture is not None:
            qdd0 = self.posture.desired_acceleration(state, t, ref)[2]
        tau = J.T @ (lam @ (xdd - drift - J @ qdd0)) + M @ qdd0 + state.bias
        if state.friction is not None:
            tau += state.friction
        log: dict[str, Any] = {"lambda_trace": float(lam.trace())}  # ≥ the largest eigenvalue of Λ
        self.last_log = log
        return tau
