"""Joint limits for time scaling: velocity, acceleration and torque bounds, each lower ≤ value ≤ upper per joint.

A limit is given as

* ``None``: not imposed;
* ``"model"``: the model's own limits (``model.velocity_limit`` or ``model.effort_limit``, symmetric);
* a scalar L > 0: ±L on every joint;
* an (n,) vector of L_j > 0: ±L_j;
* an (n, 2) array of (lower_j, upper_j) with lower_j < upper_j.

Velocity and acceleration bounds must also admit zero (lower ≤ 0 ≤ upper): the motion starts and ends at rest.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from armctl._checks import FloatArray, readonly, real_array, scalar
from armctl.errors import InvalidParameterError, NonFiniteError, ShapeError
from armctl.model.robot import RobotModel

KINDS = ("velocity", "acceleration", "torque")
UNITS = {"velocity": "rad/s", "acceleration": "rad/s²", "torque": "N·m"}


@dataclass(frozen=True)
class Bounds:
    """lower ≤ value ≤ upper per joint.

    Parameters
    ----------
    kind : str
        One of :data:`KINDS` (``"velocity"`` [rad/s], ``"acceleration"`` [rad/s²], ``"torque"`` [N·m]).
    lower, upper : ndarray, shape (n,)
        The bounds, lower < upper (read-only).
    """

    kind: str
    lower: FloatArray
    upper: FloatArray

    @property
    def unit(self) -> str:
        return UNITS[self.kind]

    def scaled(self, factor: float) -> Bounds:
        """The bounds shrunk (factor < 1) about their midpoint: mid ± factor · half-range.

        Parameters
        ----------
        factor : float
            The scale, > 0.

        Returns
        -------
        Bounds
        """
        mid, half = 0.5 * (self.upper + self.lower), 0.5 * (self.upper - self.lower)
        return Bounds(self.kind, readonly(mid - factor * half), readonly(mid + factor * half))

    def utilisation(self, values: FloatArray) -> FloatArray:
        """How much of the range each value uses: |v − mid| / half-range (1 at a bound, > 1 outside).

        For symmetric bounds ±L this is |v|/L.

        Parameters
        ----------
        values : ndarray, shape (..., n)
            Values in the bounds' unit.

        Returns
        -------
        ndarray, shape (..., n)
        """
        mid, half = 0.5 * (self.upper + self.lower), 0.5 * (self.upper - self.lower)
        return np.abs(values - mid) / half


@dataclass(frozen=True)
class JointLimits:
    """The limits a time scaling respects; each is a :class:`Bounds` or None (not imposed).

    Parameters
    ----------
    velocity, acceleration, torque : Bounds or None
        The joint velocity [rad/s], acceleration [rad/s²] and torque [N·m] bounds.
    torque_margin : float, optional
        m ∈ [0, 1): the torque bounds actually planned with are the given ones shrunk by m about their midpoint
        (``planned_torque``); velocity and acceleration are planned as given.
    """

    velocity: Bounds | None
    acceleration: Bounds | None
    torque: Bounds | None
    torque_margin: float = 0.0

    @property
    def planned_torque(self) -> Bounds | None:
        if self.torque is None or self.torque_margin == 0.0:
            return self.torque
        return self.torque.scaled(1.0 - self.torque_margin)

    def planned(self) -> dict[str, Bounds]:
        """The bounds planned with, by kind (only those imposed).

        Returns
        -------
        dict of str to Bounds
        """
        out = {"velocity": self.velocity, "acceleration": self.acceleration, "torque": self.planned_torque}
        return {k: v for k, v in out.items() if v is not None}


def bounds(value: Any, kind: str, model: RobotModel) -> Bounds | None:
    """Parse one limit (see the module docstring) for ``model``; raise an ArmctlError naming what is wrong."""
    n = model.n
    name = f"{kind} limit"
    if value is None:
        return None
    if isinstance(value, str):
        if value != "model" or kind == "acceleration":
            valid = "None, a number, an (n,) or (n, 2) array" + (", or 'model'" if kind != "acceleration" else "")
            raise InvalidParameterError(f"{name} must be {valid}; got {value!r}", value=value)
        lim = np.array(model.velocity_limit if kind == "velocity" else model.effort_limit, dtype=float)
        if not np.isfinite(lim).all():
            raise InvalidParameterError(
                f"{name}='model' but model {model.name!r} has no {kind} limit on joints "
                f"{np.flatnonzero(~np.isfinite(lim)).tolist()}; give the limits explicitly",
                value=lim,
            )
        value = lim
    a = np.array(real_array(value, name))  # a copy (made read-only below); True, "2.0", dates are refused
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.shape == (n,):
        if np.isnan(a).any() or np.isinf(a).any():
            raise NonFiniteError(
                f"{name} holds NaN or inf: {a}; give finite limits (use None for no limit)", value=value
            )
        if (a <= 0).any():
            j = int(np.argmin(a))
            raise InvalidParameterError(
                f"{name} of joint {j} is {a[j]:g} {UNITS[kind]}; a symmetric limit must be "
                "> 0 (give an (n, 2) array for asymmetric bounds)",
                value=value,
            )
        lower, upper = -a, a
    elif a.shape == (n, 2):
        if not np.isfinite(a).all():
            raise NonFiniteError(f"{name} holds NaN or inf: {a.tolist()}", value=value)
        lower, upper = a[:, 0].copy(), a[:, 1].copy()
        if (lower >= upper).any():
            j = int(np.argmax(lower - upper))
            raise InvalidParameterError(
                f"{name} of joint {j}: lower {lower[j]:g} must be below upper {upper[j]:g} "
                f"{UNITS[kind]}; columns are (lower, upper)",
                value=value,
            )
        if kind != "torque" and ((lower > 0).any() or (upper < 0).any()):
            j = int(np.flatnonzero((lower > 0) | (upper < 0))[0])
            raise InvalidParameterError(
                f"{name} of joint {j} is [{lower[j]:g}, {upper[j]:g}] {UNITS[kind]}; it must "
                "contain 0, since the motion starts and ends at rest",
                value=value,
            )
    else:
        raise ShapeError(
            f"{name} must be a scalar, an ({n},) vector or an ({n}, 2) array of (lower, upper), got shape {a.shape}",
            value=value,
        )
    return Bounds(kind, readonly(lower), readonly(upper))


def joint_limits(
    model: RobotModel,
    vel_limit: Any = None,
    acc_limit: Any = None,
    torque_limit: Any = None,
    torque_margin: float = 0.0,
) -> JointLimits:
    """All limits of a time-scaling problem, checked; at least one must be imposed.

    Parameters
    ----------
    model : RobotModel
        The arm (its limits for ``"model"``, its joint count).
    vel_limit, acc_limit, torque_limit : optional
        [rad/s], [rad/s²], [N·m]: None (not imposed), ``"model"`` (the model's velocity / effort limits; not for
        acceleration), a scalar, an (n,) vector (symmetric) or (n, 2) bounds.
    torque_margin : float, optional
        Plan with the torque bounds shrunk by this fraction, in [0, 1).

    Returns
    -------
    JointLimits

    Raises
    ------
    InvalidParameterError, ShapeError, NonFiniteError
        No limit imposed, bounds that are not numbers, of the wrong shape, or with lower ≥ upper.
    """
    m = scalar(torque_margin, "torque_margin")  # "0.1", True and NaN are refused, not converted
    if not 0.0 <= m < 1.0:
        raise InvalidParameterError(
            f"torque_margin must be in [0, 1) (0.1 plans with 90 % of the torque range), got {torque_margin!r}",
            value=torque_margin,
        )
    lim = JointLimits(
        bounds(vel_limit, "velocity", model),
        bounds(acc_limit, "acceleration", model),
        bounds(torque_limit, "torque", model),
        m,
    )
    if lim.velocity is None and lim.acceleration is None and lim.torque is None:
        raise InvalidParameterError(
            "no limit given: with no velocity, acceleration or torque limit the fastest "
            "motion takes no time; pass vel_limit=, acc_limit= and/or torque_limit= "
            "('model' uses the model's limits)",
            value=None,
        )
    if m and lim.torque is None:
        raise InvalidParameterError(f"torque_margin={m} needs a torque_limit", value=m)
    return lim
