"""Computed torque (inverse dynamics) control with an optional integral term."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, apply_gain
from armctl.controllers.base import Controller
from armctl.controllers.integral import PIDGains
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError
from armctl.references import Reference


class ComputedTorque(PIDGains, Controller):
    """τ = M(q) v + C(q, q̇) q̇ + g(q) [+ τ_f(q̇)],  v = q̈_d + K_d ė + K_p e + K_i ∫e dt,  e = q_d − q.

    With an exact model the error dynamics are linear and decoupled, ë + K_d ė + K_p e (+ K_i ∫e) = 0; with a
    wrong one (payload, parameter error) the mismatch enters as a disturbance M̂⁻¹(Δ) and the error no longer
    vanishes. The integral is accumulated at the control rate (rectangle rule over the time between calls).

    ``last_log`` (recorded by :func:`armctl.simulate` into ``res.logs``) holds the terms of the commanded
    acceleration v [rad/s²], which add up to it: ``"feedforward"`` q̈_d and ``"feedback"`` K_p e + K_d ė, and
    with an integral ``"integral"`` K_i ∫e dt; with friction compensation also ``"friction"`` τ_f [N·m], added
    to M v + C q̇ + g. (The torque of the feedback alone, M(q)·feedback, would cost a second evaluation of the
    model.) The logged arrays are those the law computed, not copies: read them before the next call.

    Parameters
    ----------
    dynamics : Dynamics
        The controller's model (M, C, g and τ_f).
    kp : array_like
        K_p [1/s²]: a scalar, an (n,) diagonal or an n×n symmetric positive definite matrix.
    kd : array_like
        K_d [1/s], likewise.
    ki : array_like, optional
        K_i [1/s³], likewise, or None (no integral term).
    friction : bool or "reference", optional
        Compensate the model's friction at the measured velocity, τ_f(q̇) (True, the default), at the reference
        velocity, τ_f(q̇_d) (``"reference"``: a feedforward that pushes a stuck joint the way it should move — the
        feedback alone, scaled by M, needs large errors to break stiction on light joints — and does not chatter
        at rest), or not at all (False).

    Raises
    ------
    InvalidParameterError, ShapeError, NonFiniteError
        A gain that is not symmetric positive definite, of the wrong size, or not finite; another ``friction``.
    """

    dynamics: Dynamics  # given to __init__, never None

    def __init__(
        self, dynamics: Dynamics, kp: ArrayLike, kd: ArrayLike, ki: ArrayLike | None = None, friction: bool | str = True
    ) -> None:
        super().__init__(dynamics)
        self._start(kp, kd, ki)
        self.friction = friction

    @property
    def friction(self) -> bool | str:
        """True (at the measured velocity), ``"reference"`` (at the reference velocity) or False."""
        return self._friction

    @friction.setter
    def friction(self, value: bool | str) -> None:
        if isinstance(value, str) and value == "reference":
            self._friction: bool | str = "reference"
        elif isinstance(value, bool | np.bool_):  # not 1 or 1.0, which equal True but are no mode
            self._friction = bool(value)
        else:
            raise InvalidParameterError(f"friction must be True, False or 'reference', got {value!r}", value=value)

    def _derive(self) -> None:
        super()._derive()
        # [v; K_p e + K_d ė] = [[I, F], [0, F]]·[q̈_d; q_d; q̇_d; q; q̇] (F: PIDGains' K_p e + K_d ė): the command
        # and its feedback term (for the log) from one product, which costs about what v's alone does
        n = self.n
        self._command = np.vstack(
            (np.hstack((np.eye(n), self._feedback)), np.hstack((np.zeros((n, n)), self._feedback)))
        )

    #: stateless without an integral; a NaN/inf in q_j or q̇_j reaches τ through v_j and M_jj > 0
    result_check = True

    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        kernel = self.dynamics.kernel
        both = self._command.dot(np.concatenate((ref.qdd, ref.q, ref.qd, q, qd)))
        n = self.n
        v = both[:n]  # q̈_d + K_d ė + K_p e
        log = {"feedforward": ref.qdd, "feedback": both[n:]}
        if self._ki is not None:
            integral = apply_gain(self._ki, self._integral.update(t, ref.q - q))
            v += integral
            log["integral"] = integral
        tau = kernel.rnea(q, qd, v)
        if self._friction and kernel.friction.any:
            friction = kernel.friction.torque(ref.qd if self._friction == "reference" else qd)
            tau += friction
            log["friction"] = friction
        self.last_log = log
        return tau
