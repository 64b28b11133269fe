"""The parts a :class:`~armctl.RobotModel` is made of: links, motors, joint friction, limits, joints, frames.

Conventions (the textbook's, see ``shared/references``):

* A link's inertia is the *augmented* link of the Lagrange formulation: the link itself plus the stator and
  the rotor (as a rigid body) of the motor that rides on it. Centre of mass and inertia tensor are given in
  the joint frame of the link (``Joint.placement`` composed with the joint motion), the tensor about the
  centre of mass.
* A motor drives joint i through a rigid gear of ratio ``k_r`` (rotor angle = k_r·q_i); its rotor rides on
  link i−1 and spins about ``axis`` (in the frame of link i−1; by default the joint axis). What the rotor adds
  beyond the augmented link is its spin: kinetic energy ½ I_m (k_r q̇_i + z_mᵀω_{i−1})² − ½ I_m (z_mᵀω_{i−1})²,
  i.e. the reflected inertia k_r² I_m q̇_i²/2 and the gyroscopic coupling k_r I_m q̇_i z_mᵀω_{i−1}.
* Friction is referred to the joint side: τ_f = F_v q̇ + F_c⁺ (q̇ > 0), F_v q̇ − F_c⁻ (q̇ < 0), 0 at rest.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, boolean, readonly, real_array, scalar, whole_number
from armctl.errors import InvalidParameterError, NonFiniteError, ShapeError

_INERTIA_TOL = 1e-9


def real_values(x: ArrayLike, name: str) -> FloatArray:
    """A new float array of ``x`` (:func:`~armctl._checks.real_array`); its shape and finiteness are the
    caller's to check."""
    return np.array(real_array(x, name))  # a copy: parts make their arrays read-only, never the caller's


def instance_of(x: Any, cls: type, name: str, optional: bool = False) -> None:
    """Raise unless ``x`` is a ``cls`` (or None, if ``optional``): a part given as anything else would fail far
    from here."""
    if not (isinstance(x, cls) or (optional and x is None)):
        what = f"an armctl.model.{cls.__name__}" + (" or None" if optional else "")
        raise InvalidParameterError(f"{name} must be {what}, got {x!r} ({type(x).__name__})", value=x)


def name_text(x: Any, name: str) -> str:
    """Raise unless ``x`` is a str (a name)."""
    if not isinstance(x, str):
        raise InvalidParameterError(f"{name} must be a str, got {x!r} ({type(x).__name__})", value=x)
    return x


def vec3(x: ArrayLike, name: str) -> FloatArray:
    """A finite 3-vector (any array of 3 numbers, flattened), read-only."""
    a = real_values(x, name).reshape(-1)
    if a.shape != (3,):
        raise ShapeError(f"{name} must have 3 components, got {np.shape(x)}", value=x)
    if not np.isfinite(a).all():
        raise NonFiniteError(f"{name} must be finite, got {a}", value=x)
    return readonly(a)


def _limit(x: Any, name: str) -> float:
    """A joint limit: a finite real number or ±inf (no limit)."""
    if isinstance(x, float | np.floating) and math.isinf(x):
        return float(x)
    if isinstance(x, float | np.floating) and math.isnan(x):
        raise NonFiniteError(f"{name} is NaN; give a number, or ±inf for no limit", value=x)
    return scalar(x, name)


