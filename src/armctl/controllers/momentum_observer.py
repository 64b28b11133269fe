"""`MomentumObserver`: the external joint torques estimated from the model and the measured q, q̇ and applied τ,
without a force sensor (De Luca and Mattone; Haddadin, De Luca and Albu-Schäffer, *Robot Collisions: A Survey on
Detection, Isolation, and Identification*, IEEE T-RO 2017).

With the generalized momentum p = M(q) q̇ and Ṁ = C + Cᵀ, the Lagrange model
M q̈ + C q̇ + g = τ − τ_f − τ_ext (τ_ext = J(q)ᵀ h_e, the sign of :attr:`armctl.sim.SimResult.tau_ext`) reads

    ṗ = τ + β(q, q̇) − τ_ext,      β = C(q, q̇)ᵀ q̇ − g(q) − τ_f(q̇),

which needs no acceleration. The residual r = K_O (∫(τ + β − r) dt − p + p₀) obeys ṙ = K_O (τ_ext − r): each
joint's entry follows its external torque through a first-order lag of time constant 1/K_O.

Discrete time. Between two updates at t_{k−1} and t_k = t_{k−1} + h the drives hold τ_{k−1} (zero-order hold), so
its integral is exactly h τ_{k−1}; β is integrated by the trapezoidal rule. The period's mean external torque is

    d_k = (h τ_{k−1} + ½ h (β_k + β_{k−1}) − (p_k − p_{k−1})) / h,

and the residual is the first-order lag r_k = γ r_{k−1} + (1 − γ) d_k, sampled exactly (γ = exp(−K_O h), stable for
every gain) or by the textbook's forward-Euler sum (γ = 1 − K_O h, unstable for K_O h ≥ 2, which the observer
refuses): :mod:`armctl.controllers.residual_lag`.

Collision detection and isolation: a collision is declared at the first update where |r_j| exceeds the
threshold of some joint j; the last such joint along the chain names the link that was hit (an external torque
at link i reaches only joints 1..i). An ``on_collision`` hook is called once, then; the detection latches until
:meth:`MomentumObserver.reset` or :meth:`MomentumObserver.clear`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FLOAT, FloatArray, boolean, per_joint, readonly, scalar, vector
from armctl.codegen.policy import compile_mode
from armctl.controllers.collision import Collision, explaining_wrench, isolate
from armctl.controllers.momentum_code import FALLBACK, CompiledStep, CompiledUpdate
from armctl.controllers.residual_lag import DISCRETIZATIONS, check_lag_gain, lag_pole
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError, NonFiniteError


class MomentumObserver(CompiledUpdate):
    """The generalized-momentum observer of the external joint torques (see the module for the equations).

    Parameters
    ----------
    dynamics : Dynamics
        The model the observer trusts (the controller's own: it may be wrong, and then so is the estimate).
    gain : float or (n,) array_like
        K_O [1/s], one per joint or one for all: the residual's bandwidth (time constant 1/K_O).
    friction : bool, optional
        Whether the model's joint friction τ_f(q̇) = F_v q̇ + F_c sgn q̇ is subtracted (default True); False: the
        observer is told not to know it, and reads friction as an external torque.
    thresholds : float or (n,) array_like, optional
        Collision thresholds on |r_j| [N·m], fixed at construction; None (default): no detection.
    period : float, optional
        The update period h [s] if known in advance: the gain bound of the ``"euler"`` form is checked here
        rather than at the first update.
    discretization : {"exact", "euler"}, optional
        The residual's update (see the module); default ``"exact"``.
    on_collision : callable, optional
        ``on_collision(observer, collision)``, called once at the update that detects a collision (e.g. to switch
        a controller to gravity compensation or to a reflex).
    compile : {"auto", True, False}, optional
        Run the update as one call of generated C code (:mod:`armctl.controllers.momentum_code`; the same numbers
        to rounding, built once per arm with the system's C compiler and cached), under the compile policy of
        :mod:`armctl.codegen.policy`: ``"auto"`` (the default) where it can be built, else the update on the
        dynamics' kernel with a :class:`~armctl.errors.PerformanceWarning`; True: the code or a
        :class:`~armctl.errors.BackendError`; False: the kernel. The code evaluates the model as the
        ``"pinocchio"`` backend does (rotors as reflected inertia): ``"auto"`` uses it on that backend only, and
        with the ``"exact"`` form only.

    Raises
    ------
    InvalidParameterError
        A gain ≤ 0, a gain too large for ``period`` in the ``"euler"`` form (K_O h ≥ 2), a threshold < 0, an
        unknown discretization, an ``on_collision`` that is not callable, ``compile=True`` with ``"euler"``.
    BackendError
        ``compile=True`` and the code cannot be built (no C compiler, nor a cached build).

    Examples
    --------
    >>> obs = MomentumObserver(dyn, gain=50.0, thresholds=5.0)             # doctest: +SKIP
    >>> tau_ext = obs.update(t, q, qd, tau_applied)                       # doctest: +SKIP
    >>> if obs.collision: print(obs.collision.link, obs.wrench(q))        # doctest: +SKIP
    """

    def __init__(
        self,
        dynamics: Dynamics,
        gain: ArrayLike,
        *,
        friction: bool = True,
        thresholds: ArrayLike | None = None,
        period: float | None = None,
        discretization: str = "exact",
        on_collision: Callable[[MomentumObserver, Collision], Any] | None = None,
        compile: bool | str = "auto",
    ) -> None:
        if not isinstance(dynamics, Dynamics):
            raise InvalidParameterError(
                f"dynamics must be an armctl.Dynamics, got {type(dynamics).__name__}", value=dynamics
            )
        self.dynamics = dynamics
        self.n = n = dynamics.n
        k = per_joint(gain, n, "gain (K_O)")
        if not np.isfinite(k).all() or (k <= 0).any():
            raise InvalidParameterError(
                f"the observer gain K_O must be finite and > 0 [1/s], got {k.tolist()}: it is the residual's "
                f"bandwidth (time constant 1/K_O)",
                value=gain,
            )
        self.gain = readonly(k)
        if discretization not in DISCRETIZATIONS:
            raise InvalidParameterError(
                f"discretization must be one of {DISCRETIZATIONS}, got {discretization!r}", value=discretization
            )
        self.discretization = discretization
        self.friction = boolean(friction, "friction")
        if thresholds is None:
            self.thresholds: FloatArray | None = None
        else:
            th = per_joint(thresholds, n, "thresholds")
            if np.isnan(th).any() or (th < 0).any():
                raise InvalidParameterError(f"collision thresholds must be >= 0 [N·m], got {th.tolist()}", value=th)
            self.thresholds = readonly(th)
        if on_collision is not None and not callable(on_collision):
            raise InvalidParameterError(f"on_collision must be callable, got {on_collision!r}", value=on_collision)
        self.on_collision = on_collision
        self.period = None if period is None else scalar(period, "period", positive=True)
        if self.period is not None:
            self.check_gain(self.period)
        self._names = [j.name for j in dynamics.model.joints]
        self._shape = (self.n,)
        mode = compile_mode(compile)
        if mode is True and discretization != "exact":
            raise InvalidParameterError(
                "compile=True runs the 'exact' discretization only: use compile=False or discretization='exact'",
                value=discretization,
            )
        if mode == "auto" and (discretization != "exact" or dynamics.backend != "pinocchio"):
            mode = False
        self._code: Any = FALLBACK.attempt(
            lambda: CompiledStep(dynamics.kernel, self.friction, self.thresholds), mode, stacklevel=2
        )
        #: whether the update runs as generated code
        self.compiled = self._code is not None
        if self._code is not None:
            self.step = self._compiled_step  # type: ignore[method-assign]  # one call fewer on the hot path
        # whether NaN or inf in any entry of any input reaches r, so that checking r is enough: the generated code
        # carries them (momentum_code), and a kernel whose Coriolis matrix propagates them (β holds C(q, q̇))
        self._fast = self._code is not None or dynamics.kernel.nan_propagates
        self.reset()

    # ------------------------------------------------------------------------------------------- state
    def reset(self) -> None:
        """Forget the past: the next update starts the observer (its residual zero) and clears a detection."""
        self._t: float | None = None
        self._p: FloatArray | None = None
        self._beta: FloatArray | None = None
        self._h = -1.0  # the period the coefficients are for (none yet)
        self._gamma = np.zeros(self.n)
        self._lag_gain = np.ones(self.n)
        #: the last estimate r of τ_ext [N·m] (the array the last update returned)
        self.residual: FloatArray = np.zeros(self.n)
        self._side = 0  # the compiled code's state buffer in use
        self.collision: Collision | None = None  #: the detected collision, None before one

    def clear(self) -> None:
        """Clear a detected collision (the residual and the integration go on)."""
        self.collision = None

    def check_gain(self, h: float) -> None:
        """Raise if K_O is too large for the period ``h`` [s] in the ``"euler"`` form (K_O h ≥ 2: the residual's
        pole 1 − K_O h leaves the unit circle); the ``"exact"`` form is stable for every K_O > 0.

        Parameters
        ----------
        h : float
            The update period [s].

        Raises
        ------
        InvalidParameterError
            The bound is violated: it names the largest gain the period allows.
        """
        check_lag_gain(self.gain, h, self.discretization)

    # ------------------------------------------------------------------------------------ the update
    def momentum_terms(self, q: FloatArray, qd: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The momentum and the rest of its rate at (q, q̇), on the kernel (unchecked).

        Parameters
        ----------
        q, qd : ndarray, shape (n,)
            Joint positions and velocities, float64, finite.

        Returns
        -------
        p, beta : ndarray, shape (n,)
            p = M(q) q̇ [N·m·s] and β = C(q, q̇)ᵀ q̇ − g(q) (− τ_f(q̇) when the observer knows the friction) [N·m].
        """
        k = self.dynamics.kernel
        p = k.mass(q).dot(qd)  # (ndarray.dot: the matmul operator costs more on the arrays Pinocchio returns)
        beta = qd.dot(k.coriolis(q, qd))  # Cᵀ q̇
        beta -= k.gravity(q)
        if self.friction and k.friction.any:
            beta -= k.friction_torque(qd)
        return p, beta

    def update(self, t: float, q: ArrayLike, qd: ArrayLike, tau_applied: ArrayLike) -> FloatArray:
        """Advance to time t and return the estimate r of the external joint torques τ_ext = J(q)ᵀ h_e [N·m].

        Parameters
        ----------
        t : float
            The measurement time [s], later than the previous update's.
        q, qd : (n,) array_like
            Measured joint positions [rad or m] and velocities [rad/s or m/s].
        tau_applied : (n,) array_like
            The torque the drives held since the previous update, τ_{k−1} [N·m or N] (after saturation:
            :attr:`armctl.controllers.Measurement.tau_applied`); ignored at the first update.

        Returns
        -------
        ndarray, shape (n,)
            r_k (a new array, kept as :attr:`residual`; zeros at the first update). With the sign of
            ``SimResult.tau_ext``: M q̈ + C q̇ + g =
            τ − τ_f − τ_ext, so a push of the environment on the arm reads −Jᵀ(push).

        Raises
        ------
        ShapeError, NonFiniteError
            An input has the wrong length or is not finite.
        InvalidParameterError
            t is not later than the previous update's, or the step is too long for the gain (``"euler"``).
        """
        if (
            self._fast
            and type(q) is np.ndarray
            and type(qd) is np.ndarray
            and type(tau_applied) is np.ndarray
            and q.dtype is FLOAT  # the one float64 dtype NumPy makes (an equal one takes the careful path)
            and qd.dtype is FLOAT
            and tau_applied.dtype is FLOAT
            and q.shape == qd.shape == tau_applied.shape == self._shape
            and type(t) is float
            and math.isfinite(t)
        ):  # float64 vectors of the right length: a non-finite entry reaches r (see _fast), checked by the step
            try:
                return self.step(t, q, qd, tau_applied)
            except NonFiniteError:
                self._checked(t, q, qd, tau_applied)  # names the input, if one is the cause
                raise
        return self.step(*self._checked(t, q, qd, tau_applied))

    def _checked(self, t: Any, q: Any, qd: Any, tau: Any) -> tuple[float, FloatArray, FloatArray, FloatArray]:
        return (
            scalar(t, "t"),
            vector(q, self.n, "q"),
            vector(qd, self.n, "qd"),
            vector(tau, self.n, "tau_applied"),
        )

    def step(self, t: float, q: FloatArray, qd: FloatArray, tau: FloatArray) -> FloatArray:
        """:meth:`update` on checked inputs: for a controller's ``compute``, whose inputs ``Controller.__call__``
        has checked.

        Parameters
        ----------
        t : float
            The measurement time [s].
        q, qd, tau : ndarray, shape (n,)
            q, q̇ and the torque held since the previous update, float64, finite.

        Returns
        -------
        ndarray, shape (n,)
            The estimate r of τ_ext [N·m] (a new array).
        """
        if self._code is not None:  # (an instance's step is _compiled_step itself: see __init__)
            return self._compiled_step(t, q, qd, tau)
        p, beta = self.momentum_terms(q, qd)
        if self._t is None or self._p is None or self._beta is None:  # the first sample: r = 0, p₀ = p
            self._t, self._p, self._beta = t, p, beta
            return self.residual.copy()
        h = t - self._t
        if not h > 0.0:
            raise InvalidParameterError(
                f"observer updates must move forward in time: t = {t} after t = {self._t} (call reset() to restart)",
                value=t,
            )
        if abs(h - self._h) > 1e-9 * h:  # a new period (not the rounding of t_k = k·T)
            self._step_changed(h)
        d = h * tau
        d += (0.5 * h) * (beta + self._beta)
        d -= p
        d += self._p
        d *= 1.0 / h
        r = self._gamma * self.residual
        d *= self._lag_gain
        r += d  # r_k = γ r_{k−1} + (1 − γ) d_k (not γ(r − d) + d: r − d → 0 would reach subnormal floats)
        if not np.isfinite(r).all():
            raise NonFiniteError(f"the observer's residual is not finite ({r}) at t = {t}", value=r)
        self._t, self._p, self._beta = t, p, beta
        self.residual = r
        if self.thresholds is not None and self.collision is None:
            self._detect(t, r)
        return r

    def _step_changed(self, h: float) -> None:
        self.check_gain(h)
        self._h = h
        self._gamma = lag_pole(self.gain, h, self.discretization)
        self._lag_gain = 1.0 - self._gamma

    def _detect(self, t: float, r: FloatArray) -> None:
        assert self.thresholds is not None
        self.collision = isolate(t, r, self.thresholds, self._names)
        if self.collision is not None and self.on_collision is not None:
            self.on_collision(self, self.collision)

    # ------------------------------------------------------------------------------------- the wrench
    def wrench(self, q: ArrayLike, frame: str | None = None, rcond: float = 1e-3) -> FloatArray:
        """The wrench h_e = [f; m] [N, N·m] at ``frame`` that explains the residual, h_e = (J(q)ᵀ)⁺ r: what the
        arm exerts (the sign of ``SimResult.wrench``), world-aligned axes, moment about the frame's origin.

        With fewer than 6 joints the minimum-norm wrench is returned (the components J cannot feel are zero).

        Parameters
        ----------
        q : (n,) array_like
            The configuration of the last update [rad or m].
        frame : str, optional
            A frame of the model (default: the tool frame).
        rcond : float, optional
            Singularity threshold on σ_min / σ_max of J (over its min(6, n) largest singular values).

        Returns
        -------
        ndarray, shape (6,)
            h_e = [f; m] [N, N·m].

        Raises
        ------
        SingularConfigurationError
            J loses rank at q: a wrench along the lost direction gives no joint torque, so it cannot be estimated
            (the error carries σ_min and that direction).
        UnknownNameError
            ``frame`` is not a frame of the model.
        """
        q = vector(q, self.n, "q")
        rcond = scalar(rcond, "rcond", positive=True)
        return explaining_wrench(self.dynamics.jacobian(q, frame), self.residual, rcond, frame, q)
