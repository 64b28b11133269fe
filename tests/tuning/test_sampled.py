"""The sampled-data margins from python-control against independent references: the spectral radius of the
discretised closed loop (built here, bisected on the gain multiplier), Jury's test by hand, and the frequency
response evaluated here."""

from __future__ import annotations

import math

import numpy as np
import pytest

from armctl.errors import ArmctlError
from armctl.tuning import SampledDataAnalysis, closed_loop_poles, linearize, sampled_pd_loop, spectral_radius
from tests.helpers.arms import dynamics


def radius(kp: float, kd: float, period: float, delay: int) -> float:
    """Spectral radius of x_{k+1} = A x_k − B (kp, kd) x_{k−d}, ZOH double integrator, state augmented with
    the d past states."""
    t = period
    a = np.array([[1, t], [0, 1]])
    b = np.array([[t * t / 2], [t]])
    size = 2 * (delay + 1)
    big = np.zeros((size, size))
    big[:2, :2] = a
    big[:2, 2 * delay : 2 * delay + 2] -= b @ np.array([[kp, kd]])
    big[2:, :-2] = np.eye(2 * delay)
    return float(np.abs(np.linalg.eigvals(big)).max())


def bisect_boundary(kp: float, kd: float, period: float, delay: int) -> float:
    """The largest stable multiplier k (gains k·(kp, kd)) below which every grid multiplier down to 1e-4 is
    stable: bisection between the last stable and the first unstable point of a logarithmic grid; 0 if no grid
    point is stable."""
    grid = np.geomspace(1e-4, 1e4, 321)
    stable = [radius(k * kp, k * kd, period, delay) < 1 for k in grid]
    if not any(stable):
        return 0.0
    last = max(i for i, s in enumerate(stable) if s)
    assert all(stable[: last + 1]), "the stable multipliers of these loops form one interval from 0"
    lo, hi = float(grid[last]), float(grid[last + 1])
    for _ in range(80):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if radius(mid * kp, mid * kd, period, delay) < 1 else (lo, mid)
    return lo


def jury_boundary(kp: float, kd: float, period: float) -> float:
    """Without delay the closed loop is z² − tr z + det with tr = 2 − k(kp T²/2 + kd T), det = 1 − k(kd T − kp T²/2).
    Jury: 1 − tr + det = k kp T² > 0 always; 1 + tr + det = 4 − 2 k kd T > 0 ⇔ k < 2/(kd T); |det| < 1 ⇔
    kd > kp T/2 and k < 2/(kd T − kp T²/2), the weaker bound. So k* = 2/(kd T) if kd > kp T/2, else no k."""
    t = period
    return 2 / (kd * t) if kd > kp * t / 2 else 0.0


def phase_margin(kp: float, kd: float, period: float, delay: int) -> tuple[float, float]:
    """Smallest 180° + ∠L over the gain crossovers of L(e^{jωT}) = (kp, kd)(zI − A)⁻¹B z^{−d}, each found by
    bisection on ω between the points of a logarithmic grid where |L| − 1 changes sign."""
    t = period
    a = np.array([[1, t], [0, 1]])
    b = np.array([[t * t / 2], [t]])

    def loop(w: float) -> complex:
        z = np.exp(1j * w * t)
        return complex((np.array([[kp, kd]]) @ np.linalg.solve(z * np.eye(2) - a, b))[0, 0] * z ** (-delay))

    grid = np.geomspace(1e-3, math.pi / t, 20001)
    above = [abs(loop(w)) > 1 for w in grid]
    best = (math.inf, math.nan)
    for i in range(len(grid) - 1):
        if above[i] != above[i + 1]:
            lo, hi = grid[i], grid[i + 1]
            for _ in range(100):
                mid = (lo + hi) / 2
                lo, hi = (mid, hi) if (abs(loop(mid)) > 1) == above[i] else (lo, mid)
            pm = 180 + math.degrees(np.angle(loop(lo)))
            best = min(best, ((pm + 180) % 360 - 180, lo))
    return best


# the last: heavily overdamped (poles at −0.001 and −10 rad/s), where python-control's interpolating fallback failed
STABLE = [
    (400, 40, 1e-3, 1),
    (2500, 100, 1e-3, 1),
    (100, 20, 5e-3, 2),
    (900, 60, 2e-3, 0),
    (1.0, 2.0, 1e-3, 1),
    (0.01, 10.0, 1e-4, 0),
]
UNSTABLE = [(1e6, 2000, 1e-3, 1), (4e5, 1200, 1e-3, 1), (1e5, 400, 1e-3, 2), (4e5, 4000, 1e-3, 0), (1e5, 2500, 2e-3, 0)]
NEVER_STABLE = [(1e6, 1000, 1e-3, 1), (1e6, 1400, 1e-3, 1), (1e6, 400, 1e-3, 0), (400, 0.0, 1e-3, 0)]