def inertia_tensor(x: ArrayLike, name: str = "inertia", triangle: bool = True) -> FloatArray:
    """A 3×3 inertia tensor from a 3×3 matrix, 3 principal moments (diagonal) or 6 values
    ``(Ixx, Ixy, Ixz, Iyy, Iyz, Izz)``; checked symmetric, positive semi-definite and satisfying the
    triangle inequalities of its principal moments."""
    a = real_values(x, name)
    if a.shape == (3,):
        a = np.diag(a)
    elif a.shape == (6,):
        xx, xy, xz, yy, yz, zz = a
        a = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    if a.shape != (3, 3):
        raise ShapeError(
            f"{name} must be 3×3, 3 principal moments or 6 values (Ixx, Ixy, Ixz, Iyy, Iyz, Izz); got shape {a.shape}",
            value=x,
        )
    if not np.isfinite(a).all():
        raise NonFiniteError(f"{name} must be finite, got {a.tolist()}", value=x)
    scale = max(float(np.abs(a).max()), 1e-300)
    if not np.allclose(a, a.T, atol=_INERTIA_TOL * scale):
        raise InvalidParameterError(f"{name} must be symmetric, got {a.tolist()}", value=x)
    a = 0.5 * (a + a.T)
    ev = np.linalg.eigvalsh(a)
    tol = _INERTIA_TOL * scale
    if ev[0] < -tol:
        raise InvalidParameterError(
            f"{name} is not positive semi-definite: principal moments {ev.tolist()} (a rigid body has none "
            "negative; a point mass or slender rod may have zeros)",
            value=x,
        )
    if triangle and ev[0] + ev[1] < ev[2] - tol:
        raise InvalidParameterError(
            f"{name} violates the triangle inequality of principal moments: {ev[0]:g} + {ev[1]:g} < {ev[2]:g};"
            " no rigid body has these moments (check units and which axis is which; physical=False takes them,"
            " as some published data sets need)",
            value=x,
        )
    return readonly(a)


@dataclass(frozen=True, eq=False, init=False)  # numpy fields: compare by identity
class Link:
    """An (augmented) link body.

    Parameters
    ----------
    mass : float
        [kg], ≥ 0.
    com : array_like, shape (3,), optional
        The centre of mass in the joint frame [m] (default the origin).
    inertia : array_like, optional
        The inertia tensor about the centre of mass, in joint-frame axes [kg·m²]: 3×3, 3 principal moments, or six
        values in URDF order Ixx, Ixy, Ixz, Iyy, Iyz, Izz — not π's order Ixx, Ixy, Iyy, Ixz, Iyz, Izz, which is
        Pinocchio's and about the joint frame (default zero).
    physical : bool, optional
        False accepts an inertia tensor that violates the triangle inequality (published data sets such as Corke's
        Puma 560 have some); it must still be positive semi-definite.

    Raises
    ------
    InvalidParameterError, ShapeError, NonFiniteError
        A negative mass, a tensor that is not symmetric positive semi-definite (or not a rigid body's, with
        ``physical``), a mass and centre of mass whose parameters overflow.
    """

    mass: float
    com: FloatArray
    inertia: FloatArray
    physical: bool

    def __init__(
        self, mass: float, com: ArrayLike | None = None, inertia: ArrayLike | None = None, physical: bool = True
    ) -> None:
        object.__setattr__(self, "mass", scalar(mass, "link mass [kg]", nonnegative=True))
        object.__setattr__(self, "com", vec3(np.zeros(3) if com is None else com, "link com"))
        object.__setattr__(self, "physical", boolean(physical, "link physical"))
        object.__setattr__(
            self, "inertia", inertia_tensor(np.zeros((3, 3)) if inertia is None else inertia, "link inertia", physical)
        )
        with np.errstate(over="ignore", invalid="ignore"):
            first, second = self.mass * self.com, self.inertia_about_origin()
        if not (np.isfinite(first).all() and np.isfinite(second).all()):  # the parameters π are made of these
            raise InvalidParameterError(
                f"link mass {self.mass:g} kg with com {self.com.tolist()} m overflows its parameters (first moment "
                f"m·c = {first.tolist()}, inertia about the joint origin I + m(|c|²1 − c cᵀ) with diagonal "
                f"{np.diag(second).tolist()}): give a mass and centre of mass whose products stay finite",
                value=self.mass,
            )

    def inertia_about_origin(self) -> FloatArray:
        """Inertia tensor about the joint-frame origin (parallel-axis theorem).

        Returns
        -------
        ndarray, shape (3, 3)
            I + m(|c|²1 − c cᵀ) [kg·m²].
        """
        c = self.com
        return self.inertia + self.mass * (float(c @ c) * np.eye(3) - np.outer(c, c))

    def transformed(self, rotation: FloatArray, translation: FloatArray) -> Link:
        """This body expressed in a frame where a point x of the old frame is ``rotation @ x + translation``.

        Parameters
        ----------
        rotation : ndarray, shape (3, 3)
            The rotation from the old frame's axes to the new.
        translation : ndarray, shape (3,)
            The old frame's origin in the new frame [m].

        Returns
        -------
        Link
        """
        return Link(self.mass, rotation @ self.com + translation, rotation @ self.inertia @ rotation.T, self.physical)

    def combined(self, other: Link) -> Link:
        """The rigid union of two bodies given in the same frame.

        Parameters
        ----------
        other : Link
            The other body.

        Returns
        -------
        Link
            Mass m₁ + m₂, the mass-weighted centre, the inertia about it (parallel-axis theorem).
        """
        m = self.mass + other.mass
        physical = self.physical and other.physical
        if m == 0.0:
            return Link(0.0, np.zeros(3), self.inertia + other.inertia, physical)
        c = (self.mass * self.com + other.mass * other.com) / m
        i = np.zeros((3, 3))
        for b in (self, other):
            d = b.com - c
            i += b.inertia + b.mass * (float(d @ d) * np.eye(3) - np.outer(d, d))
        return Link(m, c, i, physical)


