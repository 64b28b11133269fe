"""`ForceLoop`: what force control and parallel force/position control share — the desired force, the
PI action on the force error, the force source and the inner motion loop.

    e_f = P (f_d − f),    x_F = K_F e_f + K_I ∫ e_f dt   [m]

f [N] is the force the arm exerts (world axes), f_d the desired one, P the projector on the force-controlled
directions. The commanded position p_c = p_d + P x_F goes to the inner motion loop
(:class:`~armctl.controllers.interaction.inner.InnerMotion`): where the environment resists, pushing the command
into it raises the force, so x_F moves towards the force wanted; the integral makes the error vanish at rest.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, boolean, readonly, real_array, vector
from armctl.controllers.base import Controller
from armctl.controllers.interaction.force_source import ForceInput
from armctl.controllers.interaction.gains import symmetric_psd
from armctl.controllers.interaction.inner import InnerMotion
from armctl.controllers.interaction.task_space import FrameTarget, PoseTargeted
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError
from armctl.references import Reference


class ForceTarget:
    """t → f_d (3,) [N] from a constant (3,) or a callable (its output checked at each call); picklable when the
    callable is.

    Parameters
    ----------
    force : array_like or callable
        f_d, or t [s] → f_d.
    """

    def __init__(self, force: Any) -> None:
        self.fn = force if callable(force) else None
        # a constant: a read-only copy (later changes to the array given do not reach it)
        self.value = None if callable(force) else readonly(vector(force, 3, "force").copy())

    def __call__(self, t: float) -> FloatArray:
        if self.fn is not None:
            return vector(self.fn(t), 3, "force(t)")
        assert self.value is not None  # set whenever fn is None
        return self.value


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


class ForceLoop(PoseTargeted, Controller):
    """The shared machinery (see the module), with :class:`~armctl.controllers.ForceControl`'s constructor;
    :class:`ParallelForcePosition` leaves ``directions`` at all three axes.

    Parameters
    ----------
    dynamics, force, force_gain, integral_gain, frame, directions, force_source, inner, kp, kd, posture,
    posture_kp, compensate, compile
        As in :class:`~armctl.controllers.ForceControl`.
    """

    dynamics: Dynamics

    def __init__(
        self,
        dynamics: Dynamics,
        force: Any,
        force_gain: ArrayLike,
        integral_gain: ArrayLike = 0.0,
        frame: str | None = None,
        *,
        directions: ArrayLike | None = None,
        force_source: Any = "sensor",
        inner: str = "computed_torque",
        kp: ArrayLike = 400.0,
        kd: ArrayLike | None = None,
        posture: ArrayLike | None = None,
        posture_kp: ArrayLike = 10.0,
        compensate: bool = True,
        compile: bool | str = "auto",
    ) -> None:
        p = projector(directions)
        super().__init__(dynamics)
        owner = type(self).__name__
        self.force_input = ForceInput(force_source, owner)
        self.reads = self.force_input.reads  # per instance: what it reads depends on the source
        self._sensor = self.force_input.source == "sensor"
        # an observer keeps state from q and q̇, and a subclass's own compute may: their inputs are checked first
        self._checks_result = type(self).result_check and self._sensor
        self.force_target = ForceTarget(force)
        self.force_gain = readonly(symmetric_psd(force_gain, (3,), "force_gain", "m/N"))
        self.integral_gain = readonly(symmetric_psd(integral_gain, (3,), "integral_gain", "m/(N·s)"))
        self.directions = readonly(p)
        self._free = readonly(np.eye(3) - self.directions)
        self.frame = frame
        self.target = FrameTarget(owner, 6)
        self.inner = InnerMotion(dynamics, inner, kp, kd, posture_kp, frame=frame, compile=compile, force_loop=True)
        self.posture = None if posture is None else vector(posture, self.n, "posture")
        self.compensate = boolean(compensate, "compensate")
        self._pkf = readonly(self.directions @ self.force_gain)
        self._pki = readonly(self.directions @ self.integral_gain)
        self._free6 = np.eye(6)
        self._free6[:3, :3] = self._free
        readonly(self._free6)
        gen = self.inner.generated
        if gen is not None:
            inner_gains = (self.inner.kp, self.inner.kd, self.inner.posture_kp, self.inner.posture_kd)
            gen.set_gains(*inner_gains, self.directions, self._pkf, self._pki, self.compensate)
        self._integral = np.zeros(3)  # ∫ e_f dt [N·s], by the rectangle rule between calls
        n = self.n  # where τ, e, e_f, ∫e_f and x_F are in the generated law's output
        self._outputs = tuple(
            slice(a, b) for a, b in ((0, n), (n, n + 6), (n + 6, n + 9), (n + 9, n + 12), (n + 12, n + 15))
        )
        self._t: float | None = None

    def reset(self) -> None:
        super().reset()
        self._integral = np.zeros(3)
        self._t = None
        self.target.reset()
        self.force_input.reset()

    #: with a sensor, the generated law checks its own inputs (see :meth:`compute`): ``__call__`` checks τ only
    result_check = True

    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        # With a sensor q and q̇ come unchecked (result_check): nothing is kept (the held pose, the integral, the
        # time, last_log) and no user function is called (f_d(t), a trajectory) before they are known finite.
        goal = self.target.fixed  # a constant target: nothing to call, once t is known finite
        if goal is None or not math.isfinite(t):
            goal, q, qd = self.target.goal_unchecked(t, q, qd, self._checked, self.dynamics.kernel, self.frame)
        m = self.measurement
        if self._sensor and m is not None and m.world_axes and m.frame == self.frame and m.wrench is not None:
            h = m.wrench  # already in world axes at the frame (what force_input.wrench gives, without its calls)
        else:
            h = self.force_input.wrench(self, t, q, qd, self.frame)  # an observer's inputs are checked first
        force_target = self.force_target
        f_d = force_target(t)
        dt = t - self._t if self._t is not None and t > self._t else 0.0  # a new run's clock restarts: no step back
        posture = self.posture if self.posture is not None else ref.q
        gen = self.inner.generated
        if gen is not None:
            out = gen.run_force_loop(q, qd, goal, posture, h, f_d, force_target.fn is None, self._integral, dt)
            if math.isfinite(gen.check.item()):  # inputs and outputs finite
                self._t = t
                at_tau, at_error, at_force_error, at_integral, at_offset = self._outputs
                self._integral = out[at_integral]
                self.last_log = {
                    "force_error": out[at_force_error],
                    "offset": out[at_offset],
                    "wrench": h,
                    "error": out[at_error],
                }
                return self.inner.with_friction(out[at_tau], qd)
        q, qd = self._checked(t, q, qd)  # a non-finite input named, before the NumPy path
        self._t = t
        pose, twist, acc = goal
        e_f = self.directions @ (f_d - h[:3])
        integral = self._integral + e_f * dt
        x_f = self._pkf @ e_f + self._pki @ integral
        cmd = pose.copy()
        cmd[:3, 3] += x_f
        tau, e = self.inner.command(
            q, qd, (cmd, self._free6 @ twist, self._free6 @ acc), posture, h if self.compensate else None
        )
        self._integral = integral
        self.last_log = {"force_error": e_f, "offset": x_f, "wrench": h, "error": e}
        return tau
