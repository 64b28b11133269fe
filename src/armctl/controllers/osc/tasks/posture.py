"""`PostureTask`: the joints follow a joint-space reference (by default the controller's ``ref``).

    e = q_ref − q,   ė = q̇_ref − q̇,   J = I,   drift = 0,   feed-forward q̈_ref

As the lowest-priority (or lightly weighted) task it resolves the redundancy of an arm with more joints than
task rows.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, vector, whole_number
from armctl.controllers.osc.state import ModelState
from armctl.controllers.osc.tasks.base import MotionTask
from armctl.errors import ShapeError
from armctl.reference import Reference


class PostureTask(MotionTask):
    """Joint posture of an n-joint arm; gains ``kp`` [1/s²], ``kd`` [1/s] (scalar, (n,) or n×n). The target
    is the controller's joint reference ``ref`` unless :meth:`set_target` fixes one."""

    identity_jacobian = True

    def __init__(
        self,
        n: int,
        kp: ArrayLike = 100.0,
        kd: ArrayLike | None = None,
        weight: ArrayLike = 1e-2,
        priority: int = 0,
        name: str = "posture",
    ) -> None:
        super().__init__(
            whole_number(n, f"{name}: n (the number of joints)", minimum=1), name, kp, kd, weight, priority
        )
        self._fixed: Reference | None = None

    def set_target(self, q: ArrayLike | None, qd: ArrayLike | None = None, qdd: ArrayLike | None = None) -> None:
        """Fix the target (q [rad], q̇, q̈); ``None`` goes back to following the controller's ``ref``."""
        self._fixed = None if q is None else Reference(vector(q, self.dim, f"{self.name}: q"), qd, qdd)

    def reference(self, ref: Reference) -> Reference:
        """The joint target at this step: the fixed one (:meth:`set_target`) or else the controller's ``ref``."""
        return self._fixed or ref

    def check(self, evaluator: object, n: int, contacts: dict[str, int]) -> None:
        if self.dim != n:
            raise ShapeError(
                f"{self.name}: a posture task of {self.dim} joints on a model of {n} joints", value=self.dim
            )

    def kinematics(
        self, state: ModelState, t: float, ref: Reference
    ) -> tuple[None, None, FloatArray, FloatArray, FloatArray]:
        r = self._fixed or ref
        return None, None, r.q - state.q, r.qd - state.qd, r.qdd  # type: ignore[return-value]

    def _gains_changed(self) -> None:
        super()._gains_changed()
        if hasattr(self, "_kd"):
            # ẍ* with the errors inside the product: [I, K_d, −K_d, K_p, −K_p]·[q̈_ref; q̇_ref; q̇; q_ref; q]
            eye, kd, kp = np.eye(self.dim), self._kd_matrix, self._kp_matrix
            self._posture_law = np.hstack((eye, kd, -kd, kp, -kp))

    def residual(self, state: ModelState, t: float, ref: Reference) -> tuple[None, FloatArray]:
        """(None, ẍ*): :meth:`kinematics` and the PD law in one product (see ``_gains_changed``); a subclass
        that overrides :meth:`kinematics` gets the generic form on its own kinematics."""
        if type(self).kinematics is not PostureTask.kinematics:
            return super().residual(state, t, ref)  # type: ignore[return-value]
        r = self._fixed or ref
        return None, self._posture_law.dot(np.concatenate((r.qdd, r.qd, state.qd, r.q, state.q)))
