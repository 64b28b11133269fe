"""`ClosedFormOSC`: Khatib's operational-space controller in closed form, the baseline the QP is compared with.

The law, and the damped inverse it takes at or next to a singular configuration, are described with the class.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.linalg import lapack

from armctl._checks import FloatArray, scalar
from armctl.controllers.base import Controller
from armctl.controllers.osc.run_report import RunReport
from armctl.controllers.osc.state import ModelEvaluator, ModelState
from armctl.controllers.osc.task_errors import FrameTaskLog
from armctl.controllers.osc.tasks.base import MotionTask
from armctl.controllers.osc.tasks.posture import PostureTask
from armctl.dynamics.base import Dynamics
from armctl.dynamics.operational_space import operational_space_terms
from armctl.errors import InvalidParameterError, SingularityWarning
from armctl.references import Reference

#: the largest condition number of Λ used undamped (see ClosedFormOSC)
CONDITION_LIMIT = 1e12


class ClosedFormOSC(RunReport, Controller):
    """Closed-form operational-space control (Khatib) of one frame task, with an optional posture task in the
    dynamically consistent null space. No limits: near a singularity Λ grows without bound and so does τ — which
    is what this baseline is here to show.

    Parameters
    ----------
    dynamics : Dynamics
        The controller's model: M(q), C(q, q̇) q̇, g(q), τ_f(q̇) and the frame's kinematics.
    task : MotionTask
        The operational-space task: a frame task (:class:`~armctl.controllers.osc.FramePositionTask`,
        :class:`~armctl.controllers.osc.FrameOrientationTask`, :class:`~armctl.controllers.osc.FramePoseTask`, or
        a motion task of your own), not a posture task. Its gains K_p [1/s²] and K_d [1/s] make ẍ*.
    posture : PostureTask, optional
        Gives the posture acceleration q̈₀ (its PD law on the joint reference); None: q̈₀ = 0.
    condition_limit : float, optional
        κ ≥ 1: the largest condition number of Λ used as it is, beyond which Λ is damped (see Notes).

    Raises
    ------
    InvalidParameterError
        ``task`` is not a frame motion task, ``posture`` not a PostureTask, ``condition_limit`` below 1.
    UnknownNameError
        The task's frame is not one of the model's.
    ShapeError
        The posture task is sized for another number of joints.

    Notes
    -----
    With the task (J, J̇q̇, desired task acceleration ẍ*), the posture acceleration q̈₀ and the operational-space
    terms of :func:`armctl.dynamics.operational_space.operational_space_terms` at the measured state::

        Λ = (J M⁻¹ Jᵀ)⁻¹,   J̄ = M⁻¹ Jᵀ Λ,   μ = J̄ᵀ C q̇ − Λ J̇ q̇,   p = J̄ᵀ g
        F = Λ ẍ* + μ + p                        the task force
        τ = Jᵀ F + Nᵀ (M q̈₀ + C q̇ + g) + τ_f,   N = I − J̄ J   (the dynamically consistent null space)
          = Jᵀ Λ (ẍ* − J̇ q̇ − J q̈₀) + M q̈₀ + C q̇ + g + τ_f

    so that, with an exact model, J q̈ + J̇ q̇ = ẍ* and the posture acts only in the null space.

    At (or next to) a singular configuration Λ does not exist (or its condition number is beyond what floats
    resolve): where cond Λ exceeds ``condition_limit`` κ, the controller uses the damped inverse
    Λ = (J M⁻¹ Jᵀ + δ² I)⁻¹ with δ² = μ_max/κ − μ_min (μ the eigenvalues of J M⁻¹ Jᵀ; where J M⁻¹ Jᵀ is singular
    outright, ‖J‖²_F / (λ_min(M) κ), an upper bound of μ_max/κ), so that cond(J M⁻¹ Jᵀ + δ² I) is at most
    κ + 1 (κ + 1 − κ μ_min/μ_max with the first form): τ stays finite, and the task is no longer met along
    the lost direction. The default κ = 1e12 is reached when the task Jacobian's σ_min/σ_max is near 1e-6 (the
    tolerance of :meth:`armctl.Dynamics.operational_space_model`): the torque spike near a singularity is kept.

    ``last_log`` holds ``"lambda_trace"``, the trace of Λ (an upper bound of its largest eigenvalue), and
    ``"damping"``, the step's δ² (0 on a regular step), and a built-in frame task's target and weights, from
    which the run's result computes the task's errors (see :mod:`~armctl.controllers.osc.task_errors`);
    :meth:`end_run` warns once per run (:class:`~armctl.errors.SingularityWarning`) with the steps that needed
    the damping.
    """

    dynamics: Dynamics  # given to __init__, never None
    run_warning = SingularityWarning

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
        self._task_log = FrameTaskLog((task,))  # what each step logs of the task
        self.posture = posture
        self._steps = 0
        self._damped: list[float] = []  # the damping of the damped steps since the run began

    def operational_space_terms(
        self, state: ModelState, jacobian: FloatArray, drift: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, float]:
        """The operational-space terms of the task at ``state``, undamped unless cond Λ exceeds
        ``condition_limit`` (see the class's Notes).

        Parameters
        ----------
        state : ModelState
            The model terms at the measured (q, q̇): M, C q̇ + g.
        jacobian : ndarray, shape (m, n)
            The task Jacobian J.
        drift : ndarray, shape (m,)
            J̇ q̇ [the task's units per s²].

        Returns
        -------
        lam : ndarray, shape (m, m)
            Λ, the task-space inertia (damped if need be) [kg for position rows, kg·m² for rotation rows].
        jbar : ndarray, shape (n, m)
            J̄ = M⁻¹ Jᵀ Λ, the dynamically consistent inverse of J.
        mu : ndarray, shape (m,)
            μ = J̄ᵀ C q̇ − Λ J̇ q̇, the task-space Coriolis and centrifugal force [N or N·m].
        p : ndarray, shape (m,)
            p = J̄ᵀ g, the task-space gravity force [N or N·m].
        damping : float
            δ² ≥ 0 [the units of J M⁻¹ Jᵀ], 0 if Λ was used undamped.

        Raises
        ------
        InvalidParameterError
            M is not positive definite at q (the error names the joint that moves the least inertia).
        NonFiniteError
            The terms are not finite although M is positive definite.
        """
        q, mass = state.q, state.mass
        kernel = self.dynamics.kernel
        gravity = kernel.gravity(q)
        coriolis = state.bias - gravity  # C q̇
        lam = None
        try:
            terms = operational_space_terms(mass, jacobian, drift, coriolis, gravity)
        except np.linalg.LinAlgError:  # M not positive definite, or J M⁻¹ Jᵀ singular outright
            pass
        else:
            lam, _, info = lapack.dsyev(terms[0], compute_v=0)  # Λ's eigenvalues, ascending: 1 / J M⁻¹ Jᵀ's
            if info:
                lam = None
            elif np.isfinite(lam).all() and 0.0 < lam[-1] <= self.condition_limit * lam[0]:
                return (*terms, 0.0)
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
        self._task_log(log, t)
        self.last_log = log
        return tau

    def run_summary(self) -> str | None:
        """The steps since :meth:`reset` (or the last :meth:`end_run`) on which Λ was damped, in words.

        Returns
        -------
        str or None
            How many steps, the largest δ² and what it means; None if Λ was never damped.
        """
        if not self._damped:
            return None
        return (
            f"ClosedFormOSC over {self._steps} control steps: Λ = (J M⁻¹ Jᵀ)⁻¹ was damped on {len(self._damped)} "
            f"(its condition number beyond {self.condition_limit:g}: the task Jacobian at or next to a singular "
            f"configuration; damping δ² up to {max(self._damped):.3g}), and the task was not met along the lost "
            "direction there; last_log['damping'] gives δ² per step"
        )

    def _forget_run(self) -> None:
        self._steps = 0
        self._damped = []

    def reset(self) -> None:
        """Forget the run's counts."""
        super().reset()
        self._forget_run()
