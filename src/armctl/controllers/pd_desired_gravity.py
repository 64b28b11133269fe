"""PD with desired gravity compensation: the set-point regulator that needs g only at the set-point."""

from __future__ import annotations

from numpy.typing import ArrayLike

from armctl._checks import FloatArray, apply_gain
from armctl.controllers.base import Controller
from armctl.controllers.integral import PIDGains
from armctl.dynamics.base import Dynamics
from armctl.references import Reference


class PDDesiredGravity(PIDGains, Controller):
    """τ = K_p e + K_d ė + g(q_d),  e = q_d − q: gravity compensated at the reference position, not the measured
    one (Tomei 1991; Kelly 1997).

    For a constant set-point the closed loop has q = q_d as its only equilibrium, globally asymptotically stable,
    if λ_min(K_p) > k_g, the bound on ‖∂g/∂q‖ over the ranges
    (:func:`~armctl.tuning.conditions.pd_desired_gravity_condition`). With a weaker K_p the gravity left over,
    g(q) − g(q_d), can balance the spring K_p e elsewhere: the arm may come to rest at a second equilibrium.
    Unlike :class:`~armctl.controllers.PDGravity` the gravity term is constant along a set-point, so it can be
    computed once, off line.

    Parameters
    ----------
    dynamics : Dynamics
        The controller's model (its g).
    kp : array_like
        Proportional gain K_p [N·m/rad]: a scalar, an (n,) diagonal or an n×n symmetric positive definite matrix.
    kd : array_like
        Derivative gain K_d [N·m·s/rad], likewise.

    Raises
    ------
    InvalidParameterError, ShapeError, NonFiniteError
        A gain that is not symmetric positive definite, of the wrong size, or not finite.
    """

    dynamics: Dynamics  # given to __init__, never None

    def __init__(self, dynamics: Dynamics, kp: ArrayLike, kd: ArrayLike) -> None:
        super().__init__(dynamics)
        self._start(kp, kd, None)
        self._cached: tuple[tuple[float, ...], FloatArray] | None = None

    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        dyn = self.dynamics
        assert dyn is not None
        key = tuple(ref.q.tolist())
        if self._cached is None or self._cached[0] != key:  # g(q_d) once per set-point
            self._cached = (key, dyn.gravity_torque(ref.q))
        return apply_gain(self._kp, ref.q - q) + apply_gain(self._kd, ref.qd - qd) + self._cached[1]
