"""PD with gravity compensation (Takegaki–Arimoto): the set-point regulator that needs only g(q)."""

from __future__ import annotations

from numpy.typing import ArrayLike

from armctl._checks import FloatArray, apply_gain, compact_gain, gain_matrix
from armctl.controllers.base import Controller
from armctl.dynamics.base import Dynamics
from armctl.reference import Reference


class PDGravity(Controller):
    """τ = K_p (q_d − q) + K_d (q̇_d − q̇) + g(q)  [+ τ_f(q̇) with ``friction=True``].

    For a set-point (q̇_d = 0) the closed loop is globally asymptotically stable for any K_p, K_d ≻ 0 with an
    exact g (Takegaki & Arimoto 1981): V = ½ q̇ᵀM q̇ + ½ q̃ᵀK_p q̃ decreases as −q̇ᵀK_d q̇. Against Coulomb
    friction F_c the arm stops anywhere with |K_p q̃| ≤ F_c, so the steady-state error is bounded by F_c/K_p.

    kp: proportional gain [N·m/rad]; kd: derivative gain [N·m·s/rad] (scalar, vector or matrix).
    """

    def __init__(self, dynamics: Dynamics, kp: ArrayLike, kd: ArrayLike, friction: bool = False) -> None:
        super().__init__(dynamics)
        self.kp = gain_matrix(kp, self.n, "kp")
        self.kd = gain_matrix(kd, self.n, "kd")
        self.friction = bool(friction)
        self._kp, self._kd = compact_gain(self.kp), compact_gain(self.kd)

    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        dyn = self.dynamics
        assert dyn is not None
        tau = dyn.gravity_torque(q)
        tau += apply_gain(self._kp, ref.q - q)
        tau += apply_gain(self._kd, ref.qd - qd)
        if self.friction:
            tau += dyn.friction_torque(qd)
        return tau
