"""`FramePositionTask`: the origin of a frame follows a Cartesian point."""

from __future__ import annotations

from numpy.typing import ArrayLike

from armctl._checks import FloatArray
from armctl.controllers.osc.state import ModelState
from armctl.controllers.osc.tasks.frame_task import FrameTask
from armctl.references import Reference


class FramePositionTask(FrameTask):
    """The origin of a frame follows a point in the world [m]: a constant target (:meth:`set_target`) or a
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
        The task's name; None (the default): ``"position[FRAME]"`` (``"position[tool]"`` for the tool frame).

    Raises
    ------
    InvalidParameterError, ShapeError, NonFiniteError
        A gain that is not symmetric positive definite, of the wrong size or not finite; a negative weight.

    Notes
    -----
    With p the frame origin's position and J_v the linear rows (0–2) of the frame Jacobian (world axes)::

        e = p_ref − p,   ė = ṗ_ref − J_v q̇,   J = J_v,   drift = (J̇ q̇)_v

    The model's frame is checked when the task is given to a controller (UnknownNameError).
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
        super().__init__(3, "position", (3,), frame, kp, kd, weight, priority, name)

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

    def kinematics(
        self, state: ModelState, t: float, ref: Reference
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        p, v, a = self.target.at(t)
        fk = state.frame(self.frame)
        return fk.jacobian[:3], fk.drift[:3], p - fk.position, v - fk.velocity[:3], a
