"""`Admittance`: a compliant frame that yields to the measured wrench, tracked by a stiff inner motion loop."""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, all_finite, boolean, readonly, vector
from armctl.controllers.interaction.force_source import ForceInput
from armctl.controllers.interaction.gains import critical_damping, damping_ratio, symmetric_psd
from armctl.controllers.interaction.inner import InnerMotion
from armctl.controllers.interaction.spring import FRAME_SIZES, FRAME_UNITS, SpringLaw
from armctl.controllers.interaction.task_space import FrameTarget, PoseTargeted
from armctl.controllers.osc.tasks.rotation import rotation_error
from armctl.dynamics.base import Dynamics
from armctl.references import Reference


class Admittance(PoseTargeted, SpringLaw):
    """Admittance control (position-based impedance; Siciliano, Sciavicco, Villani & Oriolo, *Robotics:
    Modelling, Planning and Control*, 2009, §9.3): the measured wrench drives a compliant frame x_c through a
    mass–spring–damper about the target x_d, and an inner motion loop of your choice tracks x_c.

    Parameters
    ----------
    dynamics : Dynamics
        The controller's model.
    stiffness : array_like
        K_d [N/m; N·m/rad]: (6,) or 6×6 (rows [translation; rotation]), or (3,) or 3×3 for the position only
        (the orientation then tracks the target's), symmetric positive semi-definite.
    damping : array_like, optional
        D_d, of K_d's size, symmetric positive semi-definite; None: ζ-damped for M_d by double diagonalisation.
    frame : str, optional
        The controlled frame (None: the tool frame).
    inertia : array_like, optional
        M_d [kg; kg·m²], symmetric positive definite, of K_d's size; default 5 kg and 0.5 kg·m².
    force_source : "sensor" or observer, optional
        Where the wrench comes from (as in :class:`~armctl.controllers.ForceControl`).
    inner : {"computed_torque", "osc"}, optional
        The inner motion loop (:mod:`~armctl.controllers.interaction.inner`).
    kp, kd : array_like, optional
        Its gains K_P [1/s²] (default 900) and K_D [1/s] (None: 2 K_P^½).
    posture : array_like, optional
        q_n (n,) [rad] of the null-space posture; None: the joint reference ``ref.q``.
    posture_kp : array_like, optional
        K_P,n [1/s²] ≥ 0 of the posture (default 10).
    zeta : float, optional
        ζ ≥ 0 of the default damping; 1: critical.
    compile : bool or "auto", optional
        The inner loop as one call of generated C code: "auto" (the default) where the dynamics are Pinocchio's and
        a C compiler builds it, True (or an error), False (NumPy).
    compensate : bool, optional
        Add Jᵀ h, the measured wrench, to the inner loop's torque (default True), so that the frame follows x_c
        whatever the contact.

    Raises
    ------
    InvalidParameterError
        A stiffness that is not symmetric positive semi-definite, a negative damping, M_d not positive definite,
        ζ < 0, no force source.
    ShapeError
        A matrix of the wrong size.
    UnknownNameError
        ``frame`` or ``inner`` unknown.

    Notes
    -----
    With h the measured wrench the arm exerts (the environment's wrench on the arm is −h),
    e_c = [p_c − p_d; log(R_c R_dᵀ)] and ė_c = v_c − v_d, the compliant frame obeys::

        M_d (ẍ_c − a_d) + D_d ė_c + K_d e_c = −h

    integrated at the control rate (semi-implicit Euler over the time between calls: v_c, then
    p_c ← p_c + v_c Δt and R_c ← exp(ω_c Δt) R_c), starting at the target. The inner loop tracks (x_c, v_c,
    ẍ_c). At rest K_d e_c = −h: against a plane of stiffness k_e, with the target a depth δ_c beyond the
    surface, the force is k_e k_d / (k_e + k_d) δ_c, as for impedance control. Where it fails: the inner loop is
    stiff, so the contact is as stiff as the environment for the loop that reads the force: with a soft
    admittance (small M_d) on a stiff surface the loop rings or loses contact; with D_d too small the compliant
    frame bounces; without a force reading (a free motion) it is plain position control.

    ``last_log`` holds ``"wrench"`` h, ``"compliant"`` e_c [m; rad] and ``"error"`` the inner loop's frame error.
    """

    damping: FloatArray  # D_d: given, or derived from M_d and K_d

    def __init__(
        self,
        dynamics: Dynamics,
        stiffness: ArrayLike,
        damping: ArrayLike | None = None,
        frame: str | None = None,
        *,
        inertia: ArrayLike | None = None,
        force_source: Any = "sensor",
        inner: str = "computed_torque",
        kp: ArrayLike = 900.0,
        kd: ArrayLike | None = None,
        posture: ArrayLike | None = None,
        posture_kp: ArrayLike = 10.0,
        zeta: float = 1.0,
        compensate: bool = True,
        compile: bool | str = "auto",
    ) -> None:
        super().__init__(dynamics, stiffness, damping, FRAME_SIZES, FRAME_UNITS)
        owner = type(self).__name__
        m = self.axes = self.stiffness.shape[0]
        default_inertia = np.array([5.0, 5.0, 5.0, 0.5, 0.5, 0.5])[:m]
        self.inertia = symmetric_psd(
            default_inertia if inertia is None else inertia, (m,), "inertia", "kg; kg·m²", definite=True
        )
        if damping is None:
            self.damping = critical_damping(self.inertia, self.stiffness, damping_ratio(zeta))
        self._inv_inertia: FloatArray = np.asarray(np.linalg.inv(self.inertia), dtype=float)
        self.force_input = ForceInput(force_source, owner)
        self.reads = self.force_input.reads  # per instance: what it reads depends on the source
        self.frame = frame
        self.target = FrameTarget(owner, 6)
        self.inner = InnerMotion(
            dynamics, inner, kp, kd, posture_kp, frame=frame, compile=compile, admittance=self.axes
        )
        self.posture = None if posture is None else vector(posture, self.n, "posture")
        self.compensate = boolean(compensate, "compensate")
        for a in (self.stiffness, self.damping, self.inertia, self._inv_inertia):
            readonly(a)
        gen = self.inner.generated
        if gen is not None:
            inner_gains = (self.inner.kp, self.inner.kd, self.inner.posture_kp, self.inner.posture_kd)
            gen.set_gains(*inner_gains, self._inv_inertia, self.damping, self.stiffness, self.compensate)
        self._state: tuple[FloatArray, FloatArray, FloatArray] | None = None  # p_c, R_c, v_c
        self._t: float | None = None
        self._dt = np.zeros(1)

    def reset(self) -> None:
        super().reset()
        self.target.reset()
        self.force_input.reset()
        self._state = None
        self._t = None

    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        target = self.target
        if not target.holder.is_set:
            target.hold(self.dynamics.kernel.frame_pose(q, self.frame))
        pose_d, twist_d, acc_d = target.holder.at(t)
        h = self.force_input.wrench(self, t, q, qd, self.frame)
        if self._state is None or self._t is None or t < self._t:  # the start, or a new run's clock
            self._state = (pose_d[:3, 3].copy(), pose_d[:3, :3].copy(), twist_d.copy())
            self._t = t
        p_c, r_c, v_c = self._state
        dt = t - self._t
        self._t = t
        posture = self.posture if self.posture is not None else ref.q
        gen = self.inner.generated
        if gen is not None:
            self._dt[0] = dt
            out = gen.run_force((q, qd, pose_d.ravel(), twist_d, acc_d, posture, h, p_c, r_c.ravel(), v_c, self._dt))
            if all_finite(out):
                n, m = self.n, self.axes
                self._state = (out[n + 6 : n + 9], out[n + 9 : n + 18].reshape(3, 3).T, out[n + 18 : n + 24])
                self.last_log = {"wrench": h, "compliant": out[n + 24 :], "error": out[n : n + 6]}
                return self.inner.with_friction(out[:n], qd)
        m = self.axes
        e_c = np.concatenate((p_c - pose_d[:3, 3], -rotation_error(pose_d[:3, :3], r_c)))[:m]
        a_c = acc_d.copy()
        a_c[:m] += self._inv_inertia @ (-h[:m] - self.damping @ (v_c - twist_d)[:m] - self.stiffness @ e_c)
        v_c = v_c + a_c * dt
        if m == 3:  # the orientation tracks the target's
            v_c[3:] = twist_d[3:]
        p_c = p_c + v_c[:3] * dt
        r_c = pin.exp3(v_c[3:] * dt) @ r_c if m == 6 else pose_d[:3, :3]
        self._state = (p_c, r_c, v_c)
        cmd = np.eye(4)
        cmd[:3, :3], cmd[:3, 3] = r_c, p_c
        tau, e = self.inner.command(q, qd, (cmd, v_c, a_c), posture, h if self.compensate else None)
        self.last_log = {"wrench": h, "compliant": e_c, "error": e}
        return tau
