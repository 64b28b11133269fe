"""`FramePoseTask`: position and orientation of a frame together (6 rows, [linear; angular])."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray
from armctl.controllers.osc.state import ModelState
from armctl.controllers.osc.tasks.frame_task import FrameTask
from armctl.controllers.osc.tasks.rotation import rotation_error
from armctl.references import Reference


class FramePoseTask(FrameTask):
    """Position and orientation of a frame together (6 rows, [linear; angular]): a constant target
    (:meth:`set_target`) or a trajectory (:meth:`set_trajectory`).

    Parameters
    ----------
    frame : str, optional
        A name of the model's ``frame_names`` (its joints' frames and the frames it declares); None (the default):
        the tool frame (the last joint's frame on a model without one).
    kp : array_like, optional
        K_p [1/s²]: a scalar, a (6,) diagonal or a 6×6 symmetric positive definite matrix (rows [linear; angular]).
    kd : array_like, optional
        K_d [1/s], likewise; None (the default): critical damping, 2 K_p^½.
    weight : array_like, optional
        The rows' weights w_i ≥ 0 (scalar or (6,)).
    priority : int, optional
        Its level, 0 the most important.
    name : str, optional
        The task's name; None (the default): ``"pose[FRAME]"`` (``"pose[tool]"`` for the tool frame).

    Raises
    ------
    InvalidParameterError, ShapeError, NonFiniteError
        A gain that is not symmetric positive definite, of the wrong size or not finite; a negative weight.

    Notes
    -----
    With p, R the frame's position and rotation and J the 6×n frame Jacobian (world axes, rows [linear;
    angular])::

        e = [p_ref − p;  log(R_ref Rᵀ)],   ė = V_ref − J q̇,   J = the 6×n frame Jacobian,   drift = J̇ q̇

    A step without a target, or whose trajectory gives one that is not a pose, of the wrong shape or not finite,
    raises InvalidParameterError, ShapeError or NonFiniteError.
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
        super().__init__(6, "pose", (4, 4), frame, kp, kd, weight, priority, name)

    def set_target(
        self, pose: ArrayLike, twist: ArrayLike | None = None, acceleration: ArrayLike | None = None
    ) -> None:
        """Set a constant target (world axes); it replaces a trajectory.

        Parameters
        ----------
        pose : array_like, shape (4, 4)
            The homogeneous pose of the frame in the world: rotation R_ref (orthonormal to 1e-4, determinant +1)
            and position p_ref [m]; last row [0, 0, 0, 1].
        twist : array_like, shape (6,), optional
            V_ref = [v; ω]: the velocity of the frame origin [m/s] and the angular velocity [rad/s]; None (the
            default): zero.
        acceleration : array_like, shape (6,), optional
            [a; ω̇] [m/s²; rad/s²], the feed-forward; None (the default): zero.

        Raises
        ------
        InvalidParameterError
            ``pose`` is not one (its rotation not orthonormal or a reflection, its last row not [0, 0, 0, 1]); an
            entry is not a real number.
        ShapeError, NonFiniteError
            An array of the wrong shape or not finite.
        """
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

    def _derive(self) -> None:
        super()._derive()
        # ẍ* − J̇q̇ with the errors themselves inside the product: [I, K_d, −K_d, K_p,lin, −K_p,lin, K_p,rot, −I]
        # · [ẍ_ref; V_ref; J q̇; p_ref; p; log(R_ref Rᵀ); J̇q̇] (K_p,lin / K_p,rot: K_p's first / last 3 columns)
        eye, kd, kp = np.eye(6), self._kd_matrix, self._kp_matrix
        self._pose_law = np.hstack((eye, kd, -kd, kp[:, :3], -kp[:, :3], kp[:, 3:], -eye))

    def residual(self, state: ModelState, t: float, ref: Reference) -> tuple[FloatArray, FloatArray]:
        # kinematics and the PD law in one product; a subclass that overrides kinematics gets the generic form
        if type(self).kinematics is not FramePoseTask.kinematics:
            return super().residual(state, t, ref)  # type: ignore[return-value]  # a frame task has a Jacobian
        pose, twist, acc = self.target.at(t)
        fk = state.frame(self.frame)
        x = np.concatenate(
            (acc, twist, fk.velocity, pose[:3, 3], fk.position, rotation_error(pose[:3, :3], fk.rotation), fk.drift)
        )
        return fk.jacobian, self._pose_law.dot(x)
