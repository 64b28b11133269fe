"""Excitation trajectories: a finite Fourier series per joint (Swevers et al. 1997).

    q_i(t)  = q0_i + Σ_{l=1}^{N} [ a_il/(ω_f l) sin(ω_f l t) − b_il/(ω_f l) cos(ω_f l t) ]
    q̇_i(t)  = Σ_l [ a_il cos(ω_f l t) + b_il sin(ω_f l t) ]
    q̈_i(t)  = Σ_l ω_f l [ −a_il sin(ω_f l t) + b_il cos(ω_f l t) ]

with ω_f = 2π / period. The trajectory is periodic, so measurements can be averaged over periods and
filtered without transients, and its spectrum is known (N ω_f), so the filters of the data pipeline can be
placed above it. :func:`optimize_excitation` chooses the coefficients; this file only evaluates them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, per_joint, readonly, real_array, scalar, whole_number
from armctl.errors import InvalidParameterError, NonFiniteError, ShapeError
from armctl.references import Reference


@dataclass(frozen=True)
class FourierExcitation:
    """A periodic joint trajectory, a finite Fourier series per joint.

    Parameters
    ----------
    q0 : ndarray, shape (n,)
        Offsets [rad].
    a, b : ndarray, shape (n, N)
        Coefficients of the velocity's cosine and sine terms [rad/s].
    period : float
        T_f = 2π/ω_f [s], > 0 and large enough that N ω_f is finite.
    """

    q0: FloatArray
    a: FloatArray
    b: FloatArray
    period: float

    def __post_init__(self) -> None:
        q0 = np.array(real_array(self.q0, "q0")).reshape(-1)
        a, b = np.array(real_array(self.a, "a")), np.array(real_array(self.b, "b"))
        if a.ndim != 2 or a.shape != b.shape or a.shape[0] != q0.shape[0] or a.shape[1] < 1:
            raise ShapeError(
                f"a and b must both be (n, N) with n = len(q0) = {q0.shape[0]} and N >= 1; got {a.shape} and {b.shape}",
                value=(self.a, self.b),
            )
        if not (np.isfinite(q0).all() and np.isfinite(a).all() and np.isfinite(b).all()):
            raise InvalidParameterError("Fourier coefficients must be finite", value=(self.q0, self.a, self.b))
        period = scalar(self.period, "period", positive=True)
        if not math.isfinite(2.0 * math.pi * a.shape[1] / period):
            raise InvalidParameterError(
                f"period={self.period!r} s is too small: the top harmonic's frequency "
                f"2π·{a.shape[1]}/period overflows; use a period of seconds",
                value=self.period,
            )
        object.__setattr__(self, "q0", readonly(q0))
        object.__setattr__(self, "a", readonly(a))
        object.__setattr__(self, "b", readonly(b))
        object.__setattr__(self, "period", period)

    @property
    def n(self) -> int:
        return int(self.q0.shape[0])

    @property
    def harmonics(self) -> int:
        """Number N of harmonics."""
        return int(self.a.shape[1])

    @property
    def omega(self) -> float:
        """Fundamental frequency ω_f [rad/s]."""
        return 2.0 * math.pi / self.period

    @property
    def bandwidth(self) -> float:
        """Highest frequency in the trajectory, N ω_f / 2π [Hz]."""
        return self.harmonics / self.period

    def evaluate(self, t: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(q, q̇, q̈) at times t.

        Parameters
        ----------
        t : array_like
            A time or times [s].

        Returns
        -------
        tuple of ndarray
            Each (len(t), n), or (n,) for a scalar t [rad, rad/s, rad/s²].
        """
        tt = real_array(t, "t")
        if not np.isfinite(tt).all():
            raise NonFiniteError(f"t holds NaN or inf: {t!r:.80}", value=t)
        scalar_t = tt.ndim == 0
        tt = tt.reshape(-1)
        wl = self.omega * np.arange(1, self.harmonics + 1)  # (N,)
        phase = np.outer(tt, wl)  # (S, N)
        s, c = np.sin(phase), np.cos(phase)
        q = self.q0 + (s / wl) @ self.a.T - (c / wl) @ self.b.T
        qd = c @ self.a.T + s @ self.b.T
        qdd = (-s * wl) @ self.a.T + (c * wl) @ self.b.T
        if scalar_t:
            return q[0], qd[0], qdd[0]
        return q, qd, qdd

    def __call__(self, t: float) -> Reference:
        """The trajectory at time ``t`` [s] as a :class:`~armctl.Reference` (usable by ``simulate``)."""
        q, qd, qdd = self.evaluate(scalar(t, "t"))
        return Reference(q, qd, qdd)

    def extremes(self, samples_per_period: int = 2000) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """(min q, max q, max |q̇|, max |q̈|) per joint over one period.

        Parameters
        ----------
        samples_per_period : int, optional
            Grid points (≥ 1).

        Returns
        -------
        tuple of ndarray
            Four (n,) arrays [rad, rad, rad/s, rad/s²].
        """
        samples = whole_number(samples_per_period, "samples_per_period", minimum=1)
        t = np.linspace(0.0, self.period, samples, endpoint=False)
        q, qd, qdd = self.evaluate(t)
        return q.min(axis=0), q.max(axis=0), np.abs(qd).max(axis=0), np.abs(qdd).max(axis=0)

    def scaled(self, factor: ArrayLike) -> FourierExcitation:
        """The same trajectory with each joint's motion about q0 scaled.

        Parameters
        ----------
        factor : array_like
            A scalar or (n,) factors.

        Returns
        -------
        FourierExcitation
        """
        f = per_joint(factor, self.n, "factor")
        if not np.isfinite(f).all():
            raise NonFiniteError(f"factor holds NaN or inf: {factor!r}", value=factor)
        f = f[:, None]
        return FourierExcitation(self.q0, self.a * f, self.b * f, self.period)

    def within(
        self, lower: ArrayLike, upper: ArrayLike, velocity: ArrayLike, acceleration: ArrayLike, tol: float = 1e-9
    ) -> bool:
        """Whether the trajectory stays within limits (checked on a dense grid).

        Each limit is a scalar or an (n,) vector (±inf: none).

        Parameters
        ----------
        lower, upper : array_like
            Position limits [rad].
        velocity : array_like
            |q̇| limit [rad/s].
        acceleration : array_like
            |q̈| limit [rad/s²].
        tol : float, optional
            Slack allowed, ≥ 0.

        Returns
        -------
        bool
        """
        lo, hi, vel, acc = (
            per_joint(x, self.n, name)
            for x, name in ((lower, "lower"), (upper, "upper"), (velocity, "velocity"), (acceleration, "acceleration"))
        )
        for x, name in ((lo, "lower"), (hi, "upper"), (vel, "velocity"), (acc, "acceleration")):
            if np.isnan(x).any():
                raise NonFiniteError(f"{name} holds NaN: {x.tolist()}", value=x)
        eps = scalar(tol, "tol", nonnegative=True)
        qmin, qmax, vmax, amax = self.extremes()
        return bool(
            np.all(qmin >= lo - eps)
            and np.all(qmax <= hi + eps)
            and np.all(vmax <= vel + eps)
            and np.all(amax <= acc + eps)
        )
