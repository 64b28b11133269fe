"""`CartesianImpedance`: a frame behaves as a mass–spring–damper about its target; a redundant arm's null space
is pulled towards a posture by a joint spring."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, boolean, readonly, vector
from armctl.codegen import Fallback, compile_mode
from armctl.controllers.interaction.force_source import ForceInput
from armctl.controllers.interaction.gains import critical_damping, damping_ratio, symmetric_psd
from armctl.controllers.interaction.spring import FRAME_SIZES, FRAME_UNITS, SpringLaw
from armctl.controllers.interaction.task_space import FrameTarget, task_inertia
from armctl.controllers.osc.state import ModelEvaluator
from armctl.controllers.osc.tasks.target import Trajectory
from armctl.dynamics.base import Dynamics
from armctl.references import Reference

#: what ``compile="auto"`` runs where the generated law cannot be built
FALLBACK = Fallback("the Cartesian impedance law's generated code", "the Pinocchio/NumPy law", "several times slower")


class CartesianImpedance(SpringLaw):
    """Cartesian impedance control of one frame, with null-space joint stiffness towards a posture and, if asked,
    inertia shaping from a measured wrench.

    Parameters
    ----------
    dynamics : Dynamics
        The controller's model: M(q), C(q, q̇) q̇, g(q), τ_f(q̇) and the frame's kinematics.
    stiffness : array_like
        K [N/m; N·m/rad]: a (6,) diagonal or a 6×6 matrix (rows [translation; rotation], world axes), or a (3,)
        diagonal or 3×3 matrix for the frame's position only; symmetric positive semi-definite.
    damping : array_like, optional
        D [N·s/m; N·m·s/rad], of K's size, symmetric positive semi-definite; None (the default): the damping
        that gives every mode the damping ratio ``zeta`` for the frame's inertia, recomputed at each step from
        Λ(q) (or from Λ_d) by double diagonalisation (:func:`~armctl.controllers.interaction.gains.critical_damping`).
    frame : str, optional
        The controlled frame (a name of the model's ``frame_names``); None: the tool frame.
    nullspace_stiffness : array_like, optional
        K_n [N·m/rad] ≥ 0 (scalar, (n,) or n×n) of the joint spring towards the posture; 0 (the default): none.
    nullspace_damping : array_like, optional
        D_n [N·m·s/rad] ≥ 0; None: 2 K_n^½ (the Panda example controller's choice).
    posture : array_like, optional
        q_n (n,) [rad], the posture of the null-space spring; None (the default): the joint reference ``ref.q``.
    inertia : array_like, optional
        Λ_d [kg; kg·m²], symmetric positive definite, of K's size: the inertia the frame shows its environment.
        Given, the controller reads the wrench (``reads = {"wrench"}``, or the applied torques with an
        observer as ``force_source``). None (the default): the arm's own Λ(q), no force reading.
    force_source : "sensor" or observer, optional
        Where the wrench for inertia shaping comes from (see :mod:`~armctl.controllers.interaction.force_source`).
    zeta : float, optional
        ζ ≥ 0, the damping ratio of the default damping; 1: critical.
    friction : bool, optional
        Compensate the model's joint friction τ_f(q̇) (default True).
    compile : bool or "auto", optional
        Without ``inertia``, evaluate the law in one call of generated C code (the default damping then from the
        Λ(q) it returns; :mod:`~armctl.controllers.interaction.generated`; at a singular configuration the NumPy
        path names it):
        ``"auto"`` (the default) where the dynamics are Pinocchio's and a C compiler builds it (else NumPy, with a
        :class:`~armctl.errors.PerformanceWarning` once), True (or an error), False (NumPy).

    Raises
    ------
    InvalidParameterError
        A stiffness that is not symmetric positive semi-definite, a negative damping, a Λ_d that is not positive
        definite, ζ < 0, a force source that is neither "sensor" nor an observer.
    ShapeError
        A matrix of the wrong size.
    UnknownNameError
        ``frame`` is not one of the model's (the error lists them).
    BackendError
        ``compile=True`` and the generated code cannot be built.

    Notes
    -----
    With the frame's error e and ė (:mod:`~armctl.controllers.interaction.task_space`: e = [p_d − p; log(R_d Rᵀ)],
    ė = v_d − J q̇, world axes), the target's acceleration a_d, J the frame Jacobian, Λ = (J M⁻¹ Jᵀ)⁻¹ and
    J̄ᵀ = Λ J M⁻¹, the law is::

        τ = Jᵀ F + Nᵀ τ_n + C(q, q̇) q̇ + g(q) + τ_f(q̇),      Nᵀ = I − Jᵀ J̄ᵀ,
        τ_n = K_n (q_n − q) − D_n q̇,
        F = K e + D ė + Λ a_d                                (no inertia shaping)
        F = Λ (a_d + Λ_d⁻¹ (K e + D ė − h) − J̇ q̇) + h        (inertia shaping, h the measured wrench)

    With an exact model, and h the wrench the arm exerts on its environment (the sign of
    :meth:`armctl.Dynamics.inverse_dynamics`' ``wrench``), the frame then obeys

        Λ(q) (ẍ − J̇ q̇ − a_d) + D ė + K e = −h        or        Λ_d ë + D ė + K e = h     (ë = a_d − ẍ)

    and Nᵀ τ_n acts in the dynamically consistent null space only (J M⁻¹ Nᵀ = 0). At rest against an
    environment the frame's force is therefore h = K e exactly: against a plane of stiffness k_e, with the
    target a depth δ_c beyond the surface along a stiffness k_d, the force is k_e k_d / (k_e + k_d) · δ_c.

    Without inertia shaping nothing is measured but q and q̇ (the Panda example controller and
    Mayr & Salt-Ducaju's package compensate Coriolis and gravity the same way, with D = 2 K^½ and a
    pseudo-inverse null space). Where it fails: K and the environment's stiffness k_e make a contact mode of
    frequency √((k + k_e)/Λ) that a 1 kHz loop must resolve (stiff targets on stiff surfaces chatter); at a
    singular configuration Λ does not exist (:class:`~armctl.errors.SingularConfigurationError`).

    The gains are fixed at construction (read-only arrays). ``last_log`` holds ``"error"`` e, ``"force"`` F and,
    with inertia shaping, ``"wrench"`` h.
    """

    def __init__(
        self,
        dynamics: Dynamics,
        stiffness: ArrayLike,
        damping: ArrayLike | None = None,
        frame: str | None = None,
        *,
        nullspace_stiffness: ArrayLike = 0.0,
        nullspace_damping: ArrayLike | None = None,
        posture: ArrayLike | None = None,
        inertia: ArrayLike | None = None,
        force_source: Any = "sensor",
        zeta: float = 1.0,
        friction: bool = True,
        compile: bool | str = "auto",
    ) -> None:
        super().__init__(dynamics, stiffness, damping, FRAME_SIZES, FRAME_UNITS)
        m = self.axes = self.stiffness.shape[0]
        self.zeta = damping_ratio(zeta)
        self.evaluator = ModelEvaluator(dynamics)
        self.evaluator.check_frame(frame)
        self.frame = frame
        self.target = FrameTarget(type(self).__name__, m)
        n = self.n
        self.nullspace_stiffness = symmetric_psd(nullspace_stiffness, (n,), "nullspace_stiffness", "N·m/rad")
        self.nullspace_damping = (
            critical_damping(np.eye(n), self.nullspace_stiffness)
            if nullspace_damping is None
            else symmetric_psd(nullspace_damping, (n,), "nullspace_damping", "N·m·s/rad")
        )
        self.posture = None if posture is None else vector(posture, n, "posture")
        self.inertia = None if inertia is None else symmetric_psd(inertia, (m,), "inertia", "kg; kg·m²", True)
        self.force: ForceInput | None = None
        if self.inertia is not None:
            self.force = ForceInput(force_source, type(self).__name__)
            self.reads = self.force.reads  # per instance: what it reads depends on the source
            if self.damping is None:
                self.damping = critical_damping(self.inertia, self.stiffness, self.zeta)
        self.friction = boolean(friction, "friction")
        self._null = bool(np.any(self.nullspace_stiffness) or np.any(self.nullspace_damping))
        for a in (self.stiffness, self.damping, self.nullspace_stiffness, self.nullspace_damping, self.inertia):
            if a is not None:
                readonly(a)
        self._generated = self._generated_law(compile)
        self._outputs = (slice(0, n), slice(n, n + m), slice(n + m, n + 2 * m))  # τ, e, F in its [τ; e; F]
        # the NumPy path holds a pose, and a subclass's own compute may keep state: their inputs are checked first
        self._checks_result = type(self).result_check and self._generated is not None
        kernel_friction = dynamics.kernel.friction
        self._friction_terms = kernel_friction if self.friction and kernel_friction.any else None

    def _generated_law(self, compile: object) -> Any:
        """The generated law (a GeneratedImpedance) or None: the NumPy path."""
        mode = compile_mode(compile)
        if mode is False or self.inertia is not None:
            return None
        from armctl.dynamics.pinocchio_backend import PinocchioDynamics

        if mode == "auto" and not isinstance(self.dynamics, PinocchioDynamics):
            return None

        def make() -> Any:
            from armctl.controllers.interaction.generated import GeneratedImpedance  # CasADi, imported on use

            return GeneratedImpedance(self.dynamics, self.frame, self.axes, self._null, split=self.damping is None)

        gen = FALLBACK.attempt(make, mode, stacklevel=4)
        if gen is None:
            return None
        gen.set_gains(self.stiffness, self.damping, self.nullspace_stiffness, self.nullspace_damping)
        if gen.split:
            gen.set_damping_ratio(self.zeta)
        return gen

    def set_target(
        self, target: ArrayLike, velocity: ArrayLike | None = None, acceleration: ArrayLike | None = None
    ) -> None:
        """Set a constant target (world axes); it replaces a trajectory. Unset, the frame holds the pose it has
        at the first call.

        Parameters
        ----------
        target : array_like
            6 axes: the 4×4 pose (R_d, p_d [m]); 3 axes: the position p_d (3,) [m].
        velocity : array_like, optional
            v_d: the twist [m/s; rad/s] (6,) or velocity (3,); None: zero.
        acceleration : array_like, optional
            a_d [m/s²; rad/s²], the feed-forward; None: zero.
        """
        self.target.set(target, velocity, acceleration)

    def set_trajectory(self, fn: Trajectory) -> None:
        """Follow a trajectory; it replaces a constant target.

        Parameters
        ----------
        fn : callable
            ``fn(t) -> (target, velocity, acceleration)`` with t [s], in :meth:`set_target`'s terms (velocity and
            acceleration may be None: zero).
        """
        self.target.follow(fn)

    def reset(self) -> None:
        super().reset()
        self.target.reset()
        if self.force is not None:
            self.force.reset()

    #: the generated law checks its own inputs (see :meth:`compute`): ``__call__`` checks only τ
    result_check = True

    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        gen = self._generated
        if gen is not None:
            # Called on unchecked q and q̇ (result_check): nothing is kept (the held pose, last_log) and no user
            # function is called (a trajectory, on t) before they are known to be finite.
            goal = self.target.fixed  # a constant target: nothing to call, once t is known finite
            if goal is None or not math.isfinite(t):
                goal, q, qd = self.target.goal_unchecked(t, q, qd, self._checked, self.dynamics.kernel, self.frame)
            # gen.run(q, qd, goal, posture), written out: this is the whole per-step cost of the law
            pieces = gen.pieces
            pieces[0][...] = q
            pieces[1][...] = qd
            if goal is not gen.target:
                gen.load_target(goal)
            if self._null:
                pieces[5][...] = self.posture if self.posture is not None else ref.q
            gen.evaluate()
            if math.isfinite(gen.check.item()):  # NaN at a singular configuration: the NumPy path names it
                # the default damping, from Λ(q): one eigendecomposition between the two stages of the code
                out = gen.damp() if gen.split else gen.out.copy()
                at_tau, at_error, at_force = self._outputs
                tau = out[at_tau]
                if self._friction_terms is not None:
                    tau += self._friction_terms.torque(qd)
                self.last_log = {"error": out[at_error], "force": out[at_force]}
                return tau
            q, qd = self._checked(t, q, qd)  # a non-finite input named, before the NumPy path
        return self._numpy_law(t, q, qd, ref)

    def _numpy_law(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        state = self.evaluator.evaluate(q, qd)
        fk = state.frame(self.frame)
        value, vel, acc = self.target.at(t, fk)
        m = self.axes
        jac = fk.jacobian[:m]
        e = self.target.error(value, fk)
        edot = vel - fk.velocity[:m]
        log: dict[str, Any] = {"error": e}
        if self.damping is not None and not self._null and self.inertia is None and not acc.any():
            force = self.stiffness @ e + self.damping @ edot  # the stiffness alone: no Λ needed
            tau = jac.T @ force + state.bias
        else:
            lam, jbar_t = task_inertia(state.mass, jac, q)
            damping = self.damping if self.damping is not None else critical_damping(lam, self.stiffness, self.zeta)
            spring = self.stiffness @ e + damping @ edot
            if self.inertia is None or self.force is None:
                force = spring + lam @ acc if acc.any() else spring
            else:
                h = self.force.wrench(self, t, q, qd, self.frame)[:m]
                force = lam @ (acc + np.linalg.solve(self.inertia, spring - h) - fk.drift[:m]) + h
                log["wrench"] = h
            tau = jac.T @ force + state.bias
            if self._null:
                posture = self.posture if self.posture is not None else ref.q
                tau_n = self.nullspace_stiffness @ (posture - q) - self.nullspace_damping @ qd
                tau += tau_n - jac.T @ (jbar_t @ tau_n)
        if self.friction and state.friction is not None:
            tau += state.friction
        log["force"] = force
        self.last_log = log
        return tau
