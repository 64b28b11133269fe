"""`ClosedFormOSC`: Khatib's operational-space controller in closed form, the baseline the QP is compared with.

With the task (J, J̇q̇, desired task acceleration ẍ*) of one :class:`MotionTask`, a posture acceleration q̈₀
(PD on the joint reference, or zero), and the operational-space terms of
:func:`armctl.dynamics.operational_space.operational_space_terms` at the measured state,

    Λ = (J M⁻¹ Jᵀ)⁻¹,   J̄ = M⁻¹ Jᵀ Λ,   μ = J̄ᵀ C q̇ − Λ J̇ q̇,   p = J̄ᵀ g
    F = Λ ẍ* + μ + p                        the task force
    τ = Jᵀ F + Nᵀ (M q̈₀ + C q̇ + g) + τ_f,   N = I − J̄ J   (the dynamically consistent null space)
      = Jᵀ Λ (ẍ* − J̇ q̇ − J q̈₀) + M q̈₀ + C q̇ + g + τ_f

so that, with an exact model, J q̈ + J̇ q̇ = ẍ* and the posture acts only in the null space. No limits: near a
singularity Λ grows without bound and so does τ — which is what this baseline is here to show.

At (or next to) a singular configuration Λ does not exist (or its condition number is beyond what floats
resolve): where cond Λ exceeds ``condition_limit`` κ, the controller uses the damped inverse
Λ = (J M⁻¹ Jᵀ + δ² I)⁻¹ with δ² = μ_max/κ − μ_min (μ the eigenvalues of J M⁻¹ Jᵀ; an upper bound of
μ_max/κ where J M⁻¹ Jᵀ is singular outright), so that cond(J M⁻¹ Jᵀ + δ² I) ≤ κ: τ stays finite, and the task
is no longer met along the lost direction. δ² is in ``last_log["damping"]`` (0 on a regular step), and
:meth:`ClosedFormOSC.end_run` warns once per run (:class:`~armctl.errors.SingularityWarning`) with the steps
that needed it. The default κ = 1e12 is reached when the task Jacobian's σ_min/σ_max is near 1e-6 (the
tolerance of :meth:`armctl.Dynamics.operational_space_model`): the torque spike near a singularity is kept.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
from scipy.linalg import lapack

from armctl._checks import FloatArray, scalar
from armctl.controllers.base import Controller
from armctl.controllers.osc.state import ModelEvaluator, ModelState
from armctl.controllers.osc.tasks.base import MotionTask
from armctl.controllers.osc.tasks.posture import PostureTask
from armctl.dynamics.base import Dynamics
from armctl.dynamics.operational_space import operational_space_terms
from armctl.errors import InvalidParameterError, SingularityWarning
from armctl.reference import Reference

#: the largest condition number of Λ used undamped (see the module)
CONDITION_LIMIT = 1e12


class ClosedFormOSC(Controller):
    """Closed-form operational-space control of ``task`` (a frame task), with an optional ``posture`` task
    in the dynamically consistent null space; ``condition_limit`` κ ≥ 1: the largest condition number of Λ used
    as it is, beyond which Λ is damped (see the module). ``last_log``: the trace of Λ (an upper bound of its
    largest eigenvalue) and the damping δ² of the step."""

    def __init__(
        self,
        dynamics: Dynamics,
        task: MotionTask,
        posture: PostureTask | None = None,
        condition_limit: float = CONDITION_LIMIT,
    ) -> None:
        super().__init__(dynamics)
        if not isinstance(task, MotionTask) or isinstance(task, PostureTask):
            raise InvalidParameterError(f"task must be a frame MotionTask, got {type(task).__name__}", value=task)
        if posture is not None and not isinstance(posture, PostureTask):
            raise InvalidParameterError(f"posture must be a PostureTask, got {type(posture).__name__}", value=posture)
        self.condition_limit = scalar(condition_limit, "condition_limit", positive=True)
        if self.condition_limit < 1.0:
            raise InvalidParameterError(
                f"condition_limit is a condition number, at least 1; got {condition_limit}", value=condition_limit
            )
        self.evaluator = ModelEvaluator(dynamics)
        task.check(self.evaluator, self.n, {})
        if posture is not None:
            posture.check(self.evaluator, self.n, {})
        self.task = task
        self.posture = posture
        self._steps = 0
        self._damped: list[float] = []  # the damping of the damped steps since the run began

    def operational_space_terms(
        self, state: ModelState, jacobian: FloatArray, drift: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, float]:
        """(Λ, J̄, μ, p, δ²) of the task at ``state`` (see the module): undamped (δ² = 0) unless cond Λ exceeds
        ``condition_limit``. Raises the kernel's named error if M is not positive definite."""
        q, mass = state.q, state.mass
        kernel = self.dynamics.kernel  # type: ignore[union-attr]
        gravity = kernel.gravity(q)
        coriolis = state.bias - gravity  # C q̇
        try:
            terms = operational_space_terms(mass, jacobian, drift, coriolis, gravity)
        except np.linalg.LinAlgError:  # M not positive definite, or J M⁻¹ Jᵀ singular outright
            terms, lam = None, None
        else:
            lam, _, info = lapack.dsyev(terms[0], compute_v=0)  # Λ's eigenvalues, ascending: 1 / J M⁻¹ Jᵀ's
            if info:
                lam = None
        if lam is not None and np.isfinite(lam).all() and 0.0 < lam[-1] <= self.condition_limit * lam[0]:
            return (*terms, 0.0)  # type: ignore[misc]
        if lam is not None and np.isfinite(lam).all() and lam[0] > 0.0:
            damping = 1.0 / (self.condition_limit * lam[0]) - 1.0 / lam[-1]  # μ_max/κ − μ_min
        else:
            try:  # μ_max ≤ trace(J M⁻¹ Jᵀ) ≤ ‖J‖²_F / λ_min(M)
                smallest = float(np.linalg.eigvalsh(mass)[0])
            except np.linalg.LinAlgError:
                smallest = 0.0
            if not smallest > 0.0:
                raise kernel.nonfinite_error(q)  # names the mass matrix that is not positive definite
            damping = float(np.sum(jacobian * jacobian)) / (smallest * self.condition_limit)
        try:
            lam_d, jbar, mu, p = operational_space_terms(mass, jacobian, drift, coriolis, gravity, damping)
        except np.linalg.LinAlgError:
            raise kernel.nonfinite_error(q) from None
        return lam_d, jbar, mu, p, damping

    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        state = self.evaluator.evaluate(q, qd)
        J, drift, xdd = self.task.desired_acceleration(state, t, ref)
        if J is None:  # pragma: no cover - frame tasks always have a Jacobian
            raise InvalidParameterError("the task needs a Jacobian", value=self.task)
        lam, jbar, mu, p, damping = self.operational_space_terms(state, J, drift)
        joint = state.bias.copy()  # M q̈₀ + C q̇ + g, the joint-space torque the null space keeps
        if self.posture is not None:
            joint += state.mass @ self.posture.desired_acceleration(state, t, ref)[2]
        tau = J.T @ (lam @ xdd + mu + p - jbar.T @ joint) + joint  # Jᵀ F + Nᵀ (M q̈₀ + C q̇ + g)
        if state.friction is not None:
            tau += state.friction
        self._steps += 1
        if damping:
            self._damped.append(damping)
        log: dict[str, Any] = {"lambda_trace": float(lam.trace()), "damping": damping}  # trace ≥ largest eigenvalue
        self.last_log = log
        return tau

    def run_summary(self) -> str | None:
        """The steps since :meth:`reset` (or the last :meth:`end_run`) on which Λ was damped, in words; None if
        none was."""
        if not self._damped:
            return None
        return (
            f"ClosedFormOSC over {self._steps} control steps: Λ = (J M⁻¹ Jᵀ)⁻¹ was damped on {len(self._damped)} "
            f"(its condition number beyond {self.condition_limit:g}: the task Jacobian at or next to a singular "
            f"configuration; damping δ² up to {max(self._damped):.3g}), and the task was not met along the lost "
            "direction there; last_log['damping'] gives δ² per step"
        )

    def end_run(self) -> str | None:
        """End of a run: warn once (:class:`~armctl.errors.SingularityWarning`) with :meth:`run_summary` if Λ was
        damped, and start counting afresh; returns the summary. :func:`armctl.sim.simulate` calls it after the
        last step; call it after a loop of your own."""
        msg = self.run_summary()
        if msg is not None:
            warnings.warn(msg, SingularityWarning, stacklevel=2)
        self._steps = 0
        self._damped = []
        return msg

    def reset(self) -> None:
        """Forget the run's counts."""
        super().reset()
        self._steps = 0
        self._damped = []
