"""`AccelerationLimit`: constant bounds on the joint accelerations, lower ≤ q̈ ≤ upper [rad/s²]."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray
from armctl.controllers.osc.limits.base import Limit, per_joint
from armctl.controllers.osc.state import ModelState
from armctl.errors import InvalidParameterError
from armctl.model.robot import RobotModel


class AccelerationLimit(Limit):
    """Constant bounds on the joint accelerations, lower ≤ q̈ ≤ upper.

    Parameters
    ----------
    upper : array_like
        The upper bound [rad/s²] (m/s² for a prismatic joint): a scalar or (n,); inf for no bound.
    lower : array_like, optional
        The lower bound, likewise; None (the default): −upper.

    Raises
    ------
    InvalidParameterError, ShapeError, NonFiniteError
        When the controller binds the limit to its model: a lower bound above the upper one (so, without
        ``lower``, a negative ``upper``), a vector of another size, or NaN.
    """

    constant = True
    kind = "acceleration_limit"

    def __init__(self, upper: ArrayLike, lower: ArrayLike | None = None) -> None:
        self._upper, self._lower = upper, lower

    def bind(self, model: RobotModel) -> None:
        super().bind(model)
        self.upper = per_joint(self._upper, np.zeros(0), model.n, "acceleration upper limit", positive=False)
        self.lower = (
            -self.upper
            if self._lower is None
            else per_joint(self._lower, np.zeros(0), model.n, "acceleration lower limit", positive=False)
        )
        if (self.lower > self.upper).any():
            raise InvalidParameterError(
                f"acceleration limits: lower {self.lower.tolist()} above upper {self.upper.tolist()}", value=self._lower
            )

    def bounds(self, state: ModelState) -> tuple[FloatArray, FloatArray]:
        return self.lower, self.upper
