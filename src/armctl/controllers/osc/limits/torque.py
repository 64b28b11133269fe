"""`TorqueLimit`: |τ_i| ≤ s·τ_max,i, with τ_max the model's effort limits unless given."""

from __future__ import annotations

from numpy.typing import ArrayLike

from armctl._checks import FloatArray, scalar
from armctl.controllers.osc.limits.base import Limit, per_joint
from armctl.controllers.osc.state import ModelState
from armctl.model.robot import RobotModel


class TorqueLimit(Limit):
    """−s τ_max ≤ τ ≤ s τ_max [N·m]; ``limit`` τ_max (scalar or (n,), default the model's effort limits),
    ``scale`` s > 0 (e.g. 0.3 to show saturation)."""

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
