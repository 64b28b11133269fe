"""`JointPositionLimit`: joint position limits as acceleration bounds that keep every joint stoppable
(viability, after Del Prete, "Joint position and velocity bounds in discrete-time acceleration/torque
control of robot manipulators", IEEE RA-L 2018).

With the control period Δt, the next state under a constant q̈ is q⁺ = q + Δt q̇ + ½Δt² q̈, q̇⁺ = q̇ + Δt q̈.
Two bounds on q̈ for the upper limit q_max (the lower one is symmetric):

* position:  q⁺ ≤ q_max  ⇔  q̈ ≤ 2 (q_max − q − Δt q̇) / Δt²
* viability: from q⁺ the joint can still stop before q_max braking at a_max, (q̇⁺)² ≤ 2 a_max (q_max − q⁺);
  solving the quadratic in q̈ gives
      q̈ ≤ [−(2Δt q̇ + a_max Δt²) + Δt √(a_max² Δt² + 8 a_max (q_max − q) − 4 a_max Δt q̇)] / (2Δt²)
  (a negative discriminant means the joint can no longer stop in time: the bound is then −a_max).

Each bound is clamped to ≥ −a_max (the strongest braking asked for) so that a joint that has strayed
outside the viable set brakes at a_max instead of making the QP infeasible.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, scalar
from armctl.controllers.osc.limits.base import Limit, per_joint
from armctl.controllers.osc.state import ModelState
from armctl.errors import InvalidParameterError
from armctl.model.robot import RobotModel


def _upper_bound(gap: FloatArray, qd: FloatArray, dt: float, amax: FloatArray) -> FloatArray:
    """The tighter of the position and viability bounds on q̈ for a limit ``gap`` = q_max − q ahead,
    moving at ``qd`` towards it."""
    pos = 2.0 * (gap - dt * qd) / (dt * dt)
    disc = amax * amax * dt * dt + 8.0 * amax * gap - 4.0 * amax * dt * qd
    root = np.sqrt(np.maximum(disc, 0.0))
    via = (-(2.0 * dt * qd + amax * dt * dt) + dt * root) / (2.0 * dt * dt)
    via = np.where(disc < 0.0, -amax, via)
    return np.maximum(np.minimum(pos, via), -amax)


class JointPositionLimit(Limit):
    """q_min + margin ≤ q ≤ q_max − margin [rad], enforced through q̈ bounds (see the module); ``dt`` the
    control period [s], ``max_deceleration`` a_max [rad/s²] the braking the joints can count on."""

    kind = "position_limit"

    def __init__(self, dt: float = 1e-3, max_deceleration: ArrayLike = 10.0, margin: float = 0.0,
                 lower: ArrayLike | None = None, upper: ArrayLike | None = None) -> None:
        self.dt = scalar(dt, "dt", positive=True)
        self.margin = scalar(margin, "margin", nonnegative=True)
        self._amax, self._lo, self._up = max_deceleration, lower, upper

    def bind(self, model: RobotModel) -> None:
        super().bind(model)
        n = model.n
        self.max_deceleration = per_joint(self._amax, np.zeros(0), n, "max_deceleration")
        self.lower = per_joint(self._lo, model.lower, n, "lower position limit", positive=False) + self.margin
        self.upper = per_joint(self._up, model.upper, n, "upper position limit", positive=False) - self.margin
        if (self.lower >= self.upper).any():
            raise InvalidParameterError(f"position limits (with margin {self.margin}) leave no range: lower "
                                        f"{self.lower.tolist()}, upper {self.upper.tolist()}", value=self.margin)

    def bounds(self, state: ModelState) -> tuple[FloatArray, FloatArray]:
        q, qd, dt, amax = state.q, state.qd, self.dt, self.max_deceleration
        upper = _upper_bound(self.upper - q, qd, dt, amax)
        lower = -_upper_bound(q - self.lower, -qd, dt, amax)
        return lower, upper
