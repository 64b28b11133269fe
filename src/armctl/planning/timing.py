"""Timing laws s(t): how fast a path is traversed. Each gives s, ṡ [1/s] and s̈ [1/s²] at any time, for a
rest-to-rest motion on [0, T]: before 0 the path waits at s = 0, after T at s = 1, at rest."""

from __future__ import annotations

from abc import ABC, abstractmethod
from bisect import bisect_right

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, readonly, real_array, scalar
from armctl.errors import InvalidParameterError, NonFiniteError, ShapeError, SolverError


class Timing(ABC):
    """A rest-to-rest timing law s(t) on [0, ``duration``], s(0) = 0, s(T) = 1."""

    @property
    @abstractmethod
    def duration(self) -> float:
        """T [s]."""

    @abstractmethod
    def evaluate_inside(self, t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(s, ṡ, s̈) at times inside [0, T], not checked (:meth:`evaluate` checks t and handles the times
        outside).

        Parameters
        ----------
        t : ndarray, shape (m,)
            Times [s], each finite and inside [0, T].

        Returns
        -------
        tuple of ndarray
            (s, ṡ [1/s], s̈ [1/s²]), each (m,).
        """

    def evaluate(self, t: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(s, ṡ, s̈) at times t. Inside [0, T] the values in motion (at T, the limit from the left); outside,
        rest at the nearest end.

        Parameters
        ----------
        t : array_like
            A time [s] or an (m,) vector of times.

        Returns
        -------
        tuple of ndarray
            (s, ṡ [1/s], s̈ [1/s²]), arrays of t's shape.

        Raises
        ------
        ShapeError, NonFiniteError
            t is not a scalar or a vector, or not finite.
        """
        tt = real_array(t, "t")
        if tt.ndim > 1:
            raise ShapeError(f"t must be a scalar or a vector, got shape {tt.shape}", value=t)
        if not np.isfinite(tt).all():
            raise NonFiniteError(f"t holds NaN or inf: {t!r}", value=t)
        flat = tt.reshape(-1)
        inside = (flat >= 0.0) & (flat <= self.duration)
        s = np.where(flat > self.duration, 1.0, 0.0)
        sd, sdd = np.zeros_like(flat), np.zeros_like(flat)
        if inside.any():
            s[inside], sd[inside], sdd[inside] = self.evaluate_inside(flat[inside])
        shape = tt.shape
        return s.reshape(shape), sd.reshape(shape), sdd.reshape(shape)

    def at(self, t: float) -> tuple[float, float, float]:
        """(s, ṡ, s̈) at one time (as :meth:`evaluate`, for a control loop's rate).

        Parameters
        ----------
        t : float
            The time [s], finite.

        Returns
        -------
        tuple of float
            (s, ṡ [1/s], s̈ [1/s²]).
        """
        if t.__class__ is not float or t - t != 0.0:  # t - t: NaN for NaN and ±inf
            t = scalar(t, "t")  # a real finite scalar, or raise naming t
        if t < 0.0 or t > self.duration:
            return (0.0 if t < 0.0 else 1.0), 0.0, 0.0
        return self.at_inside(t)

    def at_inside(self, t: float) -> tuple[float, float, float]:
        """(s, ṡ, s̈) at one time inside [0, T], not checked (:meth:`at` checks t).

        Parameters
        ----------
        t : float
            The time [s], a finite float inside [0, T].

        Returns
        -------
        tuple of float
            (s, ṡ [1/s], s̈ [1/s²]).
        """
        s, sd, sdd = self.evaluate_inside(np.array([t]))
        return float(s[0]), float(sd[0]), float(sdd[0])


class GridTiming(Timing):
    """The TOPP-RA timing: x = ṡ² given at gridpoints s_i, s̈ = u_i constant over each stage [s_i, s_{i+1}]:

        u_i = (x_{i+1} − x_i) / (2 Δ_i),   Δ_i = s_{i+1} − s_i,   t_{i+1} − t_i = 2 Δ_i / (ṡ_i + ṡ_{i+1}),
        s(t) = s_i + ṡ_i τ + ½ u_i τ²,   ṡ(t) = ṡ_i + u_i τ,   τ = t − t_i.

    This is exactly the discrete model TOPP-RA optimises, so the constraints it imposed at the gridpoints hold
    at the gridpoints of the trajectory.

    Parameters
    ----------
    s : array_like, shape (N+1,)
        The gridpoints, increasing from 0 to 1.
    x : array_like, shape (N+1,)
        ṡ² at the gridpoints [1/s²], ≥ 0, with no stage at rest at both ends.

    Raises
    ------
    ShapeError, NonFiniteError, InvalidParameterError
        Arrays of different or too short lengths, not finite, or x < 0.
    SolverError
        A stage where the path would stop for ever (ṡ = 0 at both its ends).
    """

    def __init__(self, s: ArrayLike, x: ArrayLike) -> None:
        ss, xx = np.array(s, dtype=float), np.array(x, dtype=float)
        if ss.ndim != 1 or xx.shape != ss.shape or ss.shape[0] < 2:
            raise ShapeError(f"s and x must be vectors of the same length >= 2, got {ss.shape} and {xx.shape}", value=x)
        if not (np.isfinite(ss).all() and np.isfinite(xx).all()):
            raise NonFiniteError("the path velocity profile holds NaN or inf", value=x)
        if (xx < -1e-12).any():
            raise InvalidParameterError(f"x = ṡ² must be >= 0, got a minimum of {xx.min():g}", value=x)
        xx = np.maximum(xx, 0.0)
        sd = np.sqrt(xx)
        delta = np.diff(ss)
        speed = sd[:-1] + sd[1:]
        if (speed <= 0).any():
            i = int(np.flatnonzero(speed <= 0)[0])
            raise SolverError(
                f"the path velocity is zero on the whole stage s = [{ss[i]:.4g}, {ss[i + 1]:.4g}]: the "
                "motion would stop there for ever (a degenerate time-scaling result)",
                value=xx,
            )
        self.s, self.x, self.sd = readonly(ss), readonly(xx), readonly(sd)
        self.u = readonly((xx[1:] - xx[:-1]) / (2.0 * delta))
        self.t = readonly(np.concatenate(([0.0], np.cumsum(2.0 * delta / speed))))
        self._lists = (self.t.tolist(), self.s.tolist(), self.sd.tolist(), self.u.tolist())

    @property
    def duration(self) -> float:
        return float(self.t[-1])

    def evaluate_inside(self, t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        i = np.clip(np.searchsorted(self.t, t, side="right") - 1, 0, self.u.shape[0] - 1)
        tau = np.clip(t - self.t[i], 0.0, self.t[i + 1] - self.t[i])
        u = self.u[i]
        s = np.clip(self.s[i] + self.sd[i] * tau + 0.5 * u * tau**2, self.s[i], self.s[i + 1])
        sd = np.maximum(self.sd[i] + u * tau, 0.0)
        return s, sd, u

    def at_inside(self, t: float) -> tuple[float, float, float]:
        ts, ss, sds, us = self._lists
        i = min(max(bisect_right(ts, t) - 1, 0), len(us) - 1)
        tau = min(max(t - ts[i], 0.0), ts[i + 1] - ts[i])
        u = us[i]
        s = min(max(ss[i] + sds[i] * tau + 0.5 * u * tau * tau, ss[i]), ss[i + 1])
        return s, max(sds[i] + u * tau, 0.0), u


class PolynomialTiming(Timing):
    """The quintic rest-to-rest law s = 10σ³ − 15σ⁴ + 6σ⁵, σ = t/T (zero ṡ and s̈ at both ends).

    Parameters
    ----------
    duration : float
        T [s], > 0.
    """

    def __init__(self, duration: float) -> None:
        self._duration = scalar(duration, "duration", positive=True)

    @property
    def duration(self) -> float:
        return self._duration

    def evaluate_inside(self, t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        T = self._duration
        r = t / T
        s = r**3 * (10.0 - 15.0 * r + 6.0 * r**2)
        sd = 30.0 * r**2 * (1.0 - r) ** 2 / T
        sdd = 60.0 * r * (1.0 - r) * (1.0 - 2.0 * r) / T**2
        return s, sd, sdd

    def at_inside(self, t: float) -> tuple[float, float, float]:
        T = self._duration
        r = t / T
        return (
            r**3 * (10.0 - 15.0 * r + 6.0 * r**2),
            30.0 * r**2 * (1.0 - r) ** 2 / T,
            60.0 * r * (1.0 - r) * (1.0 - 2.0 * r) / T**2,
        )


class ScaledTiming(Timing):
    """A timing slowed down uniformly: s_r(t) = s(t/r), so ṡ_r = ṡ/r and s̈_r = s̈/r², and the duration is r T.

    Parameters
    ----------
    base : Timing
        The timing to scale.
    factor : float
        r > 0 (r < 1 speeds it up).
    """

    def __init__(self, base: Timing, factor: float) -> None:
        if not isinstance(base, Timing):
            raise InvalidParameterError(f"base must be a Timing, got {type(base).__name__}", value=base)
        self.base = base
        self.factor = scalar(factor, "factor", positive=True)

    @property
    def duration(self) -> float:
        return self.factor * self.base.duration

    def evaluate_inside(self, t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        r = self.factor
        s, sd, sdd = self.base.evaluate_inside(np.minimum(t / r, self.base.duration))
        return s, sd / r, sdd / r**2

    def at_inside(self, t: float) -> tuple[float, float, float]:
        r = self.factor
        s, sd, sdd = self.base.at_inside(min(t / r, self.base.duration))
        return s, sd / r, sdd / (r * r)
