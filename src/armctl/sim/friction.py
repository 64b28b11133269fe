"""Joint friction models of the simulated plant: stick–slip (the default) and a smooth tanh curve.

Both read the plant model's :class:`~armctl.model.parts.JointFriction` of every joint: viscous F_v, Coulomb
F_c⁺ / F_c⁻, static (breakaway) F_s and Stribeck velocity v_s. The kinetic friction torque of a moving joint,
acting against its motion (it enters as M q̈ + C q̇ + g = τ − τ_f − Jᵀh_e), is the Stribeck curve

    τ_f(q̇) = F_v q̇ + sgn(q̇) [F_c + (F_s − F_c) exp(−(q̇/v_s)²)]        (F_c = F_c⁺ or F_c⁻ by direction)

which is plain viscous + Coulomb when v_s = 0 or F_s = F_c.

Which model fits
----------------
:class:`StickSlip` — real stiction (a hybrid "switch" model in the spirit of Karnopp's): a joint whose velocity
reaches zero is held *exactly* at rest (q̇ = 0, q̈ = 0, no creep, no chatter) while the friction torque needed
to hold it stays within the breakaway level; above it, the joint breaks away. With several joints the holding
torques come from one constraint solve with the mass matrix (see :mod:`armctl.sim.stick_slip`). Use it
whenever behaviour near zero velocity matters: holding a pose against gravity, small or slow motions, tracking
reversals, integral action against Coulomb friction (hunting limit cycles), breakaway tests.

:class:`SmoothFriction` — the sign replaced by tanh(q̇/v_t). The dynamics become smooth, so every integrator
keeps its order and linearisation is possible, but a joint under a net torque below the breakaway level
*creeps* at a velocity of order v_t·atanh(τ/F_s) instead of sticking (F_s = F_c without a Stribeck hump),
and a small v_t makes the dynamics stiff (use the implicit integrator or small steps). Use it for fast, large
motions where the sticking phases do not matter, for sweeps that only need the dissipated energy right, and
when comparing with tools that model friction this way.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod

import numpy as np

from armctl._checks import FloatArray, boolean, scalar
from armctl.errors import InvalidParameterError, UnknownNameError
from armctl.model.robot import RobotModel


class FrictionModel(ABC):
    """Joint friction of the plant, built from ``model``'s :class:`~armctl.model.parts.JointFriction`.

    ``torque(qd, direction)`` is τ_f (n,) [N·m] acting against the motion; ``slope(qd, direction)`` its
    derivative ∂τ_f/∂q̇ (diagonal, (n,)) [N·m·s/rad] for the implicit integrator. ``direction`` (±1 per joint,
    0 for a stuck joint) is the sliding direction the stick–slip model holds fixed over a step; the smooth
    model ignores it.
    """

    #: True for models with sticking (the simulator then tracks which joints are stuck)
    stick_slip: bool = False
    name: str = ""

    def __init__(self, model: RobotModel, stribeck: bool = True) -> None:
        if not isinstance(model, RobotModel):
            raise InvalidParameterError(
                f"a friction model takes the plant's RobotModel (dynamics.model), got {type(model).__name__}",
                value=model,
            )
        stribeck = boolean(stribeck, "stribeck")
        fr = [j.friction for j in model.joints]
        self.n = model.n
        self.viscous = np.array([f.viscous for f in fr])
        self.coulomb_pos = np.array([f.coulomb for f in fr])
        self.coulomb_neg = np.array([f.coulomb_neg for f in fr])
        self.breakaway_pos = np.array([f.breakaway[0] for f in fr])
        self.breakaway_neg = np.array([f.breakaway[1] for f in fr])
        vs = np.array([f.stribeck_velocity for f in fr])
        # the Stribeck hump exists where v_s > 0 and F_s exceeds the Coulomb level
        self.stribeck_velocity = np.where(vs > 0, vs, 1.0)
        hump_pos = np.where(vs > 0, self.breakaway_pos - self.coulomb_pos, 0.0)
        hump_neg = np.where(vs > 0, self.breakaway_neg - self.coulomb_neg, 0.0)
        self.hump_pos, self.hump_neg = (hump_pos, hump_neg) if stribeck else (0 * hump_pos, 0 * hump_neg)
        self.has_viscous = bool(self.viscous.any())
        self.has_coulomb = bool(self.coulomb_pos.any() or self.coulomb_neg.any())
        self.has_stribeck = bool(self.hump_pos.any() or self.hump_neg.any())
        self.is_zero = not (
            self.has_viscous
            or self.has_coulomb
            or self.has_stribeck
            or self.breakaway_pos.any()
            or self.breakaway_neg.any()
        )

    @abstractmethod
    def torque(self, qd: FloatArray, direction: FloatArray) -> FloatArray:
        """τ_f(q̇) [N·m]."""

    @abstractmethod
    def slope(self, qd: FloatArray, direction: FloatArray) -> FloatArray:
        """∂τ_f/∂q̇ (diagonal) [N·m·s/rad]."""

    def __repr__(self) -> str:
        return f"{type(self).__name__}(n={self.n})"

    def _stribeck_shape(self, qd: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(x, exp(−x²)) with x = q̇/v_s clipped to ±40, where exp(−x²) is exactly 0 already: a tiny v_s would
        otherwise overflow x² (and x·0 in the slope would be NaN)."""
        x = np.clip(qd / self.stribeck_velocity, -40.0, 40.0)
        return x, np.exp(-(x * x))

    def _stribeck_slope(self, qd: FloatArray) -> FloatArray:
        """d/dq̇ exp(−(q̇/v_s)²) = −2 x exp(−x²) / v_s, x = q̇/v_s."""
        x, g = self._stribeck_shape(qd)
        return -2.0 * x * g / self.stribeck_velocity


