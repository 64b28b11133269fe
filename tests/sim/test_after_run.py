"""The checks made after a run with contact (armctl.sim.after_run), against closed forms.

A slider (one prismatic joint along x, a point mass m) resting inside a floor of stiffness k at a fixed depth
δ₀ feels a constant normal force f_n = k δ₀ and, below the slip velocity, a tangential friction −(μ f_n / v_slip) v:
pushed by τ < μ f_n it creeps at v = τ v_slip / (μ f_n) with the friction at −τ. The velocity's decay rate is
a = μ f_n / (m v_slip); RK4 keeps it stable only for a h ≤ 2.785 (where R(−z) = 1 − z + z²/2 − z³/6 + z⁴/24
returns to 1)."""

from __future__ import annotations

import functools
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


@pytest.mark.parametrize("split", ["points", "planes"])
def test_points_sticking_together_add_their_damping(split: str) -> None:
    # the same slider held by two contact points (one plane with two, or two planes with one each): each point
    # alone decays at a = 2.5e4 1/s (a h = 2.5 at 0.1 ms, inside RK4's 2.785), together at 5e4 (a h = 5): the
    # slider then creeps at 1.55e-3 m/s against the exact 1e-4, and the check must see the sum
    from armctl.sim.contact import ContactPoint

    def floor(points: object = None) -> Plane:
        return Plane(KelvinVoigt(K), normal=(0.0, 0.0, 1.0), point=(0.0, 0.0, DEPTH), friction=MU,
                     slip_velocity=SLIP, points=points)  # type: ignore[arg-type]

    envs = ([floor([ContactPoint(), ContactPoint(offset=(0.0, 0.01, 0.0))])] if split == "points"
            else [floor(), floor()])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = simulate(slider(MASS), OpenLoop(lambda t: np.array([PUSH])), armctl.Reference.hold([0.0]), 0.05,
                       environment=envs, dt=1e-4, energy=False)
    (item,) = res.info["unstable_friction"]
    assert item["rate_dt"] == pytest.approx(2.0 * RATE * 1e-4, rel=1e-6) and len(item["points"]) == 2
    assert item["normal_force"] == pytest.approx(2.0 * FN)
    assert any("decay rate × dt = 5" in str(w.message) for w in caught)
    assert abs(res.qd[-1, 0]) > 10.0 * PUSH * SLIP / (MU * 2.0 * FN)  # the creep is off by over ten times


def test_a_point_sliding_fast_is_not_judged_by_the_law_below_its_slip_velocity() -> None:
    # the slider pushed at μ f_n + 4 N from 0.2 m/s never slows below v_slip = 1 mm/s: its friction is μ f_n
    # throughout (a h is beyond the limit only for the viscous law it never meets), v(t) = 0.2 + 2 t exactly
    floor = Plane(KelvinVoigt(K), normal=(0.0, 0.0, 1.0), point=(0.0, 0.0, DEPTH), friction=MU, slip_velocity=SLIP)
    with warnings.catch_warnings():
        warnings.simplefilter("error", SimulationWarning)
        res = simulate(slider(MASS), OpenLoop(lambda t: np.array([MU * FN + 4.0])), armctl.Reference.hold([0.0]),
                       0.5, environment=floor, qd0=[0.2])
    np.testing.assert_allclose(res.qd[:, 0], 0.2 + 4.0 / MASS * res.t, rtol=1e-12)
    assert "unstable_friction" not in res.info


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


def _swing(k: float, integrator: str, dt: float | None = None
           ) -> tuple[armctl.sim.SimResult, list[warnings.WarningMessage]]:
    """The pendulum swung at 3 rad/s into an undamped Hunt–Crossley wall (stiffness k, exponent 1.5), 2 s."""
    dyn = armctl.Dynamics(armctl.models.pendulum())
    wall = Plane(HuntCrossley(k, 0.0, 1.5), normal=(-1.0, 0.0, 0.0), point=(0.2, 0.0, 0.0))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = simulate(dyn, OpenLoop(lambda t: np.zeros(1)), armctl.Reference([0.0]), 2.0, qd0=[3.0],
                       environment=wall, integrator=integrator, friction="smooth", dt=dt)
    return res, [w for w in caught if issubclass(w.category, SimulationWarning)]


@pytest.mark.parametrize("integrator", ["semi-implicit-euler", "euler"])
def test_first_order_schemes_gaining_energy_on_a_stiffening_wall_are_reported(integrator: str) -> None:
    # k = 1e8: implicit Euler, L-stable, bounces off with less energy (friction and the wall only take);
    # the explicit first-order schemes at 1 ms gain energy there and book it as the wall's work or leave it
    # in the balance. Before, semi-implicit Euler booked the wall's work as a left sum (the wall "did" +11 J,
    # the balance closed, no warning)
    good, warned = _swing(1e8, "implicit-euler")
    assert warned == [] and good.energy[-1] < good.energy[0] - 0.5
    bad, warned = _swing(1e8, integrator)
    assert bad.energy.max() > bad.energy[0] + 0.5  # the scheme made energy …
    assert any("no force supplied" in str(w.message) or "a compliant surface only gives back" in str(w.message)
               for w in warned)  # … and says so
    assert max(bad.info["energy_gain"] if integrator == "semi-implicit-euler" else 0.0,
               bad.info["environment_work"]) > 0.5


@functools.cache
def _fine_swing() -> armctl.sim.SimResult:
    return _swing(1e6, "rk4", 1e-4)[0]


@pytest.mark.parametrize("integrator", ["semi-implicit-euler", "euler", "rk4"])
def test_a_stable_stiffening_wall_is_not_reported(integrator: str) -> None:
    # k = 1e6: at 1 ms every scheme follows RK4 at 1e-4 s to 1e-3 rad; the first-order schemes' energy error
    # while the wall is compressed (O(h), halving with the step) is no gain, and none is reported. Euler's work
    # was booked at the step's start velocity, which drifted by h ∫|F|²/m dt and read as a 54 % gain
    fine = _fine_swing()
    res, warned = _swing(1e6, integrator)
    assert warned == []
    assert np.abs(res.q - fine.q).max() < 1e-3
