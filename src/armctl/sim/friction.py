"""Joint friction models of the simulated plant: :class:`StickSlip` (real stiction, the default) and
:class:`SmoothFriction` (a tanh curve).

Both read the plant model's :class:`~armctl.model.parts.JointFriction` of every joint: viscous F_v, Coulomb
F_c⁺ / F_c⁻, static (breakaway) F_s and Stribeck velocity v_s. The kinetic friction curve they share is given
with :class:`FrictionModel`; which model fits which use, with each of the two classes.
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

    A friction model gives the kinetic friction torque τ_f(q̇) of the joints, which acts against the motion
    (:meth:`torque`), and its derivative ∂τ_f/∂q̇ for the implicit integrators (:meth:`slope`). The built-in
    models are :class:`StickSlip` (the simulator's default) and :class:`SmoothFriction`; ``simulate`` takes
    either, or its name (``friction="stick-slip"`` or ``"smooth"``). The generated simulation step covers these
    two classes; a plant with a model of another class (a subclass included) runs on the Python step.

    Parameters
    ----------
    model : RobotModel
        The plant's model (``dynamics.model``); its joints' friction parameters are read once, here.
    stribeck : bool, optional
        Whether the Stribeck hump (F_s − F_c) exp(−(q̇/v_s)²) is part of the kinetic friction; False: plain
        viscous + Coulomb friction while sliding.

    Attributes
    ----------
    stick_slip : bool
        True for models with sticking (the simulator then tracks which joints are stuck).
    name : str
        The model's name in ``simulate(friction=...)``: ``"stick-slip"`` or ``"smooth"``.
    n : int
        Number of joints.
    viscous : ndarray, shape (n,)
        F_v [N·m·s/rad] (N·s/m for a prismatic joint).
    coulomb_pos, coulomb_neg : ndarray, shape (n,)
        The Coulomb levels F_c⁺ (for q̇ > 0) and F_c⁻ (for q̇ < 0), magnitudes [N·m] (N for a prismatic joint).
    breakaway_pos, breakaway_neg : ndarray, shape (n,)
        The breakaway (static) levels F_s⁺ and F_s⁻, magnitudes [N·m]: the joint's ``static`` level, or its
        Coulomb levels when it has none.
    stribeck_velocity : ndarray, shape (n,)
        v_s [rad/s] (m/s for a prismatic joint); 1 for a joint without a Stribeck curve (its hump is then 0).
    hump_pos, hump_neg : ndarray, shape (n,)
        The Stribeck excess F_s − F_c ≥ 0 [N·m] of each direction; 0 where v_s = 0, and everywhere with
        ``stribeck=False``.

    Raises
    ------
    InvalidParameterError
        ``model`` is not a :class:`~armctl.RobotModel`; ``stribeck`` is not True or False.

    Notes
    -----
    The kinetic friction torque of a moving joint is the Stribeck curve::

        τ_f(q̇) = F_v q̇ + sgn(q̇) [F_c + (F_s − F_c) exp(−(q̇/v_s)²)]

    with F_c = F_c⁺, F_s = F_s⁺ for q̇ > 0 and F_c⁻, F_s⁻ for q̇ < 0; it is plain viscous + Coulomb friction when
    v_s = 0 or F_s = F_c. It acts against the motion: the plant's equation of motion is
    M q̈ + C q̇ + g = τ − τ_f − Jᵀh_e. Where the models differ is near q̇ = 0: :class:`StickSlip` holds a joint
    exactly at rest while its friction can, :class:`SmoothFriction` replaces sgn(q̇) by tanh(q̇/v_t).
    """

    # True for models with sticking (the simulator then tracks which joints are stuck)
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
        """The kinetic friction torque τ_f(q̇), which acts against the motion.

        Parameters
        ----------
        qd : ndarray, shape (n,)
            Joint velocities q̇ [rad/s] (m/s for a prismatic joint).
        direction : ndarray, shape (n,)
            The sliding direction of every joint, held fixed over an integration step: +1 or −1 for a joint
            sliding that way, 0 for a stuck joint (no Coulomb or Stribeck term). :class:`StickSlip` takes its
            Coulomb and Stribeck levels from it; :class:`SmoothFriction` ignores it (it may be None there).

        Returns
        -------
        ndarray, shape (n,)
            τ_f [N·m] (N for a prismatic joint), with the sign it has in M q̈ + C q̇ + g = τ − τ_f.
        """

    @abstractmethod
    def slope(self, qd: FloatArray, direction: FloatArray) -> FloatArray:
        """The derivative ∂τ_f/∂q̇ of :meth:`torque`, a diagonal matrix given as its diagonal (the implicit
        integrators' Newton iterations use it).

        Parameters
        ----------
        qd : ndarray, shape (n,)
            Joint velocities q̇ [rad/s] (m/s for a prismatic joint).
        direction : ndarray, shape (n,)
            The sliding directions, as in :meth:`torque`.

        Returns
        -------
        ndarray, shape (n,)
            ∂τ_f,i/∂q̇_i [N·m·s/rad] (N·s/m for a prismatic joint).
        """

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


