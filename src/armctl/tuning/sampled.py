"""Sampled-data analysis of a PD loop on a double integrator with zero-order hold and measurement delay.

With an exact model, computed torque turns each joint into q̈ = v, and the digital loop is

    x_{k+1} = A x_k + B v_k,   A = [[1, T], [0, 1]],  B = [T²/2, T]   (ZOH of the double integrator)
    v_k = −k (K_p e_{k−d} + K_d ė_{k−d})                               (measurements d periods old)

The loop transfer function L(z) = (K_p, K_d)(zI − A)⁻¹B z^{−d} is built with python-control; its gain
margin is the critical multiplier k* of the gains (K_p, K_d) beyond which the loop is unstable.

The multipliers k at which a closed-loop pole crosses the unit circle are the gains −1/L(e^{jω}) at the phase
crossovers (python-control's gain margins, all of them, plus the Nyquist frequency z = −1); between two such
crossings the number of unstable poles is constant, so the stable range of k is read off by evaluating the closed
loop once inside each interval. A loop that is already unstable at k = 1 reports the k* < 1 below which the gains
must be scaled to stabilise it (or 0 when no scaling does: the derivative gain is too small for the delay).
"""

from __future__ import annotations

import itertools
import math
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from armctl._checks import scalar, whole_number
from armctl.errors import InvalidParameterError


def _delay(delay: Any) -> int:
    return whole_number(delay, "delay (in periods)")


def _loop(kp: Any, kd: Any, period: Any, delay: Any) -> tuple[float, float, float, int]:
    """The loop's K_p, K_d, period T and delay d, checked (named errors)."""
    return scalar(kp, "kp"), scalar(kd, "kd"), scalar(period, "period", positive=True), _delay(delay)


def sampled_pd_loop(kp: float, kd: float, period: float, delay: int = 1) -> Any:
    """The discrete loop transfer function L(z) of a PD on a zero-order-hold double integrator with a
    measurement delay.

    Parameters
    ----------
    kp, kd : float
        As for :func:`~armctl.tuning.closed_loop_poles`: the PD's gains on the double integrator.
    period : float
        The control period T [s], > 0.
    delay : int, optional
        Periods of measurement delay, ≥ 0.

    Returns
    -------
    control.TransferFunction
        L(z), with dt = period.
    """
    import control

    kp, kd, t, d = _loop(kp, kd, period, delay)
    plant = control.ss([[1.0, t], [0.0, 1.0]], [[t * t / 2], [t]], [[kp, kd]], [[0.0]], dt=t)
    loop = control.ss2tf(plant)
    if d:
        z = control.TransferFunction([1, 0], [1], dt=t)
        loop = loop / z**d
    return loop


def spectral_radius(kp: float, kd: float, period: float, delay: int = 1) -> float:
    """Spectral radius of the closed loop x_{k+1} = A x_k − B K x_{k−d} (state augmented with d past
    states): below 1 means stable. The same loop as :func:`sampled_pd_loop`, evaluated directly with NumPy (cheap
    enough for bisections and maps).

    Parameters
    ----------
    kp, kd, period, delay
        As for :func:`sampled_pd_loop`.

    Returns
    -------
    float
    """
    kp, kd, t, d = _loop(kp, kd, period, delay)
    big = delayed_loop_matrix(np.array([[1.0, t], [0.0, 1.0]]), -np.array([[t * t / 2], [t]]) @ np.array([[kp, kd]]), d)
    try:
        if not np.isfinite(big).all():
            raise np.linalg.LinAlgError
        return float(np.abs(np.linalg.eigvals(big)).max())
    except np.linalg.LinAlgError:
        raise _beyond_analysis(kp, kd, t) from None


def delayed_loop_matrix(a: np.ndarray, feedback: np.ndarray, delay: int) -> np.ndarray:
    """The transition matrix of a sampled loop whose feedback acts on the state measured ``delay`` periods ago,

        x_{k+1} = A x_k + F x_{k−d},

    on the state augmented with the d past samples, z_k = (x_k, x_{k−1}, …, x_{k−d}): the first block row is
    [A, 0, …, 0, F] (A + F for d = 0), and each other block row shifts a sample one period back.

    Parameters
    ----------
    a : ndarray, shape (m, m)
        A, the sampled plant (zero-order hold).
    feedback : ndarray, shape (m, m)
        F = B_d G: the feedback gain G on the delayed state through the plant's input matrix B_d.
    delay : int
        d ≥ 0 [periods], checked by the caller.

    Returns
    -------
    ndarray, shape (m(d+1), m(d+1))
    """
    m = a.shape[0]
    size = m * (delay + 1)
    big = np.zeros((size, size))
    big[:m, :m] = a
    big[:m, m * delay :] += feedback
    if delay:
        big[m:, :-m] = np.eye(m * delay)
    return big


