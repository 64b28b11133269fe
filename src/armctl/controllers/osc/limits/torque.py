"""`TorqueLimit`: |τ_i| ≤ s·τ_max,i, with τ_max the model's effort limits unless given."""

from __future__ import annotations

from numpy.typing import ArrayLike

from armctl._checks import FloatArray, scalar
from armctl.controllers.osc.limits.base import Limit, per_joint
from armctl.controllers.osc.state import ModelState
from armctl.model.robot import RobotModel


class TorqueLimit(Limit):
    """Symmetric torque bounds, −s τ_max ≤ τ ≤ s τ_max.

    Parameters
    ----------
    limit : array_like, optional
        τ_max > 0 [N·m] (N for a prismatic joint): a scalar or (n,); inf for no bound. None (the default): the
        model's effort limits.
    scale : float, optional
        s > 0, e.g. 0.3 to show saturation.

    Raises
    ------
    InvalidParameterError, NonFiniteError
        ``scale`` not a positive number. When the controller binds the limit to its model: a ``limit`` that is
        not > 0 or NaN.
    ShapeError
        Likewise, a ``limit`` of another size than the model's joints.
    """

    variable = "tau"
    constant = True
    kind = "torque_limit"

    def __init__(self, limit: ArrayLike | None = None, scale: float = 1.0) -> None:
        self._given = limit
        self.scale = scalar(scale, "scale", positive=True)

    def bind(self, model: RobotModel) -> None:
        super().bind(model)
        self.limit = self.scale * per_joint(self._given, model.effort_limit, model.n, "torque limit")
        self._lower = -self.limit

    def bounds(self, state: ModelState) -> tuple[FloatArray, FloatArray]:
        return self._lower, self.limit
