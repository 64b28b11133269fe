"""What the task-space interaction controllers share: the frame's target (a pose, or a position for 3 axes),
its error as in the operational-space tasks, and the operational-space inertia.

    e = [p_d − p;  log(R_d Rᵀ)]  (6 axes)   or   e = p_d − p  (3 axes),     ė = v_d − J q̇

(world axes at the frame origin, rows [linear; angular]; log: SO(3) → ℝ³ as
:func:`armctl.controllers.osc.tasks.rotation.rotation_error`), and Λ = (J M⁻¹ Jᵀ)⁻¹, J̄ᵀ = Λ J M⁻¹.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import lapack

from armctl._checks import FloatArray, readonly
from armctl.controllers.osc.state import FrameKinematics
from armctl.controllers.osc.tasks.rotation import rotation_error
from armctl.controllers.osc.tasks.target import TargetHolder, Trajectory
from armctl.dynamics.kernel import Kernel
from armctl.errors import SingularConfigurationError


class FrameTarget:
    """The target of a frame: constant (:meth:`set`) or a trajectory (:meth:`follow`); unset, the pose the
    frame has at the first call is held (until :meth:`reset`).

    Parameters
    ----------
    owner : str
        The controller's name, for the error messages.
    axes : {3, 6}
        6: a pose (4×4) with twist and acceleration (6,); 3: a position (3,) with velocity and acceleration (3,).
    """

    def __init__(self, owner: str, axes: int) -> None:
        self.axes = axes
        self.holder = TargetHolder(owner, (4, 4) if axes == 6 else (3,), axes)
        self._held = False
        #: the constant target's (value, velocity, acceleration), one tuple while it lasts (None: a trajectory,
        #: or no target yet); change the target through this object's methods, which keep it
        self.fixed: tuple[FloatArray, FloatArray, FloatArray] | None = None

    def set(self, value: ArrayLike, velocity: ArrayLike | None = None, acceleration: ArrayLike | None = None) -> None:
        """Hold a constant target: checked (named errors), then copied, read-only — later changes to the arrays
        given do not reach it, so a law may keep what it has read of it while it is the same."""
        self.holder.set(value, velocity, acceleration)
        self.holder.set(*(readonly(np.array(a)) for a in self.holder.at(0.0)))
        self.fixed = self.holder.at(0.0)
        self._held = False

    def follow(self, fn: Trajectory) -> None:
        self.holder.follow(fn)
        self.fixed = None
        self._held = False

    def reset(self) -> None:
        """Forget a target that was only the held first pose."""
        if self._held:
            self.holder = TargetHolder(self.holder.owner, self.holder.value_shape, self.holder.rate)
            self.fixed = None
            self._held = False

    def hold(self, pose: FloatArray) -> None:
        """Hold ``pose`` (4×4; its position for 3 axes) until :meth:`reset`, as the first call does unset."""
        self.holder.set(np.array(pose) if self.axes == 6 else np.array(pose[:3, 3]))
        self.fixed = self.holder.at(0.0)
        self._held = True

    def at(self, t: float, fk: FrameKinematics) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(value, velocity, acceleration) at t [s]; the first call without a target holds the frame's pose."""
        if not self.holder.is_set:
            pose = np.eye(4)
            pose[:3, :3], pose[:3, 3] = fk.rotation, fk.position
            self.hold(pose)  # its position for 3 axes
        return self.holder.at(t)

    def goal_unchecked(
        self,
        t: float,
        q: Any,
        qd: Any,
        checked: Callable[[float, Any, Any], tuple[FloatArray, FloatArray]],
        kernel: Kernel,
        frame: str | None,
    ) -> tuple[tuple[FloatArray, FloatArray, FloatArray], Any, Any]:
        """The target at t [s] for a law that checks its own inputs: t is checked first, and (q, q̇) only when the
        first call without a target holds the frame's pose, so that nothing is kept and no trajectory is called
        before they are known finite.

        Parameters
        ----------
        t : float
            Time [s].
        q, qd : array_like, shape (n,)
            The measured state [rad, rad/s], unchecked.
        checked : callable
            ``checked(t, q, qd) -> (q, qd)``: the controller's check (a named error if one is not finite or of
            the wrong size).
        kernel : Kernel
            The dynamics' kernel, whose ``frame_pose(q, frame)`` gives the pose to hold (4×4).
        frame : str or None
            The controlled frame.

        Returns
        -------
        goal : tuple of ndarray
            (value, velocity, acceleration) at t.
        q, qd : array_like
            The state: checked (as ``checked`` returns it) where the pose was held, as given otherwise.
        """
        if not math.isfinite(t):
            checked(t, q, qd)  # raises, naming t
        goal = self.fixed  # a constant target, or None
        if goal is None:
            holder = self.holder
            if not holder.is_set:
                q, qd = checked(t, q, qd)
                self.hold(kernel.frame_pose(q, frame))
            goal = holder.at(t)
        return goal, q, qd

    def error(self, value: FloatArray, fk: FrameKinematics) -> FloatArray:
        """e (see the module) [m; rad]."""
        if self.axes == 6:
            return np.concatenate((value[:3, 3] - fk.position, rotation_error(value[:3, :3], fk.rotation)))
        return value - fk.position


