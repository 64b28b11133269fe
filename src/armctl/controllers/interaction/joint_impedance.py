"""`JointImpedance`: every joint a spring and damper about the joint reference, on a model-compensated arm."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, boolean
from armctl.controllers.interaction.gains import critical_damping, damping_ratio
from armctl.controllers.interaction.spring import SpringLaw
from armctl.dynamics.base import Dynamics
from armctl.references import Reference


class JointImpedance(SpringLaw):
    """Joint impedance control: the arm behaves as M(q) ë + D ė + K e = Jᵀ h about the joint reference.

    Parameters
    ----------
    dynamics : Dynamics
        The controller's model: M(q), C(q, q̇) q̇, g(q), τ_f(q̇).
    stiffness : array_like
        K [N·m/rad]: a scalar, an (n,) diagonal or an n×n matrix, symmetric positive semi-definite.
    damping : array_like, optional
        D [N·m·s/rad], likewise; None (the default): the damping that gives every mode of M(q) ë + D ė + K e = 0
        the damping ratio ``zeta``, recomputed at each step from M(q) by double diagonalisation
        (:func:`~armctl.controllers.interaction.gains.critical_damping`).
    zeta : float, optional
        ζ ≥ 0 of the default damping; 1: critical.
    friction : bool, optional
        Compensate the model's joint friction τ_f(q̇) (default True).

    Raises
    ------
    InvalidParameterError
        A stiffness that is not symmetric positive semi-definite, a negative damping, ζ < 0.
    ShapeError
        A matrix of the wrong size.

    Notes
    -----
    With e = q_d − q, ė = q̇_d − q̇ and the reference's acceleration q̈_d::

        τ = M(q) q̈_d + C(q, q̇) q̇ + g(q) + τ_f(q̇) + K e + D ė

    so that, with an exact model and h the wrench the arm exerts at a frame of Jacobian J,
    M(q) ë + D ė + K e = Jᵀ h: at rest, the joints yield K⁻¹ Jᵀ h. The stiffness the frame shows is
    (J K⁻¹ Jᵀ)⁻¹, which depends on the configuration (Cartesian impedance fixes it instead).

    ``last_log`` holds ``"spring"`` K e + D ė [N·m].
    """

    def __init__(
        self,
        dynamics: Dynamics,
        stiffness: ArrayLike,
        damping: ArrayLike | None = None,
        *,
        zeta: float = 1.0,
        friction: bool = True,
    ) -> None:
        super().__init__(dynamics, stiffness, damping)
        self.zeta = damping_ratio(zeta)
        self.friction = boolean(friction, "friction")

    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        kernel = self.dynamics.kernel
        damping = self.damping
        if damping is None:
            damping = critical_damping(kernel.mass(q), self.stiffness, self.zeta)
        spring = self.stiffness @ (ref.q - q) + damping @ (ref.qd - qd)
        tau = kernel.rnea(q, qd, ref.qdd) + spring
        if self.friction and kernel.friction.any:
            tau += kernel.friction.torque(qd)
        self.last_log = {"spring": spring}
        return np.asarray(tau)