@dataclass(frozen=True, eq=False, init=False)  # numpy fields: compare by identity
class Motor:
    """A motor driving a joint through a rigid gear.

    Parameters
    ----------
    inertia : float, optional
        The rotor's moment of inertia about its spin axis, I_m [kg·m²], ≥ 0.
    gear_ratio : float, optional
        k_r (rotor angle / joint angle), sign included, non-zero.
    axis : array_like, shape (3,), optional
        The spin axis in the frame of the link the rotor rides on (None: the joint axis).
    gyroscopic : bool, optional
        Whether the rotor's coupling with the link it rides on is part of the model (the Lagrange backend's
        ``rotor_coupling``); False: only the reflected inertia k_r² I_m, an *armature* (what
        :func:`~armctl.model.from_parameters.model_from_parameters` gives a joint that had no motor).

    Raises
    ------
    InvalidParameterError
        A negative inertia, a zero gear ratio or axis, a reflected inertia k_r² I_m that overflows.
    """

    inertia: float
    gear_ratio: float
    axis: FloatArray | None
    gyroscopic: bool

    def __init__(
        self, inertia: float = 0.0, gear_ratio: float = 1.0, axis: ArrayLike | None = None, gyroscopic: bool = True
    ) -> None:
        i = scalar(inertia, "rotor inertia [kg·m²]", nonnegative=True)
        k = scalar(gear_ratio, "gear ratio")
        if k == 0:
            raise InvalidParameterError(f"gear ratio must be non-zero, got {gear_ratio!r}", value=gear_ratio)
        if not np.isfinite(k * k * i):  # the reflected inertia k_r² I_m, a parameter of π
            raise InvalidParameterError(
                f"rotor inertia {i:g} kg·m² and gear ratio {k:g} overflow the reflected inertia k_r² I_m: give "
                "values whose product stays finite",
                value=(i, k),
            )
        object.__setattr__(self, "inertia", i)
        object.__setattr__(self, "gear_ratio", k)
        object.__setattr__(self, "gyroscopic", boolean(gyroscopic, "gyroscopic"))
        object.__setattr__(self, "axis", None)
        if axis is not None:
            a = vec3(axis, "motor axis")
            nrm = float(np.linalg.norm(a))
            if nrm < 1e-12:
                raise InvalidParameterError("motor axis must be non-zero", value=axis)
            object.__setattr__(self, "axis", readonly(a / nrm))

    @property
    def reflected_inertia(self) -> float:
        """k_r² I_m [kg·m²]: the rotor inertia seen at the joint."""
        return self.gear_ratio**2 * self.inertia


