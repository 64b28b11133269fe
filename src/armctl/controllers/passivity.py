"""Passivity-based tracking control (Slotine–Li)."""

from __future__ import annotations

from numpy.typing import ArrayLike

from armctl._checks import FloatArray, Gain
from armctl.controllers.base import Controller
from armctl.dynamics.base import Dynamics
from armctl.reference import Reference


def sliding(q: FloatArray, qd: FloatArray, ref: Reference, lam: FloatArray) -> tuple[FloatArray, ...]:
    """(q̇_r, q̈_r, s) of Slotine–Li: q̃ = q − q_d, q̇_r = q̇_d − Λq̃, q̈_r = q̈_d − Λ(q̇ − q̇_d), s = q̇ − q̇_r.
    ``lam`` in :func:`~armctl._checks.compact_gain` form."""
    if lam.ndim == 1:  # apply_gain, inlined for the diagonal Λ of the hot path
        qd_r = ref.qd - lam * (q - ref.q)
        qdd_r = ref.qdd - lam * (qd - ref.qd)
    else:
        qd_r = ref.qd - lam.dot(q - ref.q)
        qdd_r = ref.qdd - lam.dot(qd - ref.qd)
    return qd_r, qdd_r, qd - qd_r


class PassivityBased(Controller):
    """τ = M(q) q̈_r + C(q, q̇) q̇_r + g(q) + F_v q̇_r + F_c sgn(q̇) − K_D s  (Slotine & Li 1987).

    The closed loop M ṡ + C s + (K_D + F_v) s = 0 is passive: with Ṁ − 2C skew-symmetric, V = ½ sᵀM s
    decreases as −sᵀ(K_D + F_v)s, so s → 0 and q̃ → 0 through the filter q̃̇ = −Λq̃ + s. Unlike computed torque
    it does not cancel the dynamics into a double integrator, which keeps it robust to model error at the
    same gains. The model terms come from two inverse-dynamics evaluations (``Dynamics.passivity_torque``).

    lam: Λ [1/s]; kd: K_D [N·m·s/rad] (scalar, vector or matrix).
    """

    lam = Gain("Λ (n×n); may be reassigned between calls (checked again).")
    kd = Gain("K_D (n×n); may be reassigned between calls (checked again).")

    def __init__(self, dynamics: Dynamics, lam: ArrayLike, kd: ArrayLike) -> None:
        super().__init__(dynamics)
        self.lam, self.kd = lam, kd
        # no state; a NaN/inf in q_j or q̇_j reaches s_j = q̃̇_j + (Λq̃)_j and τ through −K_D s (K_D ≻ 0)
        self._checks_result = self._own_law()

    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        dyn = self.dynamics
        assert dyn is not None
        qd_r, qdd_r, s = sliding(q, qd, ref, self._lam)
        tau = dyn._passivity_torque(q, qd, qd_r, qdd_r, s)  # q, q̇ checked by Controller.__call__
        tau -= self._kd * s if self._kd.ndim == 1 else self._kd.dot(s)
        return tau

    _result_checked_compute = compute  # stateless (see Controller)
