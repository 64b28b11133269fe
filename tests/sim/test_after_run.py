"""The checks made after a run with contact (armctl.sim.after_run), against closed forms.

A slider (one prismatic joint along x, a point mass m) resting inside a floor of stiffness k at a fixed depth
δ₀ feels a constant normal force f_n = k δ₀ and, below the slip velocity, a tangential friction −(μ f_n / v_slip) v:
pushed by τ < μ f_n it creeps at v = τ v_slip / (μ f_n) with the friction at −τ. The velocity's decay rate is
a = μ f_n / (m v_slip); RK4 keeps it stable only for a h ≤ 2.785 (where R(−z) = 1 − z + z²/2 − z³/6 + z⁴/24
returns to 1)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.optimize import brentq

import armctl
from armctl.errors import SimulationWarning
from armctl.sim import HuntCrossley, KelvinVoigt, Plane, simulate
from tests.sim.helpers import OpenLoop, slider

MASS, K, DEPTH, MU, SLIP, PUSH = 2.0, 1e4, 0.01, 0.5, 1e-3, 10.0
FN = K * DEPTH  # 100 N
RATE = MU * FN / (MASS * SLIP)  # 2.5e4 1/s


def _creep(dt: float, integrator: str = "rk4") -> tuple[armctl.sim.SimResult, list[warnings.WarningMessage]]:
    floor = Plane(KelvinVoigt(K), normal=(0.0, 0.0, 1.0), point=(0.0, 0.0, DEPTH), friction=MU, slip_velocity=SLIP)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = simulate(slider(MASS), OpenLoop(lambda t: np.array([PUSH])), armctl.Reference.hold([0.0]), 0.05,
                       environment=floor, integrator=integrator, dt=dt)
    return res, [w for w in caught if issubclass(w.category, SimulationWarning)]


def test_rk4_limit_on_the_real_axis() -> None:
    from armctl.sim.after_run import DAMPING_LIMIT

    z = brentq(lambda z: (1 - z + z**2 / 2 - z**3 / 6 + z**4 / 24) - 1.0, 2.0, 3.0)
    assert DAMPING_LIMIT["rk4"] == pytest.approx(z, abs=1e-3)


def test_friction_too_stiff_for_the_step_is_reported_and_chatters() -> None:
    res, warned = _creep(1e-3)
    assert not res.diverged
    (item,) = res.info["unstable_friction"]
    assert item["normal_force"] == pytest.approx(FN, rel=1e-9)
    assert item["rate_dt"] == pytest.approx(RATE * 1e-3, rel=1e-6)  # 25
    assert item["max_dt"] == pytest.approx(2.785 / RATE, rel=1e-6)
    texts = sorted(str(w.message) for w in warned)  # the friction, and the energy its chatter made
    assert len(texts) == 2 and "slip_velocity >=" in texts[0] and "no force supplied" in texts[1]
    ft = -res.contact_force[10:, 0, 0]  # the friction on the slider: −10 N in the exact creep; here it swings
    assert np.abs(ft + PUSH).mean() > PUSH and ft.max() > 0.0 and ft.min() == pytest.approx(-MU * FN)  # ±μ f_n


@pytest.mark.parametrize(("dt", "integrator"), [(1e-4, "rk4"), (1e-3, "semi-implicit-euler")])
def test_below_the_limit_or_implicit_the_slider_creeps_as_the_closed_form(dt: float, integrator: str) -> None:
    res, warned = _creep(dt, integrator)  # RK4 at 1e-4: a h = 2.5 < 2.785
    assert warned == [] and "unstable_friction" not in res.info
    ft = -res.contact_force[-20:, 0, 0]
    np.testing.assert_allclose(ft, -PUSH, rtol=1e-3)
    np.testing.assert_allclose(res.qd[-20:, 0], PUSH * SLIP / (MU * FN), rtol=1e-3)


def test_semi_implicit_euler_books_a_spring_wall_work_exactly() -> None:
    # a slider pushed by 10 N into an undamped wall (ω h = 0.3, where the scheme is stable) bounces on it for
    # ~50 periods: the arm's energy plus the wall's spring energy is conserved up to the scheme's bounded
    # error, so E − E₀ − W must not drift. The left sum h v̄ᵀτ_e(q) booked k Δq²/2 too much a step: a drift of
    # ~ω h × 2π times the oscillation energy per period
    mass, k = 2.0, 2.0 * (0.3 / 1e-3) ** 2
    wall = Plane(KelvinVoigt(k), normal=(-1.0, 0.0, 0.0), point=(0.0, 0.0, 0.0))
    res = simulate(slider(mass), OpenLoop(lambda t: np.array([PUSH])), armctl.Reference.hold([0.0]), 1.0,
                   environment=wall, integrator="semi-implicit-euler")
    balance = res.energy_balance()
    stored = 0.5 * k * (2.0 * PUSH / k) ** 2  # the spring at the deepest point of the exact bounce
    assert np.abs(balance).max() < 0.2 * stored
    half = len(balance) // 2
    assert abs(balance[half:].mean() - balance[:half].mean()) < 0.02 * stored  # no trend


def test_semi_implicit_euler_gaining_energy_on_a_stiffening_wall_is_reported() -> None:
    # the pendulum swung at 3 rad/s into a Hunt–Crossley wall (k = 1e8, exponent 1.5, no damping) that only
    # gives back what it stored: implicit Euler, L-stable, bounces off with less energy; semi-implicit Euler at
    # 1 ms gains energy there — which its contact work, booked as a left sum, used to hide (the wall "did"
    # +11 J and the balance closed, no warning)
    dyn = armctl.Dynamics(armctl.models.pendulum())

    def run(integrator: str) -> tuple[armctl.sim.SimResult, list[warnings.WarningMessage]]:
        wall = Plane(HuntCrossley(1e8, 0.0, 1.5), normal=(-1.0, 0.0, 0.0), point=(0.2, 0.0, 0.0))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res = simulate(dyn, OpenLoop(lambda t: np.zeros(1)), armctl.Reference([0.0]), 2.0, qd0=[3.0],
                           environment=wall, integrator=integrator, friction="smooth")
        return res, [w for w in caught if issubclass(w.category, SimulationWarning)]

    good, warned = run("implicit-euler")
    assert warned == [] and good.energy[-1] < good.energy[0] - 0.5  # friction and the wall only take
    bad, warned = run("semi-implicit-euler")
    assert bad.energy.max() > bad.energy[0] + 0.5  # the scheme made energy …
    assert any("no force supplied" in str(w.message) for w in warned)  # … and says so
    assert bad.info["energy_gain"] > 0.5
    assert math.isfinite(bad.info["energy_gain"])