class StickSlip(FrictionModel):
    """Stick–slip friction: kinetic Stribeck curve while sliding, exact sticking at rest.

    A joint with breakaway levels (F_s⁺, F_s⁻) > 0 sticks when its velocity reaches zero and stays stuck while
    the torque its friction must supply to hold it, λ_i, satisfies −F_s⁻ ≤ λ_i ≤ F_s⁺; it breaks away, in the
    direction of λ_i, as soon as it exceeds them. ``stribeck=False`` ignores the Stribeck curve (kinetic
    friction is then F_c while sliding, F_s is used only for breakaway). A joint with no Coulomb or static
    friction never sticks.
    """

    stick_slip = True
    name = "stick-slip"

    def __init__(self, model: RobotModel, stribeck: bool = True) -> None:
        super().__init__(model, stribeck)
        #: joints that can stick (a positive breakaway level in either direction)
        self.capable = (self.breakaway_pos > 0) | (self.breakaway_neg > 0)
        self.any_capable = bool(self.capable.any())

    def level(self, direction: FloatArray) -> FloatArray:
        """Signed Coulomb part at zero velocity for the sliding ``direction``: +F_c⁺, −F_c⁻ or 0."""
        return np.where(direction > 0, self.coulomb_pos, 0.0) - np.where(direction < 0, self.coulomb_neg, 0.0)

    def hump(self, direction: FloatArray) -> FloatArray:
        """Signed Stribeck excess (F_s − F_c) for the sliding ``direction``."""
        return np.where(direction > 0, self.hump_pos, 0.0) - np.where(direction < 0, self.hump_neg, 0.0)

    def torque(self, qd: FloatArray, direction: FloatArray) -> FloatArray:
        tau = self.viscous * qd + self.level(direction)
        if self.has_stribeck:
            tau += self.hump(direction) * self._stribeck_shape(qd)[1]
        return tau

    def slope(self, qd: FloatArray, direction: FloatArray) -> FloatArray:
        d = self.viscous.copy()
        if self.has_stribeck:
            d += self.hump(direction) * self._stribeck_slope(qd)
        return d


class SmoothFriction(FrictionModel):
    """Smooth friction: τ_f = F_v q̇ + tanh(q̇/v_t) [F_c + (F_s − F_c) exp(−(q̇/v_s)²)], F_c and F_s by the sign
    of q̇. ``velocity``: v_t [rad/s], the width of the smoothed sign (default 0.01 rad/s); a net torque
    below F_s makes a joint creep at about v_t·atanh(τ/F_s) (for v_t ≪ v_s, where the level is still F_s)."""

    name = "smooth"

    def __init__(self, model: RobotModel, velocity: float = 1e-2, stribeck: bool = True) -> None:
        super().__init__(model, stribeck)
        self.velocity = scalar(velocity, "smooth friction velocity", positive=True)

    def _levels(self, qd: FloatArray) -> FloatArray:
        pos = qd > 0
        level = np.where(pos, self.coulomb_pos, self.coulomb_neg)
        if self.has_stribeck:
            level = level + np.where(pos, self.hump_pos, self.hump_neg) * self._stribeck_shape(qd)[1]
        return level

    def torque(self, qd: FloatArray, direction: FloatArray | None = None) -> FloatArray:
        return self.viscous * qd + np.tanh(qd / self.velocity) * self._levels(qd)

    def slope(self, qd: FloatArray, direction: FloatArray | None = None) -> FloatArray:
        th = np.tanh(qd / self.velocity)
        d = self.viscous + (1.0 - th**2) / self.velocity * self._levels(qd)
        if self.has_stribeck:
            d += th * np.where(qd > 0, self.hump_pos, self.hump_neg) * self._stribeck_slope(qd)
        return d


FRICTION_MODELS = ("stick-slip", "smooth")


def make_friction(spec: str | FrictionModel, model: RobotModel) -> FrictionModel:
    """The friction model named ``spec`` ("stick-slip" or "smooth") for ``model``, or ``spec`` itself."""
    if isinstance(spec, FrictionModel):
        if spec.n != model.n:
            raise InvalidParameterError(f"friction model is for {spec.n} joints, the plant has {model.n}", value=spec)
        return spec
    if spec == "stick-slip":
        return StickSlip(model)
    if spec == "smooth":
        return SmoothFriction(model)
    raise UnknownNameError("friction model", spec, FRICTION_MODELS)


def stribeck_curve(qd: float, coulomb: float, static: float, stribeck_velocity: float, viscous: float = 0.0) -> float:
    """The kinetic friction magnitude at speed |q̇| (a scalar helper for plots and docs)."""
    s = abs(qd)
    hump = (static - coulomb) * math.exp(-((s / stribeck_velocity) ** 2)) if stribeck_velocity > 0 else 0.0
    return viscous * s + coulomb + hump