@dataclass(frozen=True, eq=False)  # numpy fields: compare by identity
class JointFriction:
    """Joint-side friction.

    Parameters
    ----------
    viscous : float, optional
        F_v [N·m·s/rad], ≥ 0.
    coulomb : float, optional
        F_c⁺, the Coulomb level for q̇ > 0 [N·m], ≥ 0.
    coulomb_negative : float, optional
        F_c⁻ for q̇ < 0, a magnitude (None: the same as ``coulomb``).
    static : float, optional
        The breakaway (stiction) level [N·m] of the simulator's stick–slip model, ≥ the Coulomb levels (None: the
        Coulomb level).
    stribeck_velocity : float, optional
        v_s [rad/s] of the Stribeck curve (0: none).

    Raises
    ------
    InvalidParameterError
        A negative or non-numeric value, a static level below the Coulomb levels.
    """

    viscous: float = 0.0
    coulomb: float = 0.0
    coulomb_negative: float | None = None
    static: float | None = None
    stribeck_velocity: float = 0.0

    def __post_init__(self) -> None:
        for name in ("viscous", "coulomb", "coulomb_negative", "static", "stribeck_velocity"):
            v = getattr(self, name)
            if v is None and name in ("coulomb_negative", "static"):  # None: follows coulomb
                continue
            object.__setattr__(self, name, scalar(v, f"friction {name}", nonnegative=True))
        if self.static is not None and self.static < max(self.coulomb, self.coulomb_neg) - 1e-12:
            raise InvalidParameterError(
                f"static friction {self.static} must be >= the Coulomb levels ({self.coulomb}, {self.coulomb_neg})",
                value=self.static,
            )

    @property
    def coulomb_neg(self) -> float:
        return self.coulomb if self.coulomb_negative is None else self.coulomb_negative

    @property
    def coulomb_mean(self) -> float:
        """(F_c⁺ + F_c⁻)/2: the Coulomb parameter of π."""
        return 0.5 * (self.coulomb + self.coulomb_neg)

    @property
    def breakaway(self) -> tuple[float, float]:
        """Breakaway magnitudes (positive direction, negative direction)."""
        if self.static is None:
            return self.coulomb, self.coulomb_neg
        return self.static, self.static

    @property
    def is_zero(self) -> bool:
        return self.viscous == 0 and self.coulomb == 0 and self.coulomb_neg == 0


@dataclass(frozen=True, eq=False)  # numpy fields: compare by identity
class JointLimits:
    """The limits of a joint (inf: none).

    Parameters
    ----------
    lower, upper : float, optional
        Position limits [rad or m], lower ≤ upper.
    velocity : float, optional
        Speed limit [rad/s or m/s], > 0.
    effort : float, optional
        Torque (force) magnitude limit [N·m or N], > 0.

    Raises
    ------
    InvalidParameterError
        lower > upper, a velocity or effort limit ≤ 0, a value that is not a number.
    """

    lower: float = -math.inf
    upper: float = math.inf
    velocity: float = math.inf
    effort: float = math.inf

    def __post_init__(self) -> None:
        vals = {k: _limit(getattr(self, k), f"joint {k} limit") for k in ("lower", "upper", "velocity", "effort")}
        if vals["lower"] > vals["upper"]:
            raise InvalidParameterError(f"joint lower limit {vals['lower']} is above upper {vals['upper']}", value=vals)
        if vals["velocity"] <= 0 or vals["effort"] <= 0:
            raise InvalidParameterError(f"velocity and effort limits must be > 0: {vals}", value=vals)
        for k, v in vals.items():
            object.__setattr__(self, k, v)


JOINT_KINDS = ("revolute", "prismatic")
# a joint's defaults: no friction, no limits (immutable, so one object serves every joint)
_NO_FRICTION = JointFriction()
_NO_LIMITS = JointLimits()


