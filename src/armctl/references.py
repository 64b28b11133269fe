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

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, scalar
from armctl.errors import InvalidParameterError, ShapeError
from armctl.reference import Reference


def _row(x: ArrayLike, name: str, n: int | None = None) -> FloatArray:
    a = np.atleast_1d(np.asarray(x, dtype=float))
    if a.ndim != 1 or (n is not None and a.shape != (n,)) or not np.isfinite(a).all():
        raise ShapeError(f"{name} must be a finite vector{'' if n is None else f' of length {n}'}, got {a!r}",
                         value=x)
    return a


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
        object.__setattr__(self, "_d", self.q1 - q0)

    def __call__(self, t: float) -> Reference:
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
        c = _row(self.center, "center")
        for name in ("amplitude", "frequency", "phase"):
            v = np.broadcast_to(np.asarray(getattr(self, name), dtype=float), c.shape).copy()
            object.__setattr__(self, name, _row(v, name, c.size))
        object.__setattr__(self, "center", c)

    def __call__(self, t: float) -> Reference:
        w = 2 * math.pi * self.frequency  # type: ignore[operator]
        arg = w * t + self.phase
        s, c = np.sin(arg), np.cos(arg)
        return Reference(self.center + self.amplitude * s, self.amplitude * w * c,  # type: ignore[operator]
                         -self.amplitude * w * w * s)  # type: ignore[operator]


class WaypointSpline:
    """A C² cubic spline through ``waypoints`` (k × n) at strictly increasing ``times`` (k,), with clamped
    (zero) end velocities by default; holds the end points outside [times[0], times[-1]]."""

    def __init__(self, times: Sequence[float] | ArrayLike, waypoints: ArrayLike, bc_type: str = "clamped") -> None:
        from scipy.interpolate import CubicSpline

        t = _row(times, "times")
        w = np.asarray(waypoints, dtype=float)
        if w.ndim != 2 or w.shape[0] != t.size or t.size < 2:
            raise ShapeError(f"waypoints must be ({t.size}, n) for {t.size} times (at least 2), got {w.shape}",
                             value=waypoints)
        if not np.isfinite(w).all():
            raise ShapeError("waypoints hold NaN or inf", value=waypoints)
        if not (np.diff(t) > 0).all():
            raise InvalidParameterError(f"times must be strictly increasing, got {t}", value=times)
        self.times, self.waypoints = t, w
        self._s = CubicSpline(t, w, bc_type=bc_type, axis=0)

    def __call__(self, t: float) -> Reference:
        tc = min(max(t, self.times[0]), self.times[-1])
        q = self._s(tc)
        if t != tc:
            return Reference(q)
        return Reference(q, self._s(tc, 1), self._s(tc, 2))
