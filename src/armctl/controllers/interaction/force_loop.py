"""`ForceLoop`: what force control and parallel force/position control share — the desired force, the
PI action on the force error, the force source and the inner motion loop.

    e_f = P (f_d − f),    x_F = K_F e_f + K_I ∫ e_f dt   [m]

f [N] is the force the arm exerts (world axes), f_d the desired one, P the projector on the force-controlled
directions. The commanded position p_c = p_d + P x_F goes to the inner motion loop
(:class:`~armctl.controllers.interaction.inner.InnerMotion`): where the environment resists, pushing the command
into it raises the force, so x_F moves towards the force wanted; the integral makes the error vanish at rest.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, boolean, readonly, real_array, vector
from armctl.controllers.base import Controller
from armctl.controllers.integral import ErrorIntegral
from armctl.controllers.interaction.force_source import ForceInput
from armctl.controllers.interaction.gains import symmetric_psd
from armctl.controllers.interaction.inner import InnerMotion
from armctl.controllers.interaction.task_space import FrameTarget
from armctl.controllers.osc.tasks.target import Trajectory
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError
from armctl.references import Reference


def force_target(force: Any) -> Callable[[float], FloatArray]:
    """t → f_d (3,) [N] from a constant (3,) or a callable (checked at each call)."""
    if callable(force):
        return lambda t: vector(force(t), 3, "force(t)")
    f = vector(force, 3, "force")
    return lambda t: f


def projector(directions: ArrayLike | None) -> FloatArray:
    """P (3×3), the orthogonal projector on the span of ``directions`` ((3,) or (k, 3) rows); None: I."""
    if directions is None:
        return np.eye(3)
    d = real_array(directions, "directions")
    d = d.reshape(1, 3) if d.shape == (3,) else d
    if d.ndim != 2 or d.shape[1] != 3 or not 1 <= d.shape[0] <= 3 or not np.isfinite(d).all():
        raise InvalidParameterError(
            f"directions must be a (3,) vector or (k, 3) rows (k ≤ 3) of world axes, got {directions!r}",
            value=directions,
        )
    u, s, _ = np.linalg.svd(d.T, full_matrices=False)
    if s[-1] <= 1e-9 * s[0]:
        raise InvalidParameterError(f"directions must be linearly independent, got {directions!r}", value=directions)
    return np.asarray(u @ u.T)


class ForceLoop(Controller):
    """The shared machinery (see the module); :class:`ForceControl` and :class:`ParallelForcePosition` set P.

    Parameters
    ----------
    dynamics, force, force_gain, integral_gain, frame, force_source, inner, kp, kd, posture, posture_kp,
    compensate, compile
        As in :class:`~armctl.controllers.ForceControl`.
    directions : ndarray, shape (3, 3)
        P.
    """

    dynamics: Dynamics

    def __init__(
        self,
        dynamics: Dynamics,
        force: Any,
        force_gain: ArrayLike,
        integral_gain: ArrayLike,
        frame: str | None,
        directions: FloatArray,
        force_source: Any,
        inner: str,
        kp: ArrayLike,
        kd: ArrayLike | None,
        posture: ArrayLike | None,
        posture_kp: ArrayLike,
        compensate: bool,
        compile: bool | str,
    ) -> None:
        super().__init__(dynamics)
        owner = type(self).__name__
        self.force_input = ForceInput(force_source, owner)
        self.reads = self.force_input.reads  # type: ignore[misc]  # per instance: what it reads depends on the source
        self.force_target = force_target(force)
        self.force_gain = symmetric_psd(force_gain, (3,), "force_gain", "m/N")
        self.integral_gain = symmetric_psd(integral_gain, (3,), "integral_gain", "m/(N·s)")
        self.directions = readonly(np.array(directions))
        self._free = readonly(np.eye(3) - self.directions)
        self.frame = frame
        self.target = FrameTarget(owner, 6)
        self.inner = InnerMotion(dynamics, inner, kp, kd, posture_kp, frame=frame, compile=compile)
        self.posture = None if posture is None else vector(posture, self.n, "posture")
        self.compensate = boolean(compensate, "compensate")
        self._integral = ErrorIntegral(3)

    def set_target(
        self, pose: ArrayLike, twist: ArrayLike | None = None, acceleration: ArrayLike | None = None
    ) -> None:
        """Set the motion target (world axes): the 4×4 pose p_d, R_d [m], the twist [m/s; rad/s] and the
        acceleration [m/s²; rad/s²] (None: zero). Unset, the frame holds the pose it has at the first call.

        Parameters
        ----------
        pose : array_like, shape (4, 4)
            The pose.
        twist, acceleration : array_like, shape (6,), optional
            Its rates.
        """
        self.target.set(pose, twist, acceleration)

    def set_trajectory(self, fn: Trajectory) -> None:
        """Follow a motion trajectory.

        Parameters
        ----------
        fn : callable
            ``fn(t) -> (pose, twist, acceleration)`` in :meth:`set_target`'s terms.
        """
        self.target.follow(fn)

    def reset(self) -> None:
        super().reset()
        self._integral.reset()
        self.target.reset()
        self.force_input.reset()

    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        target = self.target
        if not target.holder.is_set:
            target.hold(self.dynamics.kernel.frame_pose(q, self.frame))
        pose, twist, acc = target.holder.at(t)
        h = self.force_input.wrench(self, t, q, qd, self.frame)
        p = self.directions
        e_f = p @ (self.force_target(t) - h[:3])
        x_f = p @ (self.force_gain @ e_f + self.integral_gain @ self._integral.update(t, e_f))
        cmd = pose.copy()
        cmd[:3, 3] += x_f
        free = self._free
        twist_c, acc_c = twist.copy(), acc.copy()
        twist_c[:3] = free @ twist[:3]
        acc_c[:3] = free @ acc[:3]
        posture = self.posture if self.posture is not None else ref.q
        tau, e = self.inner.command(q, qd, cmd, twist_c, acc_c, posture, h if self.compensate else None)
        self.last_log = {"force_error": e_f, "offset": x_f, "wrench": h, "error": e}
        return tau
