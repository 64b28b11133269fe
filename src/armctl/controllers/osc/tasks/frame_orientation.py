"""`FrameOrientationTask`: the orientation of a frame follows a rotation.

    e = log(R_ref Rᵀ) (rotation vector, world axes),   ė = ω_ref − J_ω q̇,   J = J_ω (rows 3–5),
    drift = (J̇ q̇)_ω

The PD law on the rotation vector is exact to first order in ‖e‖ (the usual choice for tracking; for large
errors it still turns about the shortest axis).
"""

from __future__ import annotations

from numpy.typing import ArrayLike

from armctl._checks import FloatArray
from armctl.controllers.osc.state import ModelState
from armctl.controllers.osc.tasks.frame_task import FrameTask
from armctl.controllers.osc.tasks.rotation import rotation_error
from armctl.references import Reference


class FrameOrientationTask(FrameTask):
    """Orientation of ``frame`` (default: the tool frame); gains ``kp`` [1/s²], ``kd`` [1/s]. Target:
    :meth:`set_target` (rotation 3×3, angular velocity [rad/s], angular acceleration [rad/s²], world axes)."""

    def __init__(
        self,
        frame: str | None = None,
        kp: ArrayLike = 400.0,
        kd: ArrayLike | None = None,
        weight: ArrayLike = 1.0,
        priority: int = 0,
        name: str | None = None,
    ) -> None:
        super().__init__(3, "orientation", (3, 3), frame, kp, kd, weight, priority, name)

    def set_target(
        self,
        rotation: ArrayLike,
        angular_velocity: ArrayLike | None = None,
        angular_acceleration: ArrayLike | None = None,
    ) -> None:
        self.target.set(rotation, angular_velocity, angular_acceleration)

    def kinematics(
        self, state: ModelState, t: float, ref: Reference
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        rot, w, dw = self.target.at(t)
        fk = state.frame(self.frame)
        e = rotation_error(rot, fk.rotation)
        return fk.jacobian[3:], fk.drift[3:], e, w - fk.velocity[3:], dw
