"""`JointPositionLimit`: joint position limits as acceleration bounds that keep every joint stoppable
(viability, after Del Prete, IEEE RA-L 2018); the bounds and what they guarantee are described with the class.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, readonly, scalar
from armctl.controllers.osc.limits.base import Limit, per_joint
from armctl.controllers.osc.state import ModelState
from armctl.errors import InvalidParameterError
from armctl.model.robot import RobotModel


class JointPositionLimit(Limit):
    """Joint position limits q_min + margin ≤ q ≤ q_max − margin, enforced through q̈ bounds that keep every
    joint able to stop before its limit (viability, after Del Prete, "Joint position and velocity bounds in
    discrete-time acceleration/torque control of robot manipulators", IEEE RA-L 2018).

    The settings are taken when the limit is bound to a model (by the controller) and kept as read-only arrays:
    to change them, make a new limit.

    Parameters
    ----------
    dt : float, optional
        The control period Δt [s].
    max_deceleration : array_like, optional
        a_max > 0 [rad/s²], finite: the braking the joints can count on (scalar or (n,)).
    margin : float, optional
        ≥ 0 [rad] (m for a prismatic joint), kept from each limit.
    lower, upper : array_like, optional
        q_min, q_max [rad]: scalars or (n,); None (the default): the model's joint limits.
    reserve : float, optional
        ρ in [0, 1): the fraction of a_max the plan keeps for corrections (the plan brakes at (1 − ρ) a_max).

    Raises
    ------
    InvalidParameterError, NonFiniteError
        ``dt`` not > 0, ``margin`` negative, ``reserve`` outside [0, 1). When the controller binds the limit to
        its model: a ``max_deceleration`` that is not > 0 or not finite, limits that are NaN, or limits (with the
        margin) that leave no range.
    ShapeError
        Likewise, a vector of another size than the model's joints.

    Notes
    -----
    With the control period Δt, the next state under a constant q̈ is q⁺ = q + Δt q̇ + ½Δt² q̈, q̇⁺ = q̇ + Δt q̈.
    Two bounds on q̈ for the upper limit q_max (the lower one is symmetric):

    * position:  q⁺ ≤ q_max  ⇔  q̈ ≤ 2 (q_max − q − Δt q̇) / Δt²
    * viability: from q⁺ the joint can still stop before q_max braking at a = (1 − ρ) a_max,
      (q̇⁺)² ≤ 2 a (q_max − q⁺); solving the quadratic in q̈ gives::

          q̈ ≤ [−(2Δt q̇ + a Δt²) + Δt √(a² Δt² + 8 a (q_max − q) − 4 a Δt q̇)] / (2Δt²)

      (a negative discriminant means the joint can no longer stop in time: the bound is then −a_max).

    Each bound is clamped to ≥ −a_max (the strongest braking asked for) so that a joint that has strayed
    outside the viable set brakes at a_max instead of making the QP infeasible.

    What the bounds guarantee: for the discrete model, which holds q̈ over the period, a joint that starts inside
    the viable set stays there and never passes its limit, exactly. A real arm (or the simulator) holds the torque
    instead, and as q and q̇ change within the period M(q)⁻¹(τ − h) drifts from the q̈ the QP chose: braking
    exactly at the viability boundary, the arm brakes a little less than planned (on the Panda at full stretch,
    1–2 % less) and drifts outside the viable set. Hence the reserve ρ (``reserve``, default 0.1): the plan
    brakes at (1 − ρ) a_max, and a joint that drifted out of the plan's viable set is asked for up to a_max, which
    brings it back as long as the drift of a held torque stays below ρ a_max. With ρ = 0 (the plan at a_max, no
    reserve) the Panda overshot a limit by up to 1.7 mrad when driven towards a target out of reach.

    Near the point where a joint can only just stop (discriminant ≈ 0) the bound is accurate to ~1e-4 rad/s²
    (the affine form rounds q_max and q before they cancel).
    """

    kind = "position_limit"

    def __init__(
        self,
        dt: float = 1e-3,
        max_deceleration: ArrayLike = 10.0,
        margin: float = 0.0,
        lower: ArrayLike | None = None,
        upper: ArrayLike | None = None,
        reserve: float = 0.1,
    ) -> None:
        self.dt = scalar(dt, "dt", positive=True)
        self.margin = scalar(margin, "margin", nonnegative=True)
        self.reserve = scalar(reserve, "reserve", nonnegative=True)
        if self.reserve >= 1.0:
            raise InvalidParameterError(
                f"reserve is the fraction of max_deceleration kept for corrections, in [0, 1); got {reserve}",
                value=reserve,
            )
        self._amax, self._lo, self._up = max_deceleration, lower, upper

    def bind(self, model: RobotModel) -> None:
        super().bind(model)
        n = model.n
        self.max_deceleration = per_joint(self._amax, np.zeros(0), n, "max_deceleration", finite=True)
        self.lower = per_joint(self._lo, model.lower, n, "lower position limit", positive=False) + self.margin
        self.upper = per_joint(self._up, model.upper, n, "upper position limit", positive=False) - self.margin
        for arr in (self.max_deceleration, self.lower, self.upper):
            readonly(arr)
        if (self.lower >= self.upper).any():
            raise InvalidParameterError(
                f"position limits (with margin {self.margin}) leave no range: lower "
                f"{self.lower.tolist()}, upper {self.upper.tolist()}",
                value=self.margin,
            )
        # Both sides at once, each as an upper bound: the gap g = [q_max − q; q − q_min] and the velocity
        # towards the limit v = [q̇; −q̇]. The position bound 2(g − Δt v)/Δt², the discriminant
        # a²Δt² + 8a g − 4aΔt v and the part of the viability bound outside the root, −v/Δt − a/2, are affine
        # in [q; q̇]: one product y = B [q; q̇] + c gives all three (12 array operations a step instead of 40)
        dt, a_full = self.dt, np.concatenate([self.max_deceleration] * 2)
        a = (1.0 - self.reserve) * a_full  # the plan's braking
        eye = np.eye(n)
        s_q = np.vstack((-eye, eye))  # g = gap0 + s_q q
        s_v = np.vstack((eye, -eye))  # v = s_v q̇
        gap0 = np.concatenate((self.upper, -self.lower))
        self._affine = np.vstack(
            (
                np.hstack((2.0 / dt**2 * s_q, -2.0 / dt * s_v)),  # position bound
                np.hstack((8.0 * a[:, None] * s_q, -4.0 * dt * a[:, None] * s_v)),  # discriminant
                np.hstack((np.zeros((2 * n, n)), -s_v / dt)),
            )
        )  # viability bound without the root
        self._offset = np.concatenate((2.0 / dt**2 * gap0, (a * dt) ** 2 + 8.0 * a * gap0, -0.5 * a))
        self._neg_a = -a_full
        self._root_factor = np.full(2 * n, 0.5 / dt)

    def bounds(self, state: ModelState) -> tuple[FloatArray, FloatArray]:
        m = len(self._neg_a)
        y = self._affine.dot(np.concatenate((state.q, state.qd)))
        y += self._offset
        pos, disc, via = y[:m], y[m : 2 * m], y[2 * m :]
        root = np.maximum(disc, 0.0)
        np.sqrt(root, out=root)
        root *= self._root_factor
        via += root  # [−(2Δt v + aΔt²) + Δt √disc] / (2Δt²)
        bound = np.where(disc < 0.0, self._neg_a, via)  # no stopping in time: brake at a_max
        np.minimum(bound, pos, out=bound)
        np.maximum(bound, self._neg_a, out=bound)
        half = m // 2
        return -bound[half:], bound[:half]
