"""`FramePositionTask`: the origin of a frame follows a Cartesian point."""

from __future__ import annotations

from numpy.typing import ArrayLike

from armctl._checks import FloatArray
from armctl.controllers.osc.state import FrameKinematics
from armctl.controllers.osc.tasks.frame_task import FrameTask


class FramePositionTask(FrameTask):
    """The origin of a frame follows a point in the world [m]: a constant target (:meth:`set_target`) or a
    trajectory (:meth:`set_trajectory`).

    (the Parameters and Raises sections of a frame task)

    Notes
    -----
    With p the frame origin's position and J_v the linear rows (0–2) of the frame Jacobian (world axes)::

        e = p_ref − p,   ė = ṗ_ref − J_v q̇,   J = J_v,   drift = (J̇ q̇)_v

    The model's frame is checked when the task is given to a controller (UnknownNameError).
    """

    task_dim = 3
    kind = "position"
    frame_rows = slice(0, 3)
    target_shape = (3,)

    def set_target(
        self, position: ArrayLike, velocity: ArrayLike | None = None, acceleration: ArrayLike | None = None
    ) -> None:
        """Set a constant target (world axes); it replaces a trajectory.

        Parameters
        ----------
        position : array_like, shape (3,)
            p_ref [m].
        velocity : array_like, shape (3,), optional
            ṗ_ref [m/s]; None (the default): zero.
        acceleration : array_like, shape (3,), optional
            p̈_ref [m/s²], the feed-forward; None (the default): zero.

        Raises
        ------
        ShapeError, NonFiniteError, InvalidParameterError
            A vector of the wrong size, not finite, or not of real numbers.
        """
        self.target.set(position, velocity, acceleration)

    def _frame_error(self, value: FloatArray, fk: FrameKinematics) -> FloatArray:
        return value - fk.position