@dataclass(frozen=True, eq=False, init=False)  # numpy fields: compare by identity
class Joint:
    """One joint of a serial chain and the link it moves.

    Parameters
    ----------
    name : str
        The joint's name (also the name of its frame).
    kind : {"revolute", "prismatic"}
        How it moves.
    axis : array_like, shape (3,)
        The unit axis of motion in the joint frame.
    placement : array_like, shape (4, 4)
        The homogeneous transform of this joint's frame (at q = 0) in the previous joint's frame (the world for the
        first joint).
    link : Link
        The body it moves.
    motor : Motor, optional
        Its motor (None: none).
    friction : JointFriction, optional
        Its friction (default none).
    limits : JointLimits, optional
        Its limits (default none).

    Raises
    ------
    InvalidParameterError, ShapeError
        A kind that is not one of the two, an axis that is not a unit vector, a placement that is not a rigid
        transform, parts of the wrong type.
    """

    name: str
    kind: str
    axis: FloatArray
    placement: FloatArray
    link: Link
    motor: Motor | None
    friction: JointFriction
    limits: JointLimits

    def __init__(
        self,
        name: str,
        kind: str,
        axis: ArrayLike,
        placement: ArrayLike,
        link: Link,
        motor: Motor | None = None,
        friction: JointFriction = _NO_FRICTION,
        limits: JointLimits = _NO_LIMITS,
    ) -> None:
        values = (("name", name), ("kind", kind), ("axis", axis), ("placement", placement), ("link", link))
        for key, value in (*values, ("motor", motor), ("friction", friction), ("limits", limits)):
            object.__setattr__(self, key, value)
        self._check()

    def _check(self) -> None:
        name_text(self.name, "joint name")
        if not isinstance(self.kind, str) or self.kind not in JOINT_KINDS:
            raise InvalidParameterError(
                f"joint {self.name!r}: kind must be one of {JOINT_KINDS}, got {self.kind!r}", value=self.kind
            )
        instance_of(self.link, Link, f"joint {self.name!r} link")
        instance_of(self.motor, Motor, f"joint {self.name!r} motor", optional=True)
        instance_of(self.friction, JointFriction, f"joint {self.name!r} friction (JointFriction() for none)")
        instance_of(self.limits, JointLimits, f"joint {self.name!r} limits (JointLimits() for none)")
        a = vec3(self.axis, f"joint {self.name!r} axis")
        nrm = float(np.linalg.norm(a))
        if abs(nrm - 1.0) > 1e-6:
            raise InvalidParameterError(f"joint {self.name!r} axis must be a unit vector, got {a}", value=a)
        object.__setattr__(self, "axis", readonly(a / nrm))
        object.__setattr__(self, "placement", homogeneous(self.placement, f"joint {self.name!r} placement"))

    @property
    def motor_axis(self) -> FloatArray:
        """Rotor spin axis in the previous link's frame."""
        if self.motor is not None and self.motor.axis is not None:
            return self.motor.axis
        return readonly(self.placement[:3, :3] @ self.axis)


@dataclass(frozen=True, eq=False, init=False)  # numpy fields: compare by identity
class Frame:
    """A named frame rigidly attached to a joint.

    Parameters
    ----------
    name : str
        The frame's name.
    joint : int
        The joint it moves with: 0 the world, i the i-th joint (1-based).
    placement : array_like, shape (4, 4)
        Its homogeneous transform in that joint's frame.

    Raises
    ------
    InvalidParameterError, ShapeError
        An empty name, a negative joint index, a placement that is not a rigid transform.
    """

    name: str
    joint: int
    placement: FloatArray

    def __init__(self, name: str, joint: int, placement: ArrayLike) -> None:
        object.__setattr__(self, "name", name)
        name_text(name, "frame name")
        object.__setattr__(self, "joint", whole_number(joint, f"frame {name!r} joint index"))
        object.__setattr__(self, "placement", homogeneous(placement, f"frame {name!r} placement"))


def homogeneous(x: ArrayLike | None, name: str = "transform") -> FloatArray:
    """Check a 4×4 homogeneous transform (rotation orthonormal, last row 0 0 0 1); None is the identity."""
    if x is None:
        return readonly(np.eye(4))
    t = real_values(x, name)
    if t.shape != (4, 4):
        raise ShapeError(f"{name} must be a 4×4 homogeneous transform, got shape {t.shape}", value=x)
    r = t[:3, :3]
    if (
        not np.isfinite(t).all()
        or not np.allclose(r.T @ r, np.eye(3), atol=1e-6)
        or not np.allclose(t[3], [0, 0, 0, 1])
        or np.linalg.det(r) < 0
    ):
        raise InvalidParameterError(
            f"{name} is not a rigid transform (orthonormal rotation, det +1, last row 0 0 0 1): {t.tolist()}", value=x
        )
    return readonly(t)


def rot(axis: ArrayLike, angle: float) -> FloatArray:
    """Rotation matrix about a unit axis (Rodrigues)."""
    k = np.asarray(axis, dtype=float)
    s = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * s + (1 - math.cos(angle)) * (s @ s)


def transform(rotation: ArrayLike | None = None, translation: ArrayLike | None = None) -> FloatArray:
    t = np.eye(4)
    if rotation is not None:
        t[:3, :3] = rotation
    if translation is not None:
        t[:3, 3] = translation
    return t
