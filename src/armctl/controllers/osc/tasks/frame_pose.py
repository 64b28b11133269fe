"""`FramePoseTask`: position and orientation of a frame together (6 rows, [linear; angular]).

e = [p_ref − p;  log(R_ref Rᵀ)],   ė = V_ref − J q̇,   J = the 6×n frame Jacobian,   drift = J̇ q̇
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray
from armctl.controllers.osc.state import ModelState
from armctl.controllers.osc.tasks.frame_task import FrameTask
from armctl.controllers.osc.tasks.rotation import rotation_error
from armctl.references import Reference


class FramePoseTask(FrameTask):
    """Pose of ``frame`` (default: the tool frame). Gains ``kp`` [1/s²], ``kd`` [1/s] (scalar, (6,) or 6×6;
    rows [linear; angular]). Target: :meth:`set_target` (4×4 pose in the world, twist [v; ω] (6,),
    acceleration [a; ω̇] (6,), world axes) or :meth:`set_trajectory`."""

    def __init__(
        self,
        frame: str | None = None,
        kp: ArrayLike = 400.0,
        kd: ArrayLike | None = None,
        weight: ArrayLike = 1.0,
        priority: int = 0,
        name: str | None = None,
    ) -> None:
        super().__init__(6, "pose", (4, 4), frame, kp, kd, weight, priority, name)

    def set_target(
        self, pose: ArrayLike, twist: ArrayLike | None = None, acceleration: ArrayLike | None = None
    ) -> None:
        self.target.set(pose, twist, acceleration)

    def kinematics(
        self, state: ModelState, t: float, ref: Reference
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        pose, twist, acc = self.target.at(t)
        fk = state.frame(self.frame)
        e = np.empty(6)
        e[:3] = pose[:3, 3] - fk.position
        e[3:] = rotation_error(pose[:3, :3], fk.rotation)
        return fk.jacobian, fk.drift, e, twist - fk.velocity, acc

    def _gains_changed(self) -> None:
        super()._gains_changed()
        if hasattr(self, "_kd"):
            # ẍ* − J̇q̇ with the errors themselves inside the product: [I, K_d, −K_d, K_p,lin, −K_p,lin, K_p,rot, −I]
            # · [ẍ_ref; V_ref; J q̇; p_ref; p; log(R_ref Rᵀ); J̇q̇] (K_p,lin / K_p,rot: K_p's first / last 3 columns)
            eye, kd, kp = np.eye(6), self._kd_matrix, self._kp_matrix
            self._pose_law = np.hstack((eye, kd, -kd, kp[:, :3], -kp[:, :3], kp[:, 3:], -eye))

    def residual(self, state: ModelState, t: float, ref: Reference) -> tuple[FloatArray, FloatArray]:
        """(J, ẍ* − J̇q̇): :meth:`kinematics` and the PD law in one product (see ``_gains_changed``); a
        subclass that overrides :meth:`kinematics` gets the generic form on its own kinematics."""
        if type(self).kinematics is not FramePoseTask.kinematics:
            return super().residual(state, t, ref)  # type: ignore[return-value]  # a frame task has a Jacobian
        pose, twist, acc = self.target.at(t)
        fk = state.frame(self.frame)
        x = np.concatenate(
            (acc, twist, fk.velocity, pose[:3, 3], fk.position, rotation_error(pose[:3, :3], fk.rotation), fk.drift)
        )
        return fk.jacobian, self._pose_law.dot(x)
