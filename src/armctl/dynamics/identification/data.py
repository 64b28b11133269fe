"""Measured motion for identification: sampled q and τ → (q, q̇, q̈, τ) and how to reduce them.

A robot logs joint positions (encoders; q̇ and q̈ are not measured) and joint torques (motor currents) at a
fixed rate. :func:`prepare_data` turns such a log into the samples the regressor needs:

1. zero-phase low-pass F (Butterworth of ``order``, run forwards and backwards: no phase lag, so q̇ and q̈
   stay aligned with τ) on q;
2. q̇ and q̈ from the filtered q by central differences (second order);
3. parallel filtering and decimation (Gautier 1997), done when the problem is built: the same F is applied
   to τ *and to every column of the regressor* evaluated at the full rate, so that F(τ) = F(Y) π holds
   exactly. Filtering only τ would smooth its Coulomb jumps at velocity reversals while sgn(q̇) in Y stays
   sharp, a systematic error of the order of the Coulomb level; filtering only q would leave the torque
   noise unfiltered;
4. ``trim`` samples dropped at each end (where the filter's start-up transient lives), then every
   ``decimate``-th sample kept, alias-free because F has band-limited everything below the new Nyquist
   frequency (checked).

The start-up transient of F decays as rᵏ, r the largest pole magnitude of F (:func:`settling_samples`): a
Butterworth filter's slowest pole has damping sin(π/2N) at order N, so the transient of an order-20 filter
lasts five times longer than an order-4 one's (at 5 Hz, 1 kHz: 2.8 s against 0.6 s). The default trim covers
it down to :data:`TRANSIENT_LEFT` of its start; a shorter trim warns
(:class:`~armctl.errors.IdentificationWarning`).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
import scipy.signal
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, readonly, real_array, scalar, whole_number
from armctl.errors import IdentificationWarning, InvalidParameterError, NonFiniteError, ShapeError

#: the part of a filter's start-up transient the default trim leaves in the kept samples (q̈ of a noisy 1 Hz
#: motion filtered at 5 Hz then differs from the truth by 0.2 % of its range at orders 4 to 20, against 0.1 %
#: far from the ends; trimmed by 3 f_s/f_c whatever the order, 44 % at order 20)
TRANSIENT_LEFT = 1e-3


def settling_samples(sos: ArrayLike, left: float = TRANSIENT_LEFT) -> int:
    """Samples after which the start-up transient of a filter has decayed to ``left`` of its start:
    ⌈ln(left) / ln r⌉, r < 1 the largest magnitude of its poles (each section's roots of a₀z² + a₁z + a₂).

    Parameters
    ----------
    sos : array_like, shape (sections, 6)
        Second-order sections, as from ``scipy.signal.butter(..., output="sos")``.
    left : float, optional
        The fraction left, in (0, 1).

    Returns
    -------
    int

    Raises
    ------
    InvalidParameterError
        A filter that is not stable (r ≥ 1).
    """
    a = np.asarray(sos, dtype=float)[:, 3:6]
    r = max(float(np.abs(np.roots(row)).max()) if row[1:].any() else 0.0 for row in a / a[:, :1])
    if r >= 1.0:
        raise InvalidParameterError(
            f"sos is not a stable filter: it has a pole of magnitude {r:.6g} >= 1 (its output would grow without "
            "bound); design it again, e.g. scipy.signal.butter(order, cutoff, fs=fs, output='sos')",
            value=r,
        )
    return 0 if r == 0.0 else math.ceil(math.log(left) / math.log(r))


def _warn_transient(trim: int, sos: FloatArray, stacklevel: int) -> None:
    """Warn (:class:`~armctl.errors.IdentificationWarning`) if ``trim`` is shorter than the start-up transient
    of the filter ``sos`` (:func:`settling_samples`)."""
    settle = settling_samples(sos)
    if trim < settle:
        warnings.warn(
            f"trim={trim} leaves the filter's start-up transient in the kept samples: its {sos.shape[0]} "
            f"sections decay to {TRANSIENT_LEFT:g} of it only after {settle} samples (q̈, and what is identified "
            f"from it, is off near the ends); use trim >= {settle}, or prepare_data's default",
            IdentificationWarning,
            stacklevel=stacklevel,
        )


@dataclass(frozen=True)
class IdentificationData:
    """Samples of the motion and the torques, read-only, and how to reduce them before estimation.

    Build one from a raw log with :func:`prepare_data`, or directly when q̇ and q̈ are known.

    Parameters
    ----------
    t : ndarray, shape (S,)
        Sample times [s].
    q, qd, qdd : ndarray, shape (S, n)
        Joint positions [rad], velocities [rad/s], accelerations [rad/s²].
    tau : ndarray, shape (S, n)
        Joint torques [N·m].
    sos : ndarray, shape (sections, 6), optional
        Second-order sections of the zero-phase low-pass applied to τ and to the regressor's columns, as from
        ``scipy.signal.butter(..., output="sos")`` (None: none, e.g. exact simulated samples).
    decimate : int, optional
        Keep every k-th sample after filtering (a whole number ≥ 1).
    trim : int, optional
        Samples dropped at each end after filtering (a whole number ≥ 0).
    """

    t: FloatArray
    q: FloatArray
    qd: FloatArray
    qdd: FloatArray
    tau: FloatArray
    sos: FloatArray | None = None
    decimate: int = 1
    trim: int = 0

    def __post_init__(self) -> None:
        t = np.array(real_array(self.t, "t")).reshape(-1)
        arrays = {k: np.array(real_array(getattr(self, k), k)) for k in ("q", "qd", "qdd", "tau")}
        shape = arrays["q"].shape
        if len(shape) != 2:
            raise ShapeError(f"q must be (samples, n), got shape {shape}", value=self.q)
        for name, a in arrays.items():
            if a.shape != shape:
                raise ShapeError(
                    f"{name} has shape {a.shape} but q has {shape}: every signal needs one row per "
                    "sample and one column per joint",
                    value=a,
                )
        if t.shape != (shape[0],):
            raise ShapeError(f"t has {t.shape[0]} samples but q has {shape[0]}", value=self.t)
        for name, a in (("t", t), *arrays.items()):
            if not np.isfinite(a).all():
                raise NonFiniteError(f"{name} holds NaN or inf", value=a)
            object.__setattr__(self, name, readonly(a))
        object.__setattr__(self, "decimate", whole_number(self.decimate, "decimate", minimum=1))
        object.__setattr__(self, "trim", whole_number(self.trim, "trim"))
        if self.sos is not None:
            sos = np.array(real_array(self.sos, "sos"))
            if sos.ndim != 2 or sos.shape[0] < 1 or sos.shape[1] != 6:
                raise ShapeError(
                    f"sos must be second-order sections of shape (sections, 6) (scipy.signal.butter(..., "
                    f"output='sos')), got shape {sos.shape}",
                    value=self.sos,
                )
            if not np.isfinite(sos).all() or np.any(sos[:, 3] == 0):
                raise InvalidParameterError(
                    "sos must be finite with a nonzero leading denominator coefficient (column 3) in every section",
                    value=self.sos,
                )
            object.__setattr__(self, "sos", readonly(sos))
            _warn_transient(self.trim, sos, stacklevel=4)
        if len(self.kept) < 1:
            raise InvalidParameterError(
                f"{shape[0]} samples leave none after trim={self.trim} at each end", value=self.trim
            )

    @property
    def n(self) -> int:
        return int(self.q.shape[1])

    @property
    def samples(self) -> int:
        """Number of (full-rate) samples."""
        return int(self.q.shape[0])

    @property
    def kept(self) -> range:
        """Indices of the samples kept after trimming and decimation."""
        return range(self.trim, self.samples - self.trim, self.decimate)

    def reduce(self, x: ArrayLike) -> FloatArray:
        """Filter (zero-phase, along the first axis) and decimate an array with one row per sample.

        Parameters
        ----------
        x : array_like, shape (S, ...)
            One row per sample.

        Returns
        -------
        ndarray
        """
        a = real_array(x, "x")
        if a.ndim < 1 or a.shape[0] != self.samples:
            raise ShapeError(f"expected {self.samples} rows, got shape {a.shape}", value=a.shape)
        if not np.isfinite(a).all():
            raise NonFiniteError("x holds NaN or inf", value=a)
        if self.sos is not None:
            try:
                a = scipy.signal.sosfiltfilt(np.array(self.sos), a, axis=0)
            except ValueError as e:  # fewer samples than the filter's padding
                raise InvalidParameterError(
                    f"{self.samples} samples are too few for the filter sos "
                    f"({self.sos.shape[0]} sections): {e}; record more samples or use "
                    "a lower filter order",
                    value=self.samples,
                ) from None
        return a[self.trim : self.samples - self.trim : self.decimate]


def _uniform_step(t: FloatArray) -> float:
    dt = np.diff(t)
    if dt.size == 0 or not (dt > 0).all():
        raise InvalidParameterError("t must hold at least two strictly increasing sample times", value=t)
    step = float(np.median(dt))
    if np.abs(dt - step).max() > 1e-3 * step:
        raise InvalidParameterError(
            f"samples must be uniformly spaced (step {step:g} s, found steps from "
            f"{dt.min():g} to {dt.max():g} s); resample the log first",
            value=t,
        )
    return step


def prepare_data(
    t: ArrayLike,
    q: ArrayLike,
    tau: ArrayLike,
    *,
    cutoff: float,
    order: int = 4,
    decimate: int | None = None,
    trim: int | None = None,
) -> IdentificationData:
    """A log of joint positions and torques made ready for identification: q filtered and differentiated now;
    the filter, trimming and decimation recorded, to be applied to τ and to the regressor alike when the problem is
    built (parallel filtering, see the module).

    Parameters
    ----------
    t : array_like, shape (S,)
        Uniformly spaced sample times [s].
    q : array_like, shape (S, n)
        Joint positions [rad] (noisy encoders are fine).
    tau : array_like, shape (S, n)
        Joint torques [N·m] (raw; noise is fine).
    cutoff : float
        The low-pass corner f_c [Hz], above the motion's bandwidth (for a Fourier excitation, several times
        ``trajectory.bandwidth``) and below the noise.
    order : int, optional
        Of the Butterworth filter (run twice: gain |H(f)|², no phase).
    decimate : int, optional
        Keep every k-th sample (default: the largest k with f_s/k ≥ 4 f_c).
    trim : int, optional
        Samples dropped at each end (default: the longer of three periods of the cutoff frequency, ⌈3 f_s / f_c⌉,
        and the filter's start-up transient, :func:`settling_samples`, which grows with the order; a shorter one
        warns).

    Returns
    -------
    IdentificationData
    """
    tt = real_array(t, "t").reshape(-1)
    qq, tq = real_array(q, "q"), real_array(tau, "tau")
    if qq.ndim != 2 or tq.shape != qq.shape or tt.shape != (qq.shape[0],):
        raise ShapeError(
            f"t (S,), q (S, n) and tau (S, n) must have one row per sample; got t {tt.shape}, "
            f"q {qq.shape}, tau {tq.shape}",
            value=(tt.shape, qq.shape, tq.shape),
        )
    for name, a in (("t", tt), ("q", qq), ("tau", tq)):
        if not np.isfinite(a).all():
            raise NonFiniteError(f"{name} holds NaN or inf", value=a)
    dt = _uniform_step(tt)
    fs = 1.0 / dt
    fc = scalar(cutoff, "cutoff", positive=True)
    if fc >= 0.5 * fs:
        raise InvalidParameterError(
            f"cutoff {fc:g} Hz must be below the Nyquist frequency {0.5 * fs:g} Hz", value=cutoff
        )
    order = whole_number(order, "order", minimum=1)
    decimate = whole_number(decimate, "decimate", minimum=1) if decimate is not None else None
    trim = whole_number(trim, "trim") if trim is not None else None
    k = decimate if decimate is not None else max(1, int(fs / (4.0 * fc)))
    if k < 1 or fs / k < 2.0 * fc:
        raise InvalidParameterError(
            f"decimate={k} puts the new Nyquist frequency {0.5 * fs / max(k, 1):g} Hz "
            f"below the cutoff {fc:g} Hz (aliasing); use decimate <= {int(fs / (2 * fc))}",
            value=decimate,
        )
    sos = scipy.signal.butter(int(order), fc, fs=fs, output="sos")
    drop = int(trim) if trim is not None else max(math.ceil(3.0 * fs / fc), settling_samples(sos))
    if drop < 0 or qq.shape[0] - 2 * drop < 3 * k or qq.shape[0] <= 3 * 2 * (int(order) + 1):
        why = (
            ""
            if trim is not None
            else f" (the start-up transient of the order-{order} filter; lower orders are shorter)"
        )
        raise InvalidParameterError(
            f"{qq.shape[0]} samples are too few for trim={drop} at each end{why} and decimate={k}", value=trim
        )
    q_f = scipy.signal.sosfiltfilt(sos, qq, axis=0)
    qd = np.gradient(q_f, dt, axis=0)
    qdd = np.gradient(qd, dt, axis=0)
    _warn_transient(drop, sos, stacklevel=2)  # here, pointing at the caller (the data's own check is silenced)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentificationWarning)
        return IdentificationData(tt, q_f, qd, qdd, tq, sos, k, drop)
