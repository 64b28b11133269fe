"""`InnerMotion`: the stiff motion loop inside admittance and force control — a frame driven to a commanded
pose x_c by inverse dynamics, in the operational space (``"osc"``) or by resolved acceleration and computed
torque (``"computed_torque"``), optionally compensating the measured wrench.

With e = [p_c − p; log(R_c Rᵀ)] and ė = v_c − J q̇ (world axes, as the OSC tasks), the commanded frame
acceleration and the posture acceleration are::

    ẍ* = a_c + K_P e + K_D ė,        q̈₀ = K_P,n (q_n − q) − K_D,n q̇

and the torque, with h the measured wrench the arm exerts (0 when not compensated)::

    "osc":              τ = Jᵀ Λ (ẍ* − J̇ q̇ − J q̈₀) + M q̈₀ + C q̇ + g + τ_f + Jᵀ h
    "computed_torque":  q̈ = J⁺ (ẍ* − J̇ q̇) + (I − J⁺ J) q̈₀,  J⁺ = Jᵀ (J Jᵀ)⁻¹,   τ = M q̈ + C q̇ + g + τ_f + Jᵀ h

With an exact model both give J q̈ + J̇ q̇ = ẍ*, that is ë + K_D ė + K_P e = 0 whatever the contact (the Jᵀ h
term cancels the wrench's effect); without the compensation the wrench displaces the frame by
(Λ K_P)⁻¹ h at rest ("osc"). They differ in the null space: "osc" keeps the posture motion dynamically
consistent, "computed_torque" kinematically. With ``compile`` the law is one call of generated C code
(:mod:`~armctl.controllers.interaction.generated_inner`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, all_finite, readonly
from armctl.codegen import Fallback, compile_mode
from armctl.controllers.interaction.gains import critical_damping, symmetric_psd
from armctl.controllers.interaction.task_space import task_inertia
from armctl.controllers.osc.state import FrameKinematics, ModelEvaluator, ModelState
from armctl.controllers.osc.tasks.rotation import rotation_error
from armctl.dynamics.base import Dynamics
from armctl.errors import SingularConfigurationError, UnknownNameError

#: a commanded frame motion: (pose (4×4), twist (6,) [m/s; rad/s], acceleration (6,) [m/s²; rad/s²]), world axes
Motion = tuple[FloatArray, FloatArray, FloatArray]

#: the inner loops
INNER = ("osc", "computed_torque")
#: what ``compile="auto"`` runs where the generated loop cannot be built
FALLBACK = Fallback(
    "the interaction controllers' generated inner loop", "the Pinocchio/NumPy loop", "several times slower"
)


class InnerMotion:
    """The inner motion loop (see the module).

    Parameters
    ----------
    dynamics : Dynamics
        The controller's model.
    kind : {"osc", "computed_torque"}
        The law.
    kp : array_like
        K_P [1/s²]: scalar, (6,) or 6×6, symmetric positive definite.
    kd : array_like, optional
        K_D [1/s]; None: 2 K_P^½ (critical).
    posture_kp, posture_kd : array_like, optional
        K_P,n [1/s²] ≥ 0 and K_D,n [1/s] (None: 2 K_P,n^½) of the posture (scalar, (n,) or n×n).
    frame : str, optional
        The controlled frame (None: the tool frame).
    compile : bool or "auto", optional
        Generated code for the law: "auto" where the dynamics are Pinocchio's and a C compiler builds it (else
        NumPy, with a PerformanceWarning once), True (or an error), False (NumPy).
    force_loop : bool, optional
        Generate the force loop of :mod:`~armctl.controllers.interaction.force_loop` with the law (its owner
        then calls the generated code itself; :meth:`command` takes the NumPy path).
    admittance : int, optional
        Likewise, the compliant frame of :class:`~armctl.controllers.Admittance` with that many axes (3 or 6); 0:
        none.

    Raises
    ------
    UnknownNameError
        ``kind`` is neither.
    InvalidParameterError, ShapeError
        A gain that is not symmetric positive (semi-)definite or of the wrong size.
    """

    def __init__(
        self,
        dynamics: Dynamics,
        kind: str,
        kp: ArrayLike,
        kd: ArrayLike | None = None,
        posture_kp: ArrayLike = 10.0,
        posture_kd: ArrayLike | None = None,
        frame: str | None = None,
        compile: bool | str = "auto",
        force_loop: bool = False,
        admittance: int = 0,
    ) -> None:
        if kind not in INNER:
            raise UnknownNameError("inner motion loop", kind, INNER)
        self.kind = kind
        self.dynamics = dynamics
        n = dynamics.n
        self.kp = symmetric_psd(kp, (6,), "kp", "1/s²", definite=True)
        self.kd = critical_damping(np.eye(6), self.kp) if kd is None else symmetric_psd(kd, (6,), "kd", "1/s")
        self.posture_kp = symmetric_psd(posture_kp, (n,), "posture_kp", "1/s²")
        self.posture_kd = (
            critical_damping(np.eye(n), self.posture_kp)
            if posture_kd is None
            else symmetric_psd(posture_kd, (n,), "posture_kd", "1/s")
        )
        for a in (self.kp, self.kd, self.posture_kp, self.posture_kd):
            readonly(a)
        self.frame = frame
        self.evaluator = ModelEvaluator(dynamics)
        self.evaluator.check_frame(frame)
        friction = dynamics.kernel.friction
        self._friction = friction if friction.any else None
        self.force_loop, self.admittance = force_loop, admittance
        self.generated = self._generated_law(compile)

    def _generated_law(self, compile: object) -> Any:
        """The generated law (a GeneratedInner) or None: the NumPy path."""
        mode = compile_mode(compile)
        from armctl.dynamics.pinocchio_backend import PinocchioDynamics

        if mode is False or (mode == "auto" and not isinstance(self.dynamics, PinocchioDynamics)):
            return None

        def make() -> Any:
            from armctl.controllers.interaction.generated_inner import GeneratedInner  # CasADi, imported on use

            return GeneratedInner(self.dynamics, self.frame, self.kind, self.force_loop, self.admittance)

        gen = FALLBACK.attempt(make, mode, stacklevel=5)
        if gen is None:
            return None
        if not (self.force_loop or self.admittance):
            gen.set_gains(self.kp, self.kd, self.posture_kp, self.posture_kd)
        return gen

    def with_friction(self, tau: FloatArray, qd: FloatArray) -> FloatArray:
        """τ + τ_f(q̇) (in place) if the model has friction."""
        if self._friction is not None:
            tau += self._friction.torque(qd)
        return tau

    def command(
        self, q: FloatArray, qd: FloatArray, goal: Motion, posture: FloatArray, wrench: FloatArray | None = None
    ) -> tuple[FloatArray, FloatArray]:
        """τ [N·m] and the frame error e (6,) [m; rad] at the measured (q, q̇) (checked finite by the caller), by
        the generated law where there is one (the NumPy path at a singular configuration, to name it).

        Parameters
        ----------
        q, qd : ndarray, shape (n,)
            The measured state [rad, rad/s].
        goal : tuple of ndarray
            The commanded motion (x_c (4×4), v_c (6,), a_c (6,)), world axes.
        posture : ndarray, shape (n,)
            q_n [rad].
        wrench : ndarray, shape (6,), optional
            h [N; N·m] to compensate; None: not compensated.
        """
        gen = self.generated
        if gen is not None and not (self.force_loop or self.admittance):
            out = gen.run(q, qd, goal, posture, wrench)
            if all_finite(out):
                n = self.dynamics.n
                return self.with_friction(out[:n], qd), out[n : n + 6]
        state = self.evaluator.evaluate(q, qd)
        return self.torque(state, state.frame(self.frame), goal, posture, wrench)

    def torque(
        self,
        state: ModelState,
        fk: FrameKinematics,
        goal: Motion,
        posture: FloatArray,
        wrench: FloatArray | None = None,
    ) -> tuple[FloatArray, FloatArray]:
        """τ [N·m] driving the frame to the commanded motion ``goal`` = (pose (4×4), twist (6,), acceleration
        (6,)), and the frame error e (6,) [m; rad].

        Parameters
        ----------
        state : ModelState
            The model terms at the measured (q, q̇).
        fk : FrameKinematics
            The frame's kinematics at that state.
        goal : tuple of ndarray
            (x_c (4×4), v_c (6,) [m/s; rad/s], a_c (6,) [m/s²; rad/s²]), world axes.
        posture : ndarray, shape (n,)
            q_n [rad].
        wrench : ndarray, shape (6,), optional
            h [N; N·m] to compensate (world axes at the frame); None: not compensated.
        """
        q, qd = state.q, state.qd
        pose, twist, acceleration = goal
        jac = fk.jacobian
        e = np.concatenate((pose[:3, 3] - fk.position, rotation_error(pose[:3, :3], fk.rotation)))
        xdd = acceleration + self.kp @ e + self.kd @ (twist - fk.velocity) - fk.drift
        qdd0 = self.posture_kp @ (posture - q) - self.posture_kd @ qd
        if self.kind == "osc":
            lam, _ = task_inertia(state.mass, jac, q)
            tau = jac.T @ (lam @ (xdd - jac @ qdd0)) + state.mass @ qdd0 + state.bias
        else:
            try:
                pinv = np.linalg.solve(jac @ jac.T, jac).T  # Jᵀ (J Jᵀ)⁻¹
            except np.linalg.LinAlgError:
                sv = np.linalg.svd(jac, compute_uv=False)
                raise SingularConfigurationError(
                    f"the frame Jacobian is singular at q = {q} (singular values {sv}): J⁺ does not exist",
                    value=q,
                    sigma_min=float(sv[-1]),
                ) from None
            qdd = pinv @ xdd + qdd0 - pinv @ (jac @ qdd0)
            tau = state.mass @ qdd + state.bias
        if wrench is not None:
            tau += jac.T @ wrench
        if state.friction is not None:
            tau += state.friction
        return tau, e
