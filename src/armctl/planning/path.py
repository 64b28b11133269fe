"""Geometric paths q(s) in joint space, s ∈ [0, 1], with their first two derivatives.

A path is the geometry only; a timing law s(t) turns it into a trajectory (see :mod:`.trajectory`). Along a
path, with ṡ = ds/dt and s̈ = d²s/dt²,

    q̇ = q'(s) ṡ,        q̈ = q'(s) s̈ + q''(s) ṡ²,

which is what time scaling works with. Two paths are provided: :class:`SplinePath`, a cubic spline through
joint waypoints (knots at the normalised cumulative chord length, so that |q'| is of the order of the path
length everywhere), and :class:`LinePath`, a straight line between two configurations (q'' = 0).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from bisect import bisect_right

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, readonly, real_array, scalar, vector
from armctl.errors import InvalidParameterError, NonFiniteError, ShapeError

BC_TYPES = ("not-a-knot", "natural", "clamped")
KNOTS = ("chord", "uniform")


class Path(ABC):
    """A C² path q(s) (n joints) on s ∈ [0, 1].

    Subclasses implement :meth:`_derivatives`; :meth:`__call__` and :meth:`derivatives` check ``s``.
    """

    n: int

    @property
    def interval(self) -> tuple[float, float]:
        """The path parameter range (0, 1)."""
        return (0.0, 1.0)

    @property
    def breakpoints(self) -> FloatArray:
        """Parameters s of the waypoints (where the path's pieces join), first 0 and last 1."""
        return readonly(np.array([0.0, 1.0]))

    def piece(self, s: float) -> int:
        """The piece the parameter lies in.

        Parameters
        ----------
        s : float
            The path parameter, in [0, 1].

        Returns
        -------
        int
            k such that s lies in the piece [s_k, s_{k+1}] between waypoints k and k + 1 (the last one at s = 1).
        """
        bp = self.breakpoints
        return int(np.clip(np.searchsorted(bp, s, side="right") - 1, 0, len(bp) - 2))

    def range_points(self, per_piece: int = 400) -> FloatArray:
        """Parameters s at which the path reaches its extreme joint positions, for range checks.

        Here the breakpoints and ``per_piece`` evenly spaced samples of every piece between them (subclasses that know
        their pieces return the exact extrema).

        Parameters
        ----------
        per_piece : int, optional
            Samples per piece.

        Returns
        -------
        ndarray
            Parameters in [0, 1], increasing.
        """
        knots = self.breakpoints
        frac = np.linspace(0.0, 1.0, per_piece + 1)
        return np.unique(np.concatenate(((knots[:-1, None] + np.diff(knots)[:, None] * frac).ravel(), knots)))

    @abstractmethod
    def _derivatives(self, s: FloatArray, order: int) -> FloatArray:
        """d^order q / ds^order at every s (m,) → (m, n); s is checked and inside [0, 1]."""

    def __call__(self, s: ArrayLike, order: int = 0) -> FloatArray:
        """q(s) (order 0), q'(s) (1) or q''(s) (2) [rad, rad, rad]; a scalar s gives (n,), an array (m,) gives
        (m, n)."""
        if order not in (0, 1, 2):
            raise InvalidParameterError(f"path derivative order must be 0, 1 or 2, got {order!r}", value=order)
        ss = self._params(s)
        out = self._derivatives(ss.reshape(-1), order)
        return out[0] if ss.ndim == 0 else out

    def derivatives(self, s: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(q, q', q'') at many parameters.

        Parameters
        ----------
        s : array_like, shape (m,)
            Parameters in [0, 1].

        Returns
        -------
        tuple of ndarray
            (q, q', q''), each (m, n).

        Raises
        ------
        InvalidParameterError, NonFiniteError
            A parameter outside [0, 1] or not finite.
        """
        ss = self._params(s).reshape(-1)
        return self._derivatives(ss, 0), self._derivatives(ss, 1), self._derivatives(ss, 2)

    def at(self, s: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(q, q', q'') at one parameter — :meth:`derivatives` for a control loop's rate.

        Parameters
        ----------
        s : float
            The parameter, in [0, 1].

        Returns
        -------
        tuple of ndarray
            (q, q', q''), each (n,).
        """
        if s.__class__ is not float:
            s = scalar(s, "path parameter s")
        if not 0.0 <= s <= 1.0:
            return Path._at(self, s)  # checked there: raises beyond [0, 1], clips a rounding error
        return self._at(s)

    def _at(self, s: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        """:meth:`at` for a float s in [0, 1]; a path with a closed form at one parameter overrides it."""
        q, dq, ddq = self.derivatives(np.array([s]))
        return q[0], dq[0], ddq[0]

    @staticmethod
    def _params(s: ArrayLike) -> FloatArray:
        ss = real_array(s, "path parameter s")
        if ss.ndim > 1:
            raise ShapeError(f"path parameter s must be a scalar or a vector, got shape {ss.shape}", value=s)
        if not np.isfinite(ss).all():
            raise NonFiniteError(f"path parameter s holds NaN or inf: {s!r}", value=s)
        if ss.size and (ss.min() < -1e-12 or ss.max() > 1.0 + 1e-12):
            raise InvalidParameterError(
                f"path parameter s must lie in [0, 1], got values in [{ss.min():g}, {ss.max():g}]", value=s
            )
        return np.clip(ss, 0.0, 1.0)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(n={self.n})"


class SplinePath(Path):
    """Cubic spline through joint waypoints.

    Parameters
    ----------
    waypoints : array_like, shape (m, n)
        Joint positions [rad], m ≥ 2, consecutive ones distinct.
    knots : {"chord", "uniform"} or array_like, optional
        ``"chord"`` (default) puts waypoint k at s_k = L_k / L with L_k the cumulative joint-space distance
        Σ|q_{i+1} − q_i| up to it; ``"uniform"`` at k/(m−1); or an explicit increasing (m,) array from 0 to 1.
    bc_type : {"not-a-knot", "natural", "clamped"}, optional
        End conditions of :class:`scipy.interpolate.CubicSpline`: ``"not-a-knot"`` (default; two waypoints give a
        straight line), ``"natural"`` (q'' = 0 at the ends) or ``"clamped"`` (q' = 0 at the ends — avoid for time
        scaling: where q' = 0 the path velocity ṡ is unbounded by joint velocity limits).

    Raises
    ------
    ShapeError, NonFiniteError, InvalidParameterError
        Waypoints of the wrong shape, not finite or repeated; knots that are not increasing from 0 to 1.
    """

    def __init__(self, waypoints: ArrayLike, knots: str | ArrayLike = "chord", bc_type: str = "not-a-knot") -> None:
        """See the class."""
        from scipy.interpolate import CubicSpline

        w = np.array(real_array(waypoints, "waypoints"))
        if w.ndim != 2 or w.shape[0] < 2 or w.shape[1] < 1:
            raise ShapeError(
                f"waypoints must be an (m, n) array with m >= 2 waypoints of n joints, got shape {w.shape}",
                value=waypoints,
            )
        if not np.isfinite(w).all():
            bad = np.argwhere(~np.isfinite(w))[0]
            raise NonFiniteError(
                f"waypoint {bad[0]} joint {bad[1]} is {w[tuple(bad)]}; waypoints must be finite", value=waypoints
            )
        steps = np.linalg.norm(np.diff(w, axis=0), axis=1)
        if (steps <= 1e-12 * max(1.0, float(np.abs(w).max()))).any():
            k = int(np.argmin(steps))
            raise InvalidParameterError(
                f"waypoints {k} and {k + 1} coincide; remove the repeated waypoint (a "
                "path that stops has no time-optimal scaling through the stop)",
                value=w,
            )
        if isinstance(knots, str):
            if knots == "chord":
                s = np.concatenate(([0.0], np.cumsum(steps))) / steps.sum()
            elif knots == "uniform":
                s = np.linspace(0.0, 1.0, w.shape[0])
            else:
                raise InvalidParameterError(f"knots must be one of {KNOTS} or an array, got {knots!r}", value=knots)
        else:
            s = vector(knots, w.shape[0], "knots")
            if s[0] != 0.0 or s[-1] != 1.0 or (np.diff(s) <= 0).any():
                raise InvalidParameterError(f"knots must increase strictly from 0 to 1, got {s}", value=knots)
        if bc_type not in BC_TYPES:
            raise InvalidParameterError(f"bc_type must be one of {BC_TYPES}, got {bc_type!r}", value=bc_type)
        s[-1] = 1.0
        self.n = w.shape[1]
        self.waypoints = readonly(w)
        self._knots = readonly(s)
        self._splines = [CubicSpline(s, w, bc_type=bc_type)]
        self._splines += [self._splines[0].derivative(k) for k in (1, 2)]
        self._knot_list = s.tolist()
        self._coeffs = [tuple(self._splines[0].c[:, k, :]) for k in range(s.shape[0] - 1)]

    @property
    def breakpoints(self) -> FloatArray:
        return self._knots

    def range_points(self, per_piece: int = 400) -> FloatArray:
        """The breakpoints and, in every piece, the roots of each joint's q'(s) (a quadratic there): where the
        cubic pieces reach their extreme positions, exactly.

        Parameters
        ----------
        per_piece : int, optional
            Not needed here (kept for the signature of :meth:`Path.range_points`).

        Returns
        -------
        ndarray
            Parameters in [0, 1], increasing.
        """
        c = self._splines[0].c  # (4, pieces, n): q = c0 t³ + c1 t² + c2 t + c3, t = s − s_k
        a, b, d = 3.0 * c[0], 2.0 * c[1], c[2]  # q' = a t² + b t + d
        width = np.diff(self._knots)[:, None]
        with np.errstate(divide="ignore", invalid="ignore"):
            root = np.sqrt(b * b - 4.0 * a * d)
            big = np.abs(a) > 1e-12 * (np.abs(b) + np.abs(d) + 1e-300)
            roots = [np.where(big, (-b + root) / (2.0 * a), -d / b), np.where(big, (-b - root) / (2.0 * a), np.nan)]
        starts = np.broadcast_to(self._knots[:-1, None], a.shape)
        points = [self._knots]
        for t in roots:
            ok = np.isfinite(t) & (t > 0.0) & (t < width)
            points.append(starts[ok] + t[ok])
        return np.unique(np.concatenate(points))

    def _derivatives(self, s: FloatArray, order: int) -> FloatArray:
        return self._splines[order](s)

    def _at(self, s: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        # the cubic piece q = c₀d³ + c₁d² + c₂d + c₃, d = s − s_k, evaluated directly (no scipy call)
        knots = self._knot_list
        k = min(max(bisect_right(knots, s) - 1, 0), len(knots) - 2)
        d = s - knots[k]
        c0, c1, c2, c3 = self._coeffs[k]
        return (((c0 * d + c1) * d + c2) * d + c3, (3.0 * c0 * d + 2.0 * c1) * d + c2, 6.0 * c0 * d + 2.0 * c1)


class LinePath(Path):
    """The straight line q(s) = q₀ + s (q₁ − q₀) in joint space; q' = q₁ − q₀, q'' = 0.

    Parameters
    ----------
    start, end : array_like, shape (n,)
        q₀ and q₁ [rad], finite and distinct.

    Raises
    ------
    ShapeError, NonFiniteError, InvalidParameterError
        Vectors of different lengths, not finite, or equal.
    """

    def __init__(self, start: ArrayLike, end: ArrayLike) -> None:
        a, b = real_array(start, "start"), real_array(end, "end")
        if a.ndim > 1 or a.size == 0:
            raise ShapeError(f"start must be a non-empty vector, got shape {a.shape}: {start!r}", value=start)
        if b.ndim > 1 or b.size != a.size:
            raise ShapeError(
                f"start and end must be vectors of the same length, got start {start!r} (shape "
                f"{a.shape}) and end {end!r} (shape {b.shape})",
                value=end,
            )
        self.n = a.size
        self.start = readonly(np.array(vector(a.reshape(-1), self.n, "start")))
        self.end = readonly(np.array(vector(b.reshape(-1), self.n, "end")))
        delta = self.end - self.start
        if not np.abs(delta).max() > 0.0:
            raise InvalidParameterError(
                f"start and end coincide ({self.start.tolist()}): a line path needs two distinct configurations",
                value=end,
            )
        self.delta = readonly(delta)
        self.waypoints = readonly(np.stack([self.start, self.end]))

    def _derivatives(self, s: FloatArray, order: int) -> FloatArray:
        if order == 0:
            return self.start + s[:, None] * self.delta
        if order == 1:
            return np.repeat(self.delta[None, :], s.shape[0], axis=0)
        return np.zeros((s.shape[0], self.n))

    def _at(self, s: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        return self.start + s * self.delta, self.delta.copy(), np.zeros(self.n)


def as_path(path_or_waypoints: Path | ArrayLike, n: int | None = None) -> Path:
    """``path_or_waypoints`` as a :class:`Path`: a Path is returned as it is, an (m, n) array becomes a
    :class:`SplinePath`. With ``n`` given, the path must have n joints."""
    path = path_or_waypoints if isinstance(path_or_waypoints, Path) else SplinePath(path_or_waypoints)
    if n is not None and path.n != n:
        raise ShapeError(
            f"the path has {path.n} joints (waypoints of width {path.n}), the arm {n}; give waypoints "
            f"as an (m, {n}) array",
            value=path_or_waypoints,
        )
    return path
