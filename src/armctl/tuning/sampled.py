"""Sampled-data analysis of a PD loop on a double integrator with zero-order hold and measurement delay.

With an exact model, computed torque turns each joint into q̈ = v, and the digital loop is

    x_{k+1} = A x_k + B v_k,   A = [[1, T], [0, 1]],  B = [T²/2, T]   (ZOH of the double integrator)
    v_k = −k (K_p e_{k−d} + K_d ė_{k−d})                               (measurements d periods old)

The loop transfer function L(z) = (K_p, K_d)(zI − A)⁻¹B z^{−d} is built with python-control; its gain
margin is the critical multiplier k* of the gains (K_p, K_d) beyond which the loop is unstable.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armctl._checks import scalar
from armctl.errors import InvalidParameterError


def sampled_pd_loop(kp: float, kd: float, period: float, delay: int = 1):  # type: ignore[no-untyped-def]
    """The discrete loop transfer function L(z) (a ``control.TransferFunction`` with dt = period) of a PD
    (kp [1/s²], kd [1/s]) on a ZOH double integrator with ``delay`` periods of measurement delay."""
    import control

    t = scalar(period, "period", positive=True)
    if int(delay) != delay or delay < 0:
        raise InvalidParameterError(f"delay must be a whole number of periods >= 0, got {delay}", value=delay)
    plant = control.ss([[1.0, t], [0.0, 1.0]], [[t * t / 2], [t]], [[kp, kd]], [[0.0]], dt=t)
    loop = control.ss2tf(plant)
    if delay:
        z = control.TransferFunction([1, 0], [1], dt=t)
        loop = loop / z**int(delay)
    return loop


def spectral_radius(kp: float, kd: float, period: float, delay: int = 1) -> float:
    """Spectral radius of the closed loop x_{k+1} = A x_k − B K x_{k−d} (state augmented with d past states):
    below 1 means stable. The same loop as :func:`sampled_pd_loop`, evaluated directly with NumPy (cheap
    enough for bisections and maps)."""
    t = float(period)
    d = int(delay)
    size = 2 * (d + 1)
    big = np.zeros((size, size))
    big[:2, :2] = [[1.0, t], [0.0, 1.0]]
    big[:2, 2 * d: 2 * d + 2] -= np.array([[t * t / 2], [t]]) @ np.array([[kp, kd]])
    if d:
        big[2:, :-2] = np.eye(2 * d)
    return float(np.abs(np.linalg.eigvals(big)).max())


@dataclass(frozen=True)
class SampledDataAnalysis:
    """critical_multiplier: gain margin of the loop (k* scaling both gains); phase_margin [deg];
    crossover [rad/s]; closed-loop spectral radius at multiplier 1."""

    critical_multiplier: float
    phase_margin_deg: float
    crossover_rad_s: float
    spectral_radius: float

    @classmethod
    def of(cls, kp: float, kd: float, period: float, delay: int = 1) -> SampledDataAnalysis:
        import control

        loop = sampled_pd_loop(kp, kd, period, delay)
        # the double integrator's phase is −180° as ω → 0: that "crossing" is not a margin, so look above a
        # static band and take the smallest gain margin above 1 (gain can always be lowered: PD on a double
        # integrator has no lower margin)
        gms, pms, _sm, _wpc, wgcs, _wms = control.stability_margins(loop, returnall=True, epsw=1e-3 * np.pi / period)
        candidates = [float(g) for g in np.atleast_1d(gms) if g > 1.0]
        at_nyquist = complex(loop(-1.0))  # z = −1 (ω = π/T) is an end point of the frequency range
        if at_nyquist.real < 0 and abs(at_nyquist.imag) <= 1e-9 * abs(at_nyquist):
            candidates.append(-1.0 / at_nyquist.real)
        gm = min((g for g in candidates if g > 1.0), default=float("inf"))
        pm_all = np.atleast_1d(pms)
        k = int(np.argmin(pm_all)) if pm_all.size else 0
        pm = float(pm_all[k]) if pm_all.size else float("inf")
        wgc = float(np.atleast_1d(wgcs)[k]) if pm_all.size else float("nan")
        closed = control.feedback(loop, 1)
        radius = float(np.abs(control.poles(closed)).max())
        return cls(gm, pm, wgc, radius)
