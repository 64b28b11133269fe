"""Adaptive control (Slotine–Li) with the passivity regressor, and the protections it needs in practice."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, flag, scalar, vector
from armctl.controllers.base import Controller
from armctl.controllers.gains import gain
from armctl.controllers.passivity import SlidingGains, sliding
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError, ShapeError
from armctl.model import RobotModel
from armctl.model.consistency import project_physical, projection
from armctl.references import Reference


class Adaptive(SlidingGains, Controller):
    """τ = Y(q, q̇, q̇_r, q̈_r) θ̂ − K_D s,   θ̂̇ = −Γ (Yᵀ s + σ (θ̂ − θ₀) + κ W_fᵀ (W_f θ̂ − τ_f))

    (Slotine & Li 1987; s, q̇_r, q̈_r as in :class:`PassivityBased`). With θ̂ = π the law is
    :class:`PassivityBased`'s. An asymmetric Coulomb friction of the controller's model enters through Y's
    Coulomb column (:meth:`~armctl.Dynamics.coulomb_column`): θ̂ adapts the mean level, the ratio of the two
    levels stays the model's. With σ = κ = 0, no projection and no disturbance,
    V = ½ sᵀM s + ½ θ̃ᵀΓ⁻¹θ̃ has V̇ = −sᵀ(K_D + F_v)s ≤ 0: tracking converges whatever θ̂(0), while θ̂ itself
    converges only under persistent excitation. θ̂ is integrated at the control rate over the time between
    calls: explicit Euler, but for the composite term κ W_fᵀW_f θ̂, which is stiff (explicit Euler diverges once
    Γ κ dt λ_max(W_fᵀW_f) > 2: a pendulum at κ = 10, 1 ms did) and is taken at the new θ̂ (backward Euler, by
    the Woodbury identity: one n × n solve), non-expansive in the Γ⁻¹ norm (eigenvalues in (0, 1]) for every κ
    and dt.

    Protections against drift under disturbances and noise (off by default, as in the textbook law):

    * ``projection``: after each update, each link's pseudo-inertia is projected onto the PSD cone, so θ̂ stays
      physically consistent (positive masses, triangle inequalities; rotor and friction terms ≥ 0). That cone
      is unbounded, so it does not stop drift by itself; ``radius`` R adds the ball ‖θ̂ − θ₀‖ ≤ R (θ₀
      physical), a bounded set assumed to contain the true parameters: radial shrink towards θ₀, the exact
      projection onto the ball, keeps consistency because the cone is convex. The projection is the nearest
      consistent point in the Frobenius norm of each link's pseudo-inertia, not in the Γ⁻¹ metric of V, so it
      can move θ̂ away from the true parameters and V can increase at a projection: with planar_2r's preset
      gains (Γ spanning four decades), V rises from 212 to 1.5e3 over the scene's 5 s, in half of the steps,
      whatever the control period. Consistency is guaranteed, V̇ ≤ 0 is not (a Γ⁻¹-metric projection is a small
      semidefinite program per link, solved iteratively: milliseconds a step). The shipped presets therefore
      adapt without it;
    * ``sigma``: σ-modification, a leak towards θ₀ that bounds θ̂;
    * ``dead_zone``: θ̂ is held while ‖s‖ < δ (no term of the law moves it: noise alone does not);
    * ``composite`` κ: composite adaptation, adding the torque prediction error of the first-order-filtered
      regressor W_f = F[Y(q, q̇, q̈̂)] and filtered commanded torque τ_f = F[τ] (bandwidth
      ``filter_bandwidth`` [rad/s]; q̈̂ by differencing q̇; the commanded torque is taken as applied).

    Each step replaces ``theta`` (θ̂) by a new array (the controller never changes it in
    place), so ``last_log["theta"]`` is that same array, not a copy: change ``theta`` by assigning a new array,
    not in place, or the last log changes with it. ``last_log["s"]`` holds s. A diagonal Γ·dt is formed once per
    control-period length (anew when dt changes by more than 1e-9 relative).

    Parameters
    ----------
    dynamics : Dynamics
        The controller's model (its regressor Y and initial π).
    lam : array_like
        Λ [1/s]: a scalar, an (n,) diagonal or an n×n symmetric positive definite matrix.
    kd : array_like
        K_D [N·m·s/rad], likewise.
    gamma : array_like
        Γ: a scalar, a (13 n,) diagonal or a 13n × 13n symmetric positive definite matrix.
    theta0 : array_like, shape (13 n,), optional
        The initial θ̂ (None: the controller model's own π).
    projection : bool, optional
        Project θ̂ onto the physically consistent set after each update (see above).
    sigma : float, optional
        σ of the σ-modification, ≥ 0.
    dead_zone : float, optional
        δ [rad/s]: θ̂ is held while ‖s‖ < δ.
    composite : float, optional
        κ of the composite term, ≥ 0.
    filter_bandwidth : float, optional
        The bandwidth of the composite term's filter [rad/s], > 0.
    radius : float, optional
        R of the ball ‖θ̂ − θ₀‖ ≤ R, with ``projection=True`` only.
    plant : Dynamics or RobotModel, optional
        The true arm (as many joints), for simulation studies only: each step then also logs ``last_log["V"]``,
        the Lyapunov function V = ½ sᵀM(q)s + ½ θ̃ᵀΓ⁻¹θ̃ with the plant's M and θ̃ = θ̂ − π_plant (θ̂ after this
        step's update), so a run's ``res.logs["V"]`` is V(t). The law never uses it (a real controller knows
        neither M nor π); it costs one mass-matrix evaluation a step (and with a full Γ two triangular solves).

    Raises
    ------
    InvalidParameterError, ShapeError, NonFiniteError
        A gain that is not symmetric positive definite, a θ₀ of the wrong size, a negative σ, δ or κ, a radius
        without projection, a plant of another size.
    """

    dynamics: Dynamics  # given to __init__, never None

    _outside = False  # whether the last projection changed θ̂ (see _project); reset() clears it
    _plant: Dynamics | None
    _gamma_factor: Any = None

    gain_names: ClassVar[dict[str, bool]] = {**SlidingGains.gain_names, "gamma": False}
    gamma = gain("gamma", "Γ (13n×13n).")
    _gamma: FloatArray  # Γ in the compact form set_gains keeps (its diagonal if diagonal)
    _gamma_matrix: FloatArray
    _gamma_dt: FloatArray  # Γ·dt for the control period _dt (a diagonal Γ)

    def __init__(
        self,
        dynamics: Dynamics,
        lam: ArrayLike,
        kd: ArrayLike,
        gamma: ArrayLike,
        theta0: ArrayLike | None = None,
        *,
        projection: bool = False,
        sigma: float = 0.0,
        dead_zone: float = 0.0,
        composite: float = 0.0,
        filter_bandwidth: float = 20.0,
        radius: float | None = None,
        plant: Dynamics | RobotModel | None = None,
    ) -> None:
        super().__init__(dynamics)
        p = 13 * self.n
        self.set_gains(lam=lam, kd=kd, gamma=gamma)
        self.theta0 = dynamics.parameters().copy() if theta0 is None else vector(theta0, p, "theta0").copy()
        self.projection = projection
        self.sigma = scalar(sigma, "sigma", nonnegative=True)
        self.dead_zone = scalar(dead_zone, "dead_zone", nonnegative=True)
        self.composite = scalar(composite, "composite", nonnegative=True)
        self.filter_bandwidth = scalar(filter_bandwidth, "filter_bandwidth", positive=True)
        self.radius = None if radius is None else scalar(radius, "radius", positive=True)
        if self.radius is not None and not self.projection:
            raise InvalidParameterError("radius bounds the projection: use it with projection=True", value=radius)
        if self.projection:
            self.theta0 = project_physical(self.theta0)
        self.plant = plant
        self.reset()

    projection = flag(
        "projection", "Project θ̂ onto the physically consistent set after each update (may be switched between calls)."
    )
    _projection: bool

    @property
    def plant(self) -> Dynamics | None:
        """The true arm whose M and π give the logged V (None: V not logged)."""
        return self._plant

    @plant.setter
    def plant(self, value: Dynamics | RobotModel | None) -> None:
        if value is None:
            self._plant = None
            return
        if isinstance(value, RobotModel):
            value = Dynamics(value)
        if not isinstance(value, Dynamics):
            raise InvalidParameterError(
                f"plant must be an armctl.Dynamics, a RobotModel or None, got {type(value).__name__}", value=value
            )
        if value.n != self.n:
            raise ShapeError(f"plant has {value.n} joints, the controller {self.n}", value=value.n)
        self._plant = value

    def lyapunov(self, q: ArrayLike, s: ArrayLike, theta: ArrayLike | None = None) -> float:
        """V = ½ sᵀM(q)s + ½ θ̃ᵀΓ⁻¹θ̃ with :attr:`plant`'s M and θ̃ = θ − π_plant.

        Parameters
        ----------
        q : array_like, shape (n,)
            Joint positions [rad or m].
        s : array_like, shape (n,)
            The sliding variable s = q̇ − q̇_r [rad/s].
        theta : array_like, shape (13 n,), optional
            θ (default: the current θ̂).

        Returns
        -------
        float
            V [J].

        Raises
        ------
        InvalidParameterError
            No plant was given.
        """
        if self._plant is None:
            raise InvalidParameterError("V needs the true arm: set plant= (a Dynamics or RobotModel)", value=None)
        q, s = vector(q, self.n, "q"), vector(s, self.n, "s")
        err = (self.theta if theta is None else vector(theta, 13 * self.n, "theta")) - self._plant.parameters()
        gamma = self._gamma
        if gamma.ndim == 1:
            weighted = err / gamma
        else:  # a full Γ: its Cholesky factor, formed once per Γ
            if self._gamma_factor is None:
                self._gamma_factor = scipy.linalg.cho_factor(gamma)
            weighted = scipy.linalg.cho_solve(self._gamma_factor, err)
        return 0.5 * float(s.dot(self._plant.mass_matrix(q).dot(s)) + err.dot(weighted))

    def _gain_spec(self, name: str) -> tuple[int, str]:
        return (13 if name == "gamma" else 1) * self.n, name

    def _derive(self) -> None:
        super()._derive()
        self._dt = 0.0  # Γ·dt formed anew at the next update (no update has dt = 0)
        self._gamma_factor = None  # and Γ's Cholesky factor, for V

    def reset(self) -> None:
        super().reset()
        self.theta = self.theta0.copy()
        self._outside = False  # the last projection changed θ̂
        self._t_prev: float | None = None
        self._qd_prev: FloatArray | None = None
        self._tau_prev: FloatArray | None = None
        self._w_f: FloatArray | None = None
        self._tau_f: FloatArray | None = None
        self._dt, self._gamma_dt = 0.0, self._gamma * 0.0

    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        dyn = self.dynamics
        assert dyn is not None
        qd_r, qdd_r, s, kd_s, a, w = sliding(q, qd, ref, self._sliding)
        # q, q̇ checked by Controller.__call__; Y may be the dynamics' workspace (read before the next
        # regressor call: the composite term makes one, so it needs a copy)
        y = dyn.kernel.passivity_regressor(q, qd, qd_r, qdd_r, a, w, copy=bool(self.composite))
        dt = 0.0 if self._t_prev is None else t - self._t_prev  # ≤ 0 for a new run without reset: no update
        # the filters run inside the dead zone too; they start at the first call with composite on
        composite = bool(self.composite) and dt > 0 and self._qd_prev is not None
        if composite:
            w_f, tau_f = self._filtered(q, qd, dt)
        if dt > 0 and (self.dead_zone == 0 or float(np.linalg.norm(s)) >= self.dead_zone):
            grad = y.T.dot(s)
            if self.sigma:
                grad = grad + self.sigma * (self.theta - self.theta0)
            if composite:  # the explicit part of κ W_fᵀ(W_f θ̂ − τ_f); W_fᵀW_f θ̂ follows implicitly
                grad = grad - self.composite * w_f.T.dot(tau_f)
            # a new array, not an update in place: the log below can then keep it without a copy
            if self._gamma.ndim == 1:  # diagonal Γ: Γ dt is kept while the control period stays the same
                if abs(dt - self._dt) > 1e-9 * dt:
                    self._dt, self._gamma_dt = dt, self._gamma * dt
                self.theta = self.theta - self._gamma_dt * grad
            else:  # a full Γ: Γ (g dt), not (Γ dt) g, which a jittery measured dt would form anew each step
                step = self._gamma.dot(grad)
                step *= dt
                self.theta = self.theta - step
            if composite:
                self.theta = self._implicit_prediction(self.theta, w_f, dt)
            if self._projection:
                self.theta = self._project(self.theta)
        self._t_prev = t
        tau = y.dot(self.theta)
        tau -= kd_s
        if self.composite:  # copies: the caller may reuse its q̇ buffer, or clip τ in place
            self._qd_prev, self._tau_prev = qd.copy(), tau.copy()  # the torque the parameters must explain
        self.last_log = {"theta": self.theta, "s": s}
        if self._plant is not None:
            self.last_log["V"] = self.lyapunov(q, s)
        return tau

    def _project(self, theta: FloatArray) -> FloatArray:
        # an estimate that needed projecting sits on the boundary of the physical set, where the next one
        # likely is too: then straight to the eigendecomposition
        theta, self._outside = projection(theta, likely_inside=not self._outside)
        if self.radius is not None:
            d = theta - self.theta0
            norm = float(np.linalg.norm(d))
            if norm > self.radius:
                theta = self.theta0 + d * (self.radius / norm)
        return theta

    def _filtered(self, q: FloatArray, qd: FloatArray, dt: float) -> tuple[FloatArray, FloatArray]:
        """(W_f, τ_f), first-order filters of bandwidth ω: x_f += (1 − e^{−ω dt})(x − x_f)."""
        dyn = self.dynamics
        assert dyn is not None and self._qd_prev is not None and self._tau_prev is not None
        w = dyn.regressor(q, qd, (qd - self._qd_prev) / dt)
        a = 1.0 - float(np.exp(-self.filter_bandwidth * dt))
        if self._w_f is None or self._tau_f is None:
            self._w_f, self._tau_f = w, self._tau_prev.copy()
        else:
            self._w_f = self._w_f + a * (w - self._w_f)
            self._tau_f = self._tau_f + a * (self._tau_prev - self._tau_f)
        return self._w_f, self._tau_f

    def _implicit_prediction(self, b: FloatArray, w_f: FloatArray, dt: float) -> FloatArray:
        """θ⁺ = (I + κ dt Γ W_fᵀW_f)⁻¹ b = b − κ dt Γ W_fᵀ (I + κ dt W_f Γ W_fᵀ)⁻¹ W_f b (Woodbury)."""
        a = self.composite * dt
        gw = self._gamma[:, None] * w_f.T if self._gamma.ndim == 1 else self._gamma.dot(w_f.T)  # Γ W_fᵀ
        inner = np.eye(w_f.shape[0]) + a * w_f.dot(gw)
        return b - a * gw.dot(np.linalg.solve(inner, w_f.dot(b)))