def _signed(direction: FloatArray, pos: FloatArray, neg: FloatArray) -> FloatArray:
    """``pos`` where ``direction`` > 0, −``neg`` where it is < 0, 0 elsewhere (a level on each side of rest)."""
    return np.where(direction > 0, pos, 0.0) - np.where(direction < 0, neg, 0.0)


class StickSlip(FrictionModel):
    """Stick–slip friction: the kinetic Stribeck curve while a joint slides, exact sticking at rest (the
    simulator's default friction model).

    A joint whose velocity reaches zero is held *exactly* at rest (q̇ = 0, q̈ = 0: no creep, no chatter) while
    the torque its friction must supply to hold it stays within its breakaway levels; beyond them, it breaks
    away. Use it whenever behaviour near zero velocity matters: holding a pose against gravity, small or slow
    motions, reversals, integral action against Coulomb friction (hunting limit cycles), breakaway tests.

    Parameters
    ----------
    model : RobotModel
        The plant's model (``dynamics.model``).
    stribeck : bool, optional
        False ignores the Stribeck curve: the kinetic friction is then F_v q̇ ± F_c while sliding, and F_s is
        used only for breakaway.

    Attributes
    ----------
    capable : ndarray of bool, shape (n,)
        The joints that can stick: those with a positive breakaway level in either direction. A joint with
        neither Coulomb nor static friction never sticks.
    any_capable : bool
        Some joint can stick.

    Raises
    ------
    InvalidParameterError
        ``model`` is not a :class:`~armctl.RobotModel`; ``stribeck`` is not True or False.

    See Also
    --------
    SmoothFriction : the sign smoothed by tanh, without sticking.

    Notes
    -----
    A hybrid "switch" model in the spirit of Karnopp's. While joint i slides in the direction d_i = ±1 (held
    fixed over an integration step), its friction is the kinetic curve::

        τ_f,i = F_v q̇_i + d_i [F_c + (F_s − F_c) exp(−(q̇_i/v_s)²)]        (F_c, F_s of the direction d_i)

    A sliding joint whose velocity reaches zero during a step is an event: the step is cut there, the velocity
    set to exactly 0, and the joint becomes a candidate for sticking. With S the stuck joints and F the others,
    sticking is the constraint q̈_S = 0, and the friction torques λ_S that hold the stuck joints are its
    multipliers::

        M q̈ = r − E_S λ_S,   q̈_S = 0     ⇒   M_FF q̈_F = r_F,   λ_S = r_S − M_SF q̈_F

    where E_S holds the columns of the identity of the stuck joints and r = τ − C q̇ − g − τ_f,F − Jᵀh_e every
    other torque (the kinetic friction of the sliding joints included). A stuck joint stays stuck while
    −F_s⁻ ≤ λ_i ≤ F_s⁺; beyond, it breaks away in the direction of λ_i with the kinetic friction it has at
    zero speed. Releasing a joint changes the others' λ, so joints are released one at a time, the one
    furthest beyond its band (largest |λ_i|/F_s) first, and λ is solved again. This largest-violation-first
    rule is a heuristic for what is, in general, a linear complementarity problem; the simulator checks its
    outcome: a released joint that does not move in its breakaway direction is held again and the step redone.
    """

    stick_slip = True
    name = "stick-slip"

    def __init__(self, model: RobotModel, stribeck: bool = True) -> None:
        super().__init__(model, stribeck)
        # joints that can stick (a positive breakaway level in either direction)
        self.capable = (self.breakaway_pos > 0) | (self.breakaway_neg > 0)
        self.any_capable = bool(self.capable.any())

    def level(self, direction: FloatArray) -> FloatArray:
        """The signed Coulomb part of the kinetic friction for the sliding directions.

        Parameters
        ----------
        direction : ndarray, shape (n,)
            The sliding direction of every joint: +1, −1, or 0 (stuck).

        Returns
        -------
        ndarray, shape (n,)
            +F_c⁺ where ``direction`` > 0, −F_c⁻ where it is < 0, 0 elsewhere [N·m] (N for a prismatic joint).
        """
        return _signed(direction, self.coulomb_pos, self.coulomb_neg)

    def hump(self, direction: FloatArray) -> FloatArray:
        """The signed Stribeck excess F_s − F_c for the sliding directions (its weight exp(−(q̇/v_s)²) is 1 at
        rest).

        Parameters
        ----------
        direction
            As for :meth:`level`.

        Returns
        -------
        ndarray, shape (n,)
            +(F_s⁺ − F_c⁺) where ``direction`` > 0, −(F_s⁻ − F_c⁻) where it is < 0, 0 elsewhere (and 0 for a
            joint without a Stribeck curve, or with ``stribeck=False``) [N·m].
        """
        return _signed(direction, self.hump_pos, self.hump_neg)

    def torque(self, qd: FloatArray, direction: FloatArray) -> FloatArray:
        # (a second source: armctl.sim.generated_plant.PlantExpressions.friction, the generated step's;
        # a change here is a change there: tests/sim/test_compiled_plant.py fails when they disagree)
        tau = self.viscous * qd + self.level(direction)
        if self.has_stribeck:
            tau += self.hump(direction) * self._stribeck_shape(qd)[1]
        return tau

    def slope(self, qd: FloatArray, direction: FloatArray) -> FloatArray:
        # (a second source: armctl.sim.generated_plant.PlantExpressions.friction_slope, the generated step's;
        # a change here is a change there: tests/sim/test_compiled_plant.py fails when they disagree)
        d = self.viscous.copy()
        if self.has_stribeck:
            d += self.hump(direction) * self._stribeck_slope(qd)
        return d


