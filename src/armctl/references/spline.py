"""`WaypointSpline`: a C² cubic spline through timed waypoints (zero end velocities by default)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import real_array, scalar
from armctl.errors import InvalidParameterError, NonFiniteError, ShapeError, UnknownNameError
from armctl.references._rows import row
from armctl.references.reference import Reference

#: the end conditions of :class:`WaypointSpline` given by name (scipy's ``CubicSpline`` also takes explicit pairs)
BC_TYPES = ("clamped", "natural", "not-a-knot", "periodic")


class WaypointSpline:
    """A C² cubic spline through timed waypoints, with clamped (zero) end velocities by default; holds
    the end points outside [times[0], times[-1]].

    Parameters
    ----------
    times : array_like, shape (k,)
        [s], strictly increasing, k ≥ 2.
    waypoints : array_like, shape (k, n)
        Joint positions [rad or m], finite.
    bc_type : str or tuple, optional
        The end conditions: one of :data:`BC_TYPES`, or scipy ``CubicSpline``'s explicit ``((order, value), ...)``.

    Raises
    ------
    ShapeError, NonFiniteError, InvalidParameterError, UnknownNameError
        Waypoints of the wrong shape or not finite, times not increasing, end conditions that do not fit.
    """

    def __init__(
        self, times: Sequence[float] | ArrayLike, waypoints: ArrayLike, bc_type: str | tuple[Any, Any] = "clamped"
    ) -> None:
        """See the class."""
        from scipy.interpolate import CubicSpline

        t = row(times, "times")
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
        if t != tc:  # held: zero velocity and acceleration (float arrays, which the Reference checks as a whole)
            zero = np.zeros(q.shape)
            return Reference(q, zero, zero)
        return Reference(q, self._s(tc, 1), self._s(tc, 2))
