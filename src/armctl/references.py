"""Joint-space references: callables ``t -> Reference`` for closed-loop runs and tuning.

* :class:`Quintic` — minimum-jerk point-to-point move (zero velocity and acceleration at both ends);
* :class:`Sinusoid` — q_d = c + a sin(2π f t + φ) per joint;
* :class:`WaypointSpline` — a cubic spline through timed waypoints (zero end velocities by default).

Time-optimal references along geometric paths come from :mod:`armctl.planning`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, readonly, real_array, scalar, vector
from armctl.errors import InvalidParameterError, NonFiniteError, ShapeError, UnknownNameError
from armctl.reference import Reference

#: the end conditions of :class:`WaypointSpline` given by name (scipy's ``CubicSpline`` also takes explicit pairs)
BC_TYPES = ("clamped", "natural", "not-a-knot", "periodic")


def _row(x: ArrayLike, name: str, n: int | None = None, *, broadcast: bool = False) -> FloatArray:
    """``x`` as a finite vector of ``n`` entries (``n`` None: any length >= 1; a scalar is one entry or, with
    ``broadcast``, the value of every entry, as is a one-entry vector)."""
    a = real_array(x, name)
    if (a.ndim == 0 and (n is None or n == 1)) or (broadcast and a.shape in ((), (1,))):
        a = np.full(1 if n is None else n, a.item())
    if n is None:
        if a.ndim != 1 or not a.shape[0]:
            raise ShapeError(
                f"{name} must be a vector of at least one joint value, got shape {a.shape}: {x!r}", value=x
            )
        n = a.shape[0]
    return vector(a, n, name)


@dataclass(frozen=True, eq=False)
class Quintic:
    """Minimum-jerk move from ``q0`` to ``q1`` in ``duration`` [s] starting at ``t0``, holding before and after:
    q_d = q0 + (q1 − q0)(10σ³ − 15σ⁴ + 6σ⁵), σ = (t − t0)/T."""

    q0: ArrayLike
    q1: ArrayLike
    duration: float
    t0: float = 0.0
    _d: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        q0 = _row(self.q0, "q0")
        object.__setattr__(self, "q0", q0)
        object.__setattr__(self, "q1", _row(self.q1, "q1", q0.size))
        object.__setattr__(self, "duration", scalar(self.duration, "duration", positive=True))
        object.__setattr__(self, "t0", scalar(self.t0, "t0"))
        object.__setattr__(self, "_d", self.q1 - q0)

    def __call__(self, t: float) -> Reference:
        """The reference at time ``t`` [s] (a real finite scalar)."""
        if t.__class__ is not float or t - t != 0.0:  # t - t: NaN for NaN and ±inf
            t = scalar(t, "t")  # a real finite scalar, or raise naming t
        big_t = self.duration
        s = min(max((t - self.t0) / big_t, 0.0), 1.0)
        p = 10 * s**3 - 15 * s**4 + 6 * s**5
        v = (30 * s**2 - 60 * s**3 + 30 * s**4) / big_t
        a = (60 * s - 180 * s**2 + 120 * s**3) / big_t**2
        if s in (0.0, 1.0):
            v = a = 0.0
        return Reference(self.q0 + p * self._d, v * self._d, a * self._d)


@dataclass(frozen=True, eq=False)
class Sinusoid:
    """q_d = center + amplitude · sin(2π·frequency·t + phase), per joint (amplitude [rad], frequency [Hz])."""

    center: ArrayLike
    amplitude: ArrayLike
    frequency: ArrayLike
    phase: ArrayLike = 0.0

    def __post_init__(self) -> None:
        # read-only copies: the factors below are formed from them once, so the fields must not change later
        c = readonly(np.array(_row(self.center, "center")))
        for name in ("amplitude", "frequency", "phase"):
            object.__setattr__(self, name, readonly(np.array(_row(getattr(self, name), name, c.size, broadcast=True))))
        object.__setattr__(self, "center", c)
        self._factors()

    def _factors(self) -> None:
        """The per-call factors, formed once: ω = 2π f, a ω and −a ω² (a call is then eight vector operations)."""
        w = 2 * math.pi * self.frequency  # type: ignore[operator]
        object.__setattr__(self, "_w", w)
        object.__setattr__(self, "_aw", self.amplitude * w)  # type: ignore[operator]
        object.__setattr__(self, "_maww", -self.amplitude * w * w)  # type: ignore[operator]

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        if "_w" not in state:  # pickled before the factors were kept
            self._factors()

    def __call__(self, t: float) -> Reference:
        """The reference at time ``t`` [s] (a real finite scalar)."""
        if t.__class__ is not float or t - t != 0.0:  # t - t: NaN for NaN and ±inf
            t = scalar(t, "t")  # a real finite scalar, or raise naming t
        arg = self._w * t  # type: ignore[attr-defined]
        arg += self.phase
        s = np.sin(arg)
        q = self.amplitude * s  # type: ignore[operator]
        q += self.center
        s *= self._maww  # type: ignore[attr-defined]
        return Reference(q, self._aw * np.cos(arg), s)  # type: ignore[attr-defined]


class WaypointSpline:
    """A C² cubic spline through ``waypoints`` (k × n) at strictly increasing ``times`` (k,), with clamped
    (zero) end velocities by default; holds the end points outside [times[0], times[-1]]."""

    def __init__(
        self, times: Sequence[float] | ArrayLike, waypoints: ArrayLike, bc_type: str | tuple[Any, Any] = "clamped"
    ) -> None:
        """times: (k,) [s], strictly increasing, k >= 2; waypoints: (k, n) joint positions; bc_type: the end
        conditions, one of :data:`BC_TYPES` (or scipy ``CubicSpline``'s explicit ``((order, value), ...)``)."""
        from scipy.interpolate import CubicSpline

        t = _row(times, "times")
        w = real_array(waypoints, "waypoints")
        if w.ndim != 2 or w.shape[0] != t.size or t.size < 2 or not w.shape[1]:
            raise ShapeError(
                f"waypoints must be ({t.size}, n) for {t.size} times (at least 2) and n >= 1 joints, "
                f"got shape {w.shape}",
                value=waypoints,
            )
        if not np.isfinite(w).all():
            k, j = np.argwhere(~np.isfinite(w))[0]
            raise NonFiniteError(f"waypoints must be finite; waypoint {k} joint {j} is {w[k, j]}", value=waypoints)
        if not (np.diff(t) > 0).all():
            raise InvalidParameterError(f"times must be strictly increasing, got {t}", value=times)
        if not (isinstance(bc_type, tuple | list) or (isinstance(bc_type, str) and bc_type in BC_TYPES)):
            raise UnknownNameError("bc_type", bc_type, BC_TYPES)
        try:
            spline = CubicSpline(t, w, bc_type=bc_type, axis=0)
        except (ValueError, TypeError) as e:  # explicit pairs of the wrong form, periodic with different ends
            raise InvalidParameterError(
                f"bc_type={bc_type!r} does not fit these waypoints: {e}", value=bc_type
            ) from None
        self.times, self.waypoints = t, w
        self._s = spline

    def __call__(self, t: float) -> Reference:
        """The reference at time ``t`` [s] (a real finite scalar); the end points are held outside the times."""
        if t.__class__ is not float or t - t != 0.0:  # t - t: NaN for NaN and ±inf
            t = scalar(t, "t")  # a real finite scalar, or raise naming t
        tc = min(max(t, self.times[0]), self.times[-1])
        q = self._s(tc)
        if t != tc:  # held: zero velocity and acceleration (as arrays: the Reference's fast path)
            zero = np.zeros(q.shape)
            return Reference(q, zero, zero)
        return Reference(q, self._s(tc, 1), self._s(tc, 2))