class SmoothFriction(FrictionModel):
    """Smooth friction: the sign of the Stribeck curve replaced by tanh(q̇/v_t), so that the dynamics are smooth.

    Every integrator keeps its order and the dynamics can be linearised, but a joint under a net torque below
    its breakaway level *creeps* instead of sticking, and a small v_t makes the dynamics stiff (use an implicit
    integrator or small steps). Use it for fast, large motions where the sticking phases do not matter, for
    sweeps that only need the dissipated energy right, and to compare with tools that model friction this way.

    Parameters
    ----------
    model : RobotModel
        The plant's model (``dynamics.model``).
    velocity : float, optional
        v_t > 0 [rad/s] (m/s for a prismatic joint), the width of the smoothed sign.
    stribeck : bool, optional
        False ignores the Stribeck curve (the level is then F_c at every speed).

    Attributes
    ----------
    velocity : float
        The width v_t of the smoothed sign [rad/s].

    Raises
    ------
    InvalidParameterError
        ``model`` is not a :class:`~armctl.RobotModel`; ``stribeck`` is not True or False; ``velocity`` is not
        a number > 0.
    NonFiniteError
        ``velocity`` is NaN or infinite.

    See Also
    --------
    StickSlip : exact sticking at rest.

    Notes
    -----
    ::

        τ_f(q̇) = F_v q̇ + tanh(q̇/v_t) [F_c + (F_s − F_c) exp(−(q̇/v_s)²)]

    with F_c, F_s those of the sign of q̇. A net torque τ below F_s makes a joint creep at
    q̇ ≈ v_t·atanh(τ/F_s) (for v_t ≪ v_s, where the level is still F_s; F_s = F_c without a Stribeck hump).
    The ``direction`` argument of :meth:`torque` and :meth:`slope` is not used.
    """

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
        # (a second source: armctl.sim.generated_plant.PlantExpressions.friction, the generated step's;
        # a change here is a change there: tests/sim/test_compiled_plant.py fails when they disagree)
        return self.viscous * qd + np.tanh(qd / self.velocity) * self._levels(qd)

    def slope(self, qd: FloatArray, direction: FloatArray | None = None) -> FloatArray:
        # (a second source: armctl.sim.generated_plant.PlantExpressions.friction_slope, the generated step's;
        # a change here is a change there: tests/sim/test_compiled_plant.py fails when they disagree)
        th = np.tanh(qd / self.velocity)
        d = self.viscous + (1.0 - th**2) / self.velocity * self._levels(qd)
        if self.has_stribeck:
            d += th * np.where(qd > 0, self.hump_pos, self.hump_neg) * self._stribeck_slope(qd)
        return d


FRICTION_MODELS = ("stick-slip", "smooth")


def make_friction(spec: str | FrictionModel, model: RobotModel) -> FrictionModel:
    """The friction model of a plant.

    Parameters
    ----------
    spec : str or FrictionModel
        ``"stick-slip"`` (:class:`StickSlip`), ``"smooth"`` (:class:`SmoothFriction` with its defaults), or a
        model made for ``model``.
    model : RobotModel
        The plant's model.

    Returns
    -------
    FrictionModel
        The model named ``spec``, or ``spec`` itself.

    Raises
    ------
    UnknownNameError
        ``spec`` is neither a FrictionModel nor one of the names.
    InvalidParameterError
        ``spec`` is a FrictionModel for another number of joints.
    """
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
    """The kinetic friction magnitude F_v |q̇| + F_c + (F_s − F_c) exp(−(q̇/v_s)²) of one joint (a scalar helper
    for plots and docs; values unchecked).

    Parameters
    ----------
    qd : float
        The velocity q̇ [rad/s]; only its magnitude is used.
    coulomb, static : float
        F_c and F_s [N·m].
    stribeck_velocity : float
        v_s [rad/s]; 0: no Stribeck hump.
    viscous : float, optional
        F_v [N·m·s/rad].

    Returns
    -------
    float
        The friction magnitude [N·m].
    """
    s = abs(qd)
    hump = (static - coulomb) * math.exp(-((s / stribeck_velocity) ** 2)) if stribeck_velocity > 0 else 0.0
    return viscous * s + coulomb + hump
