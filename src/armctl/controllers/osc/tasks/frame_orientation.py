"""`FrameOrientationTask`: the orientation of a frame follows a rotation."""

from __future__ import annotations

from numpy.typing import ArrayLike

from armctl._checks import FloatArray
from armctl.controllers.osc.state import ModelState
from armctl.controllers.osc.tasks.frame_task import FrameTask
from armctl.controllers.osc.tasks.rotation import rotation_error
from armctl.references import Reference


class FrameOrientationTask(FrameTask):
    """The orientation of a frame follows a rotation (world axes): a constant target (:meth:`set_target`) or a
    trajectory (:meth:`set_trajectory`).

    Parameters
    ----------
    frame : str, optional
        A name of the model's ``frame_names`` (its joints' frames and the frames it declares); None (the default):
        the tool frame (the last joint's frame on a model without one).
    kp : array_like, optional
        K_p [1/s²]: a scalar, a (3,) diagonal or a 3×3 symmetric positive definite matrix.
    kd : array_like, optional
        K_d [1/s], likewise; None (the default): critical damping, 2 K_p^½.
    weight : array_like, optional
        The rows' weights w_i ≥ 0 (scalar or (3,)).
    priority : int, optional
        Its level, 0 the most important.
    name : str, optional
        The task's name; None (the default): ``"orientation[FRAME]"`` (``"orientation[tool]"`` for the tool frame).

    Raises
    ------
    InvalidParameterError, ShapeError, NonFiniteError
        A gain that is not symmetric positive definite, of the wrong size or not finite; a negative weight.

    Notes
    -----
    With R the frame's rotation and J_ω the angular rows (3–5) of the frame Jacobian (world axes)::

        e = log(R_ref Rᵀ) (rotation vector, world axes),   ė = ω_ref − J_ω q̇,   J = J_ω,   drift = (J̇ q̇)_ω

    The PD law on the rotation vector is exact to first order in ‖e‖ (the usual choice for tracking; for large
    errors it still turns about the shortest axis).
    """

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

    def kinematics(
        self, state: ModelState, t: float, ref: Reference
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        rot, w, dw = self.target.at(t)
        fk = state.frame(self.frame)
        e = rotation_error(rot, fk.rotation)
        return fk.jacobian[3:], fk.drift[3:], e, w - fk.velocity[3:], dw