def _beyond_analysis(kp: float, kd: float, t: float) -> InvalidParameterError:
    return InvalidParameterError(
        f"the sampled loop cannot be analysed in floating point: K_p T² = {kp * t * t:g}, "
        f"K_d T = {kd * t:g} (period T = {t:g} s); stable loops have K_p T² < 4 and "
        "K_d T < 2",
        value=(kp, kd, t),
    )


def _frequency_response(kp: float, kd: float, period: float, delay: int, w: Any) -> Any:
    """L(e^{jωT}) = (K_p, K_d)(zI − A)⁻¹B z^{−d} written out, with z − 1 = expm1(jωT): no cancellation as ω → 0,
    where evaluating the polynomials of the transfer function loses (ωT)² of the digits."""
    zm1 = np.expm1(1j * np.asarray(w, dtype=float) * period)
    t2 = period * period
    return (kp * (t2 / 2 * zm1 + t2) / zm1**2 + kd * period / zm1) * (zm1 + 1.0) ** (-delay)


def _gain_crossings(kp: float, kd: float, period: float, delay: int) -> list[float]:
    """Every multiplier k > 0 at which a closed-loop pole of the loop with gains k (kp, kd) can be on the unit
    circle: −1/L(z) at the phase crossovers z = e^{jωT} (python-control's gain margins) and at z = −1."""
    import control

    loop = sampled_pd_loop(kp, kd, period, delay)
    # the double integrator's phase is −180° as ω → 0: that "crossing" (k = 0) is not a margin, so look above a
    # static band. The polynomial method finds every crossing on the unit circle; its fallback (an interpolated
    # frequency response, taken when python-control fears round-off) can invent or miss some, or fail outright.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        warnings.simplefilter("ignore", RuntimeWarning)  # from the stability-margin (sm) search, unused here
        gms = control.stability_margins(loop, returnall=True, method="poly", epsw=1e-3 * np.pi / period)[0]
    crossings = [float(g) for g in np.atleast_1d(gms) if 0.0 < g < math.inf]
    at_nyquist = complex(loop(-1.0))  # z = −1 (ω = π/T) is an end point of the frequency range
    if at_nyquist.real < 0 and abs(at_nyquist.imag) <= 1e-9 * abs(at_nyquist):
        crossings.append(-1.0 / at_nyquist.real)
    return crossings


def _stable_ranges(
    kp: float, kd: float, period: float, delay: int, crossings: list[float]
) -> list[tuple[float, float]]:
    """The open intervals of multipliers k > 0 for which the loop with gains k (kp, kd) is stable, given every k
    at which a closed-loop pole can cross the unit circle: between two crossings the number of unstable poles is
    constant, so one evaluation of the closed loop inside each interval classifies it (stable neighbours merged)."""
    edges = [0.0, *sorted(set(crossings)), math.inf]
    ranges: list[tuple[float, float]] = []
    for lo, hi in itertools.pairwise(edges):
        if lo == 0.0 and hi == math.inf:
            probe = 1.0
        elif lo == 0.0:
            probe = hi / 2
        elif hi == math.inf:
            probe = 2 * lo
        else:
            probe = math.sqrt(lo * hi)
        if spectral_radius(probe * kp, probe * kd, period, delay) < 1.0:
            if ranges and ranges[-1][1] == lo:
                ranges[-1] = (ranges[-1][0], hi)
            else:
                ranges.append((lo, hi))
    return ranges


def _phase_margin(kp: float, kd: float, period: float, delay: int) -> tuple[float, float]:
    """(smallest phase margin [deg], its gain crossover [rad/s]) from every ω in (0, π/T] with |L(e^{jωT})| = 1.

    python-control's polynomial method misplaces or misses gain crossovers far below the Nyquist frequency (the
    roots cluster at z = 1) and drops those below its static band, so they are bracketed on a logarithmic grid of
    the frequency response and refined with Brent's method. Below ω₀ = 10⁻³ min(√K_p, π/T), |L| ≥ K_p/ω² ≫ 1."""
    from scipy.optimize import brentq

    w_top = math.pi / period
    w_low = 1e-3 * min(math.sqrt(kp), w_top)
    n = max(2001, int(200 * math.log10(w_top / w_low)) + 1)
    w = np.geomspace(w_low, w_top, n)
    w[-1] = w_top

    def log_gain(x: float) -> float:
        return float(np.log(np.abs(_frequency_response(kp, kd, period, delay, x))))

    side = np.sign(np.log(np.abs(_frequency_response(kp, kd, period, delay, w))))
    best = (math.inf, math.nan)
    for i in np.flatnonzero(side[:-1] != side[1:]):
        wc = (
            float(w[i + 1])
            if side[i + 1] == 0
            else float(brentq(log_gain, w[i], w[i + 1], xtol=1e-14 * w[i], rtol=4 * np.finfo(float).eps))
        )
        pm = math.degrees(float(np.angle(-_frequency_response(kp, kd, period, delay, wc))))
        best = min(best, (pm, wc))
    return best


