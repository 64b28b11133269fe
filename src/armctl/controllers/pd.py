"""PD with gravity compensation (Takegaki–Arimoto): the set-point regulator that needs only g(q)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, apply_gain, flag
from armctl.controllers.base import Controller
from armctl.controllers.integral import PIDGains
from armctl.dynamics.base import Dynamics
from armctl.references import Reference


class PDGravity(PIDGains, Controller):
    """τ = K_p e + K_d ė + g(q)  [+ K_i ∫e dt] [+ τ_f(q̇) with ``friction=True``],  e = q_d − q.

    For a set-point (q̇_d = 0) the closed loop is globally asymptotically stable for any K_p, K_d ≻ 0 with an
    exact g (Takegaki & Arimoto 1981): V = ½ q̇ᵀM q̇ + ½ eᵀK_p e decreases as −q̇ᵀK_d q̇. Against Coulomb
    friction the arm stops anywhere with |K_p e| below the breakaway level F_s, so the steady-state error is
    bounded by F_s/K_p (F_c/K_p without stiction). An integral term removes that error in theory, but against
    stiction (breakaway above the Coulomb level) it produces the stick–slip "hunting" limit cycle: the integral
    winds up while the joint sticks, the joint breaks away, overshoots, and sticks again on the other side.

    ``last_log`` (recorded by :func:`armctl.simulate` into ``res.logs``) holds the terms of τ [N·m], which add
    up to it: ``"feedback"`` K_p e + K_d ė, ``"gravity"`` g(q), and where used ``"integral"`` K_i ∫e dt and
    ``"friction"`` τ_f(q̇). The fused law of ``compile=True`` computes τ in one call and logs only the
    integral and friction terms (splitting it would cost a second evaluation). The logged arrays are those the
    law computed, not copies: read them before the next call.

    The integral is accumulated at the control rate. On ``armctl.Dynamics(model, compile=True)`` the law
    g + K_p e + K_d ė runs as one call of the generated code.

    Parameters
    ----------
    dynamics : Dynamics
        The controller's model (its g and, with ``friction``, its τ_f).
    kp : array_like
        Proportional gain K_p [N·m/rad]: a scalar, an (n,) diagonal or an n×n symmetric positive definite matrix.
    kd : array_like
        Derivative gain K_d [N·m·s/rad], likewise.
    ki : array_like, optional
        Integral gain K_i [N·m/(rad·s)], likewise, or None (no integral term).
    friction : bool, optional
        Add the model's friction τ_f(q̇) at the measured velocity.

    Raises
    ------
    InvalidParameterError, ShapeError, NonFiniteError
        A gain that is not symmetric positive definite, of the wrong size, or not finite.
    """

    dynamics: Dynamics  # given to __init__, never None

    def __init__(
        self, dynamics: Dynamics, kp: ArrayLike, kd: ArrayLike, ki: ArrayLike | None = None, friction: bool = False
    ) -> None:
        super().__init__(dynamics)
        self._start(kp, kd, ki)
        self.friction = friction

    friction = flag("friction", "Compensate the model's friction at the measured velocity.")
    _friction: bool

    #: the fused law g + F·[q_d; q̇_d; q; q̇] in generated code (:mod:`armctl.controllers.pd_generated`, on
    #: ``Dynamics(model, compile=True)``; None for others) and the kernel it was made for: made again at the next
    #: step on another kernel (another dynamics object, another thread)
    _law: Any = None
    _law_for: Any = None

    def _derive(self) -> None:
        super()._derive()
        # [τ; K_p e + K_d ė] = [[F, I], [F, 0]]·[q_d; q̇_d; q; q̇; g]: the torque and its feedback term (for the
        # log) from one product
        n = self.n
        self._with_gravity = np.vstack(
            (np.hstack((self._feedback, np.eye(n))), np.hstack((self._feedback, np.zeros((n, n)))))
        )
        if self._law is not None:  # new gains into the law's own F, in place (binding a new law costs more)
            self._law.feedback[...] = self._feedback

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state.pop("_law", None)  # bound to this process's compiled buffers; made again after unpickling
        state.pop("_law_for", None)
        return state

    def _generated_law(self) -> Any:
        if not self.dynamics.compiled:
            return None
        from armctl.controllers.pd_generated import generated_law  # CasADi, imported on use

        return generated_law(self.dynamics, self._feedback)

    #: stateless without an integral; a NaN/inf in q_j or q̇_j reaches τ through K_p e or K_d ė (K ≻ 0)
    result_check = True

    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        kernel = self.dynamics.kernel
        if kernel is not self._law_for:
            self._law, self._law_for = self._generated_law(), kernel
        law = self._law
        if law is not None:
            tau = law(q, qd, ref.q, ref.qd)
            log: dict[str, Any] = {}
        else:  # g + K_p e + K_d ė = [F, I]·[q_d; q̇_d; q; q̇; g] (F: PIDGains' feedback map): one product adds it all
            g = kernel.gravity(q)
            both = self._with_gravity.dot(np.concatenate((ref.q, ref.qd, q, qd, g)))
            n = self.n
            tau = both[:n]
            log = {"feedback": both[n:], "gravity": g}
        if self._ki is not None:
            integral = apply_gain(self._ki, self._integral.update(t, ref.q - q))
            tau += integral
            log["integral"] = integral
        if self._friction and kernel.friction.any:
            friction = kernel.friction.torque(qd)
            tau += friction
            log["friction"] = friction
        self.last_log = log
        return tau