class PoseTargeted:
    """What a controller whose frame follows a pose target shares: :meth:`set_target` and :meth:`set_trajectory`
    on its :attr:`target` (a 6-axis :class:`FrameTarget`, which the controller creates)."""

    #: the frame's target: a 4×4 pose with its twist and acceleration
    target: FrameTarget

    def set_target(
        self, pose: ArrayLike, twist: ArrayLike | None = None, acceleration: ArrayLike | None = None
    ) -> None:
        """Set the motion target x_d (world axes): the 4×4 pose p_d, R_d [m], the twist [m/s; rad/s] and the
        acceleration [m/s²; rad/s²] (None: zero); it replaces a trajectory. Unset, the frame holds the pose it has
        at the first call.

        Parameters
        ----------
        pose : array_like, shape (4, 4)
            The pose.
        twist, acceleration : array_like, shape (6,), optional
            Its rates.
        """
        self.target.set(pose, twist, acceleration)

    def set_trajectory(self, fn: Trajectory) -> None:
        """Follow a motion trajectory; it replaces a constant target.

        Parameters
        ----------
        fn : callable
            ``fn(t) -> (pose, twist, acceleration)`` in :meth:`set_target`'s terms.
        """
        self.target.follow(fn)


def task_inertia(mass: FloatArray, jac: FloatArray, q: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Λ = (J M⁻¹ Jᵀ)⁻¹ [kg, kg·m²] and J̄ᵀ = Λ J M⁻¹.

    Raises
    ------
    SingularConfigurationError
        J M⁻¹ Jᵀ is singular at q (J loses rank): the impedance is not defined along the lost direction.
    """
    low_m, info = lapack.dpotrf(mass, lower=1)
    if not info:
        mij, info = lapack.dpotrs(low_m, jac.T, lower=1)  # M⁻¹ Jᵀ
    if not info:
        low_a, info = lapack.dpotrf(jac @ mij, lower=1)  # J M⁻¹ Jᵀ = L Lᵀ
    if not info:
        lam, info = lapack.dpotri(low_a, lower=1)  # its inverse, lower triangle
    if info:
        sv = np.linalg.svd(jac, compute_uv=False)
        raise SingularConfigurationError(
            f"the task Jacobian is singular at q = {q} (singular values {sv}): Λ = (J M⁻¹ Jᵀ)⁻¹ does not exist; "
            "move away from the singularity or control fewer axes",
            value=q,
            sigma_min=float(sv[-1]),
        )
    lam = np.tril(lam) + np.tril(lam, -1).T
    return lam, lam @ mij.T
