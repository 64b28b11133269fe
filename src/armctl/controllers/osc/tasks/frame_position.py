"""`FramePositionTask`: the origin of a frame follows a Cartesian point.

e = p_ref − p,   ė = ṗ_ref − J_v q̇,   J = J_v (rows 0–2 of the frame Jacobian),   drift = (J̇ q̇)_v
"""

from __future__ import annotations

from numpy.typing import ArrayLike

from armctl._checks import FloatArray
from armctl.controllers.osc.state import ModelState
from armctl.controllers.osc.tasks.frame_task import FrameTask
from armctl.references import Reference


class FramePositionTask(FrameTask):
    """Position of ``frame``'s origin (default: the tool frame) in the world [m]; gains ``kp`` [1/s²],
    ``kd`` [1/s]. Target: :meth:`set_target` (position, velocity, acceleration) or :meth:`set_trajectory`."""

    def __init__(
        self,
        frame: str | None = None,
        kp: ArrayLike = 400.0,
        kd: ArrayLike | None = None,
        weight: ArrayLike = 1.0,
        priority: int = 0,
        name: str | None = None,
    ) -> None:
        super().__init__(3, "position", (3,), frame, kp, kd, weight, priority, name)

    def set_target(
        self, position: ArrayLike, velocity: ArrayLike | None = None, acceleration: ArrayLike | None = None
    ) -> None:
        """Constant target: position [m], velocity [m/s] and acceleration [m/s²] (world axes; default 0)."""
        self.target.set(position, velocity, acceleration)

    def kinematics(
        self, state: ModelState, t: float, ref: Reference
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        p, v, a = self.target.at(t)
        fk = state.frame(self.frame)
        return fk.jacobian[:3], fk.drift[:3], p - fk.position, v - fk.velocity[:3], a