@dataclass(frozen=True)
class SampledDataAnalysis:
    """Margins of the sampled PD loop (see the module docstring) at gains (K_p, K_d), i.e. multiplier k = 1.

    Attributes
    ----------
    critical_multiplier : float
        The factor k* on both gains at the stability boundary. For a stable loop it is the gain margin: the loop
        stays stable when both gains are scaled by up to k* > 1 (inf if by any factor). For an unstable loop it is
        < 1: the gains must be scaled below k* to stabilise the loop; 0 when scaling them down does not stabilise it
        (K_d/K_p too small for the delay and the hold). ``critical_multiplier > 1`` exactly when :attr:`stable`;
        :meth:`summary` says which.
    phase_margin_deg : float
        The smallest phase margin [deg]; nan for an unstable loop (a phase margin is a margin of a stable loop).
    crossover_rad_s : float
        The gain crossover frequency it is measured at [rad/s]; nan for an unstable loop.
    spectral_radius : float
        Of the closed loop at multiplier 1; below 1 exactly when :attr:`stable`.
    """

    critical_multiplier: float
    phase_margin_deg: float
    crossover_rad_s: float
    spectral_radius: float

    @property
    def stable(self) -> bool:
        """Whether the closed loop at the given gains is (asymptotically) stable: spectral radius below 1."""
        return self.spectral_radius < 1.0

    def summary(self) -> str:
        """One line for logs and tuning records, saying "unstable" for an unstable loop.

        Returns
        -------
        str
        """
        gap = self.spectral_radius - 1.0
        radius = f"1 {'+' if gap > 0 else '-'} {abs(gap):.2g}" if 0 < abs(gap) < 1e-4 else f"{self.spectral_radius:.6g}"
        if self.stable:
            return (
                f"stable (spectral radius {radius}): gain margin {self.critical_multiplier:.4g}, "
                f"phase margin {self.phase_margin_deg:.3g}° at {self.crossover_rad_s:.4g} rad/s"
            )
        if self.critical_multiplier > 0:
            fix = f"scale both gains below {self.critical_multiplier:.4g} to stabilise it"
        else:
            fix = "no scaling of the gains stabilises it (K_d/K_p too small for the delay and the hold)"
        return f"unstable (spectral radius {radius}): {fix}"

    def __str__(self) -> str:
        return self.summary()

    @classmethod
    def of(cls, kp: float, kd: float, period: float, delay: int = 1) -> SampledDataAnalysis:
        """Analyse the loop at gains (K_p, K_d).

        Parameters
        ----------
        kp, kd, period, delay
            As for :func:`sampled_pd_loop`, with K_p > 0 and K_d ≥ 0.

        Returns
        -------
        SampledDataAnalysis
        """
        import control

        kp = scalar(kp, "kp", positive=True)
        kd = scalar(kd, "kd", nonnegative=True)
        t = scalar(period, "period", positive=True)
        d = _delay(delay)
        try:
            radius = float(np.abs(control.poles(control.feedback(sampled_pd_loop(kp, kd, t, d), 1))).max())
        except (np.linalg.LinAlgError, ValueError):
            raise _beyond_analysis(kp, kd, t) from None
        if not math.isfinite(radius):
            raise _beyond_analysis(kp, kd, t)
        stable = radius < 1.0
        # the stable range of multipliers that contains 1 (stable loop) or lies highest below 1 (unstable loop)
        below = [r for r in _stable_ranges(kp, kd, t, d, _gain_crossings(kp, kd, t, d)) if r[0] <= 1.0]
        gm = below[-1][1] if below else 0.0
        if 0.0 < gm < math.inf:
            # polish: a large margin leaves the loop's numerator tiny next to its denominator, which costs the
            # polynomial method digits; at gains scaled to the boundary the margin is near 1 and well conditioned
            again = _gain_crossings(gm * kp, gm * kd, t, d)
            nearest = min(again, key=lambda c: abs(math.log(c)), default=math.inf)
            if abs(math.log(nearest)) < 0.1:
                gm *= nearest
        # k = 1 on the boundary itself: let round-off not contradict the spectral radius
        gm = max(gm, 1.0) if stable else min(gm, 1.0)
        pm, wgc = _phase_margin(kp, kd, t, d) if stable else (math.nan, math.nan)
        return cls(gm, pm, wgc, radius)