@pytest.mark.parametrize(("kp", "kd", "period", "delay"), STABLE + UNSTABLE)
def test_critical_multiplier_is_the_stability_boundary(kp: float, kd: float, period: float, delay: int) -> None:
    got = SampledDataAnalysis.of(kp, kd, period, delay)
    expected = bisect_boundary(kp, kd, period, delay)
    assert got.critical_multiplier == pytest.approx(expected, rel=1e-6)
    assert (
        radius(kp * got.critical_multiplier * (1 - 1e-6), kd * got.critical_multiplier * (1 - 1e-6), period, delay) < 1
    )
    assert (
        radius(kp * got.critical_multiplier * (1 + 1e-6), kd * got.critical_multiplier * (1 + 1e-6), period, delay) > 1
    )
    if delay == 0:
        assert got.critical_multiplier == pytest.approx(jury_boundary(kp, kd, period), rel=1e-9)


@pytest.mark.parametrize(("kp", "kd", "period", "delay"), STABLE)
def test_stable_loop_reports_its_gain_and_phase_margins(kp: float, kd: float, period: float, delay: int) -> None:
    got = SampledDataAnalysis.of(kp, kd, period, delay)
    assert got.stable and got.spectral_radius < 1 and got.critical_multiplier > 1
    pm, wc = phase_margin(kp, kd, period, delay)
    assert got.phase_margin_deg == pytest.approx(pm, abs=1e-6)
    assert got.crossover_rad_s == pytest.approx(wc, rel=1e-8)
    assert got.phase_margin_deg > 0
    assert str(got).startswith("stable") and "unstable" not in got.summary()


def test_phase_margin_of_a_lightly_damped_loop() -> None:
    """ω_n = 20 rad/s, ζ = 0.025 at 10 kHz: the gain crossover (20 rad/s) lies below python-control's static band
    (10⁻³ of the Nyquist frequency), where the phase margin used to come out inf. For ωT ≪ 1 the loop is
    (K_p + jωK_d)/(−ω²) delayed by (d + ½)T (hold + measurement): |L| = 1 at ω² = (K_d² + √(K_d⁴ + 4K_p²))/2,
    phase margin atan(ωK_d/K_p) − ω(d + ½)T, here 2.81°."""
    kp, kd, period, delay = 400.0, 1.0, 1e-4, 0
    got = SampledDataAnalysis.of(kp, kd, period, delay)
    w = math.sqrt((kd**2 + math.sqrt(kd**4 + 4 * kp**2)) / 2)
    assert got.crossover_rad_s == pytest.approx(w, rel=1e-6)
    assert got.phase_margin_deg == pytest.approx(
        math.degrees(math.atan(w * kd / kp) - w * (delay + 0.5) * period), abs=1e-4
    )
    assert got.phase_margin_deg == pytest.approx(phase_margin(kp, kd, period, delay)[0], abs=1e-6)


@pytest.mark.parametrize(("kp", "kd", "period", "delay"), UNSTABLE)
def test_unstable_loop_reports_the_multiplier_that_stabilises_it(
    kp: float, kd: float, period: float, delay: int
) -> None:
    """The loop is unstable at the given gains: k* < 1 (not the inf of a loop "with no upper margin")."""
    assert radius(kp, kd, period, delay) > 1
    got = SampledDataAnalysis.of(kp, kd, period, delay)
    assert not got.stable and got.spectral_radius == pytest.approx(radius(kp, kd, period, delay), rel=1e-9)
    assert 0 < got.critical_multiplier < 1
    assert math.isnan(got.phase_margin_deg) and math.isnan(got.crossover_rad_s)
    assert str(got).startswith("unstable") and f"{got.critical_multiplier:.4g}" in got.summary()


@pytest.mark.parametrize(("kp", "kd", "period", "delay"), NEVER_STABLE)
def test_loop_no_scaling_stabilises_reports_zero(kp: float, kd: float, period: float, delay: int) -> None:
    """K_d/K_p below about (d + ½)T: unstable for every multiplier (checked on a grid here)."""
    assert all(radius(k * kp, k * kd, period, delay) > 1 for k in np.geomspace(1e-4, 1e4, 321))
    if delay == 0:
        assert jury_boundary(kp, kd, period) == 0.0
    got = SampledDataAnalysis.of(kp, kd, period, delay)
    assert not got.stable and got.critical_multiplier == 0.0
    assert got.summary().startswith("unstable") and "no scaling" in got.summary()


