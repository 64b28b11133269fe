"""`FrameOrientationTask`: the orientation of a frame follows a rotation."""

from __future__ import annotations

from numpy.typing import ArrayLike

from armctl._checks import FloatArray
from armctl.controllers.osc.state import FrameKinematics
from armctl.controllers.osc.tasks.frame_task import FrameTask
from armctl.controllers.osc.tasks.rotation import rotation_error


class FrameOrientationTask(FrameTask):
    """The orientation of a frame follows a rotation (world axes): a constant target (:meth:`set_target`) or a
    trajectory (:meth:`set_trajectory`).

    (the Parameters and Raises sections of a frame task)

    Notes
    -----
    With R the frame's rotation and J_ω the angular rows (3–5) of the frame Jacobian (world axes)::

        e = log(R_ref Rᵀ) (rotation vector, world axes),   ė = ω_ref − J_ω q̇,   J = J_ω,   drift = (J̇ q̇)_ω

    The PD law on the rotation vector is exact to first order in ‖e‖ (the usual choice for tracking; for large
    errors it still turns about the shortest axis).
    """

    task_dim = 3
    kind = "orientation"
    frame_rows = slice(3, 6)
    target_shape = (3, 3)

    def set_target(
        self,
        rotation: ArrayLike,
        angular_velocity: ArrayLike | None = None,
        angular_acceleration: ArrayLike | None = None,
    ) -> None:
        """Set a constant target (world axes); it replaces a trajectory.

        Parameters
        ----------
        rotation : array_like, shape (3, 3)
            R_ref, a rotation matrix (orthonormal to 1e-4, determinant +1).
        angular_velocity : array_like, shape (3,), optional
            ω_ref [rad/s]; None (the default): zero.
        angular_acceleration : array_like, shape (3,), optional
            ω̇_ref [rad/s²], the feed-forward; None (the default): zero.

        Raises
        ------
        InvalidParameterError
            ``rotation`` is not a rotation (not orthonormal, or a reflection); an entry is not a real number.
        ShapeError, NonFiniteError
            An array of the wrong shape or not finite.
        """
        self.target.set(rotation, angular_velocity, angular_acceleration)

    def _frame_error(self, value: FloatArray, fk: FrameKinematics) -> FloatArray:
        return rotation_error(value, fk.rotation)
