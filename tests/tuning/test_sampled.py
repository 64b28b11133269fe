"""The sampled-data margin from python-control against an independent eigenvalue bisection."""

from __future__ import annotations

import numpy as np
import pytest

from armctl.tuning import SampledDataAnalysis, spectral_radius


def bisect_critical(kp: float, kd: float, period: float, delay: int) -> float:
    """Largest k for which the delayed ZOH double-integrator loop's augmented state matrix is Schur."""
    t = period
    a = np.array([[1, t], [0, 1]])
    b = np.array([[t * t / 2], [t]])

    def radius(k: float) -> float:
        size = 2 * (delay + 1)
        big = np.zeros((size, size))
        big[:2, :2] = a
        big[:2, 2 * delay: 2 * delay + 2] -= b @ (k * np.array([[kp, kd]]))
        big[2:, :-2] = np.eye(2 * delay)
        return float(np.abs(np.linalg.eigvals(big)).max())

    lo, hi = 1e-3, 1e5
    for _ in range(80):
        mid = (lo * hi) ** 0.5
        lo, hi = (mid, hi) if radius(mid) < 1 else (lo, mid)
    return lo


@pytest.mark.parametrize(("kp", "kd", "period", "delay"), [(400, 40, 1e-3, 1), (2500, 100, 1e-3, 1),
                                                          (100, 20, 5e-3, 2), (900, 60, 2e-3, 0)])
def test_gain_margin_is_the_critical_multiplier(kp: float, kd: float, period: float, delay: int) -> None:
    got = SampledDataAnalysis.of(kp, kd, period, delay)
    assert got.critical_multiplier == pytest.approx(bisect_critical(kp, kd, period, delay), rel=1e-6)
    assert got.spectral_radius < 1.0


@pytest.mark.parametrize(("kp", "kd", "period", "delay"), [(400, 40, 1e-3, 1), (100, 20, 5e-3, 2), (900, 60, 2e-3, 0)])
def test_numpy_spectral_radius_matches_python_control(kp: float, kd: float, period: float, delay: int) -> None:
    for k in (0.5, 1.0, 3.0):
        got = spectral_radius(k * kp, k * kd, period, delay)
        assert got == pytest.approx(SampledDataAnalysis.of(k * kp, k * kd, period, delay).spectral_radius, rel=1e-9)