def test_large_margin_is_accurate() -> None:
    """A margin of ~10⁹ (tiny gains, fast loop): the loop's numerator is minute next to its denominator."""
    kp, period = 1e-3, 1e-3
    kd = kp * period / 2 * 1.1
    assert SampledDataAnalysis.of(kp, kd, period, 0).critical_multiplier == pytest.approx(
        jury_boundary(kp, kd, period), rel=1e-9
    )
    kp, kd, period, delay = 1.0, 1.0 * 1e-4 * 3.5 * 1.001, 1e-4, 3
    got = SampledDataAnalysis.of(kp, kd, period, delay).critical_multiplier
    k = got * (1 - 1e-6)
    assert radius(k * kp, k * kd, period, delay) < 1
    k = got * (1 + 1e-6)
    assert radius(k * kp, k * kd, period, delay) > 1


@pytest.mark.parametrize(("kp", "kd", "period", "delay"), [(400, 40, 1e-3, 1), (100, 20, 5e-3, 2), (900, 60, 2e-3, 0)])
def test_numpy_spectral_radius_matches_python_control(kp: float, kd: float, period: float, delay: int) -> None:
    for k in (0.5, 1.0, 3.0, 100.0):
        got = spectral_radius(k * kp, k * kd, period, delay)
        assert got == pytest.approx(SampledDataAnalysis.of(k * kp, k * kd, period, delay).spectral_radius, rel=1e-9)
        assert got == pytest.approx(radius(k * kp, k * kd, period, delay), rel=1e-12)


BAD_INPUTS = {
    "analysis kp < 0": (lambda: SampledDataAnalysis.of(-1.0, 1.0, 1e-3), "-1.0"),
    "analysis kd < 0": (lambda: SampledDataAnalysis.of(1.0, -2.0, 1e-3), "-2.0"),
    "analysis kd nan": (lambda: SampledDataAnalysis.of(1.0, float("nan"), 1e-3), "nan"),
    "analysis period 0": (lambda: SampledDataAnalysis.of(1.0, 1.0, 0.0), "0.0"),
    "analysis delay 1.5": (lambda: SampledDataAnalysis.of(1.0, 1.0, 1e-3, 1.5), "1.5"),
    "analysis delay str": (lambda: SampledDataAnalysis.of(1.0, 1.0, 1e-3, "one"), "'one'"),
    "radius kp inf": (lambda: spectral_radius(float("inf"), 1.0, 1e-3), "inf"),
    "radius period < 0": (lambda: spectral_radius(1.0, 1.0, -1e-3), "-0.001"),
    "radius delay < 0": (lambda: spectral_radius(1.0, 1.0, 1e-3, -1), "-1"),
    "loop delay nan": (lambda: sampled_pd_loop(1.0, 1.0, 1e-3, float("nan")), "nan"),
    "poles kp nan": (lambda: closed_loop_poles(float("nan"), 1.0), "nan"),
    "linearize step 0": (lambda: linearize(dynamics("pendulum"), [0.3], step=0.0), "0.0"),
}


@pytest.mark.parametrize("case", BAD_INPUTS)
def test_bad_input_raises_armctl_error_naming_the_value(case: str) -> None:
    call, named = BAD_INPUTS[case]
    with pytest.raises(ArmctlError, match=named.replace(".", r"\.")):
        call()


@pytest.mark.parametrize("delay", [0, 1, 3])
def test_delayed_loop_matrix_poles_are_the_roots_of_the_delayed_characteristic_polynomial(delay: int) -> None:
    """x_{k+1} = a x_k + f x_{k−d} (one state): its poles are the roots of z^{d+1} − a z^d − f."""
    from armctl.tuning.sampled import delayed_loop_matrix

    a, f = 0.9, -0.35
    poles = np.linalg.eigvals(delayed_loop_matrix(np.array([[a]]), np.array([[f]]), delay))
    roots = np.roots([1.0, -a, *([0.0] * (delay - 1)), -f] if delay else [1.0, -(a + f)])
    np.testing.assert_allclose(np.sort_complex(poles), np.sort_complex(roots), atol=1e-12)


def test_delayed_loop_matrix_without_delay_is_the_plant_plus_the_feedback() -> None:
    from armctl.tuning.sampled import delayed_loop_matrix

    a = np.array([[1.0, 0.1], [0.0, 1.0]])
    f = np.array([[-0.2, -0.05], [0.3, -0.4]])
    np.testing.assert_array_equal(delayed_loop_matrix(a, f, 0), a + f)
