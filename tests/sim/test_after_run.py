"""The checks made after a run with contact (armctl.sim.after_run), against closed forms.

A slider (one prismatic joint along x, a point mass m) resting inside a floor of stiffness k at a fixed depth
δ₀ feels a constant normal force f_n = k δ₀ and, below the slip velocity, a tangential friction −(μ f_n / v_slip) v:
pushed by τ < μ f_n it creeps at v = τ v_slip / (μ f_n) with the friction at −τ. The velocity's decay rate is
a = μ f_n / (m v_slip); RK4 keeps it stable only for a h ≤ 2.785 (where R(−z) = 1 − z + z²/2 − z³/6 + z⁴/24
returns to 1)."""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np
import pytest
from scipy.optimize import brentq

import armctl
from armctl.errors import SimulationWarning
from armctl.sim import Forces, HuntCrossley, KelvinVoigt, Plane, simulate
from tests.sim.helpers import OpenLoop, slider

MASS, K, DEPTH, MU, SLIP, PUSH = 2.0, 1e4, 0.01, 0.5, 1e-3, 10.0
FN = K * DEPTH  # 100 N
RATE = MU * FN / (MASS * SLIP)  # 2.5e4 1/s


def _creep(dt: float, integrator: str = "rk4") -> tuple[armctl.sim.SimResult, list[warnings.WarningMessage]]:
    floor = Plane(KelvinVoigt(K), normal=(0.0, 0.0, 1.0), point=(0.0, 0.0, DEPTH), friction=MU, slip_velocity=SLIP)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = simulate(
            slider(MASS),
            OpenLoop(lambda t: np.array([PUSH])),
            armctl.Reference.hold([0.0]),
            0.05,
            integrator=integrator,
            dt=dt,
            forces=Forces(environment=floor),
        )
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
    # the slip velocity at which the same step would pass: μ f_n h / (m v) = 2.785
    assert item["min_slip_velocity"] == pytest.approx(MU * FN * 1e-3 / (MASS * 2.785), rel=1e-6)
    texts = sorted(str(w.message) for w in warned)  # the friction, and the energy its chatter made
    assert len(texts) == 2 and "slip_velocity >=" in texts[0] and "no force supplied" in texts[1]
    ft = res.contact_force_on_robot[10:, 0, 0]  # the friction on the slider: −10 N in the exact creep; here it swings
    assert np.abs(ft + PUSH).mean() > PUSH and ft.max() > 0.0 and ft.min() == pytest.approx(-MU * FN)  # ±μ f_n


@pytest.mark.parametrize("split", ["points", "planes"])
def test_points_sticking_together_add_their_damping(split: str) -> None:
    # the same slider held by two contact points (one plane with two, or two planes with one each): each point
    # alone decays at a = 2.5e4 1/s (a h = 2.5 at 0.1 ms, inside RK4's 2.785), together at 5e4 (a h = 5): the
    # slider then creeps at 1.55e-3 m/s against the exact 1e-4, and the check must see the sum
    from armctl.sim.contact import ContactPoint

    def floor(points: object = None) -> Plane:
        return Plane(
            KelvinVoigt(K),
            normal=(0.0, 0.0, 1.0),
            point=(0.0, 0.0, DEPTH),
            friction=MU,
            slip_velocity=SLIP,
            points=points,
        )  # type: ignore[arg-type]

    envs = [floor([ContactPoint(), ContactPoint(offset=(0.0, 0.01, 0.0))])] if split == "points" else [floor(), floor()]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = simulate(
            slider(MASS),
            OpenLoop(lambda t: np.array([PUSH])),
            armctl.Reference.hold([0.0]),
            0.05,
            dt=1e-4,
            energy=False,
            forces=Forces(environment=envs),
        )
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
        res = simulate(
            slider(MASS),
            OpenLoop(lambda t: np.array([MU * FN + 4.0])),
            armctl.Reference.hold([0.0]),
            0.5,
            qd0=[0.2],
            forces=Forces(environment=floor),
        )
    np.testing.assert_allclose(res.qd[:, 0], 0.2 + 4.0 / MASS * res.t, rtol=1e-12)
    assert "unstable_friction" not in res.info


@pytest.mark.parametrize(("dt", "integrator"), [(1e-4, "rk4"), (1e-3, "semi-implicit-euler")])
def test_below_the_limit_or_implicit_the_slider_creeps_as_the_closed_form(dt: float, integrator: str) -> None:
    res, warned = _creep(dt, integrator)  # RK4 at 1e-4: a h = 2.5 < 2.785
    assert warned == [] and "unstable_friction" not in res.info
    ft = res.contact_force_on_robot[-20:, 0, 0]
    np.testing.assert_allclose(ft, -PUSH, rtol=1e-3)
    np.testing.assert_allclose(res.qd[-20:, 0], PUSH * SLIP / (MU * FN), rtol=1e-3)


def test_semi_implicit_euler_books_a_spring_wall_work_exactly() -> None:
    # a slider pushed by 10 N into an undamped wall (ω h = 0.3, where the scheme is stable) bounces on it for
    # ~50 periods: the arm's energy plus the wall's spring energy is conserved up to the scheme's bounded
    # error, so E − E₀ − W must not drift. The left sum h v̄ᵀτ_e(q) booked k Δq²/2 too much a step: a drift of
    # ~ω h × 2π times the oscillation energy per period
    mass, k = 2.0, 2.0 * (0.3 / 1e-3) ** 2
    wall = Plane(KelvinVoigt(k), normal=(-1.0, 0.0, 0.0), point=(0.0, 0.0, 0.0))
    res = simulate(
        slider(mass),
        OpenLoop(lambda t: np.array([PUSH])),
        armctl.Reference.hold([0.0]),
        1.0,
        integrator="semi-implicit-euler",
        forces=Forces(environment=wall),
    )
    balance = res.energy_balance()
    stored = 0.5 * k * (2.0 * PUSH / k) ** 2  # the spring at the deepest point of the exact bounce
    assert np.abs(balance).max() < 0.2 * stored
    half = len(balance) // 2
    assert abs(balance[half:].mean() - balance[:half].mean()) < 0.02 * stored  # no trend


def _swing(
    k: float, integrator: str, dt: float | None = None
) -> tuple[armctl.sim.SimResult, list[warnings.WarningMessage]]:
    """The pendulum swung at 3 rad/s into an undamped Hunt–Crossley wall (stiffness k, exponent 1.5), 2 s."""
    dyn = armctl.Dynamics(armctl.models.pendulum())
    wall = Plane(HuntCrossley(k, 0.0, 1.5), normal=(-1.0, 0.0, 0.0), point=(0.2, 0.0, 0.0))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = simulate(
            dyn,
            OpenLoop(lambda t: np.zeros(1)),
            armctl.Reference([0.0]),
            2.0,
            qd0=[3.0],
            integrator=integrator,
            dt=dt,
            forces=Forces(environment=wall, friction="smooth"),
        )
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
    assert any(
        "no force supplied" in str(w.message) or "a compliant surface only gives back" in str(w.message) for w in warned
    )  # … and says so
    assert (
        max(bad.info["energy_gain"] if integrator == "semi-implicit-euler" else 0.0, bad.info["environment_work"]) > 0.5
    )


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


def _quiet(*args: object, **kwargs: object) -> tuple[armctl.sim.SimResult, list[warnings.WarningMessage]]:
    """simulate(*args, **kwargs) and the SimulationWarnings it gave."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = simulate(*args, **kwargs)  # type: ignore[arg-type]
    return res, [w for w in caught if issubclass(w.category, SimulationWarning)]


def test_a_plane_s_friction_is_judged_from_its_own_columns_of_the_contact_forces() -> None:
    """The creeping slider of the module with a frictionless wall of two points ahead of its floor in the list
    (never touched): the floor's normal force must be read from its own column of res.contact_force_on_environment."""
    from armctl.sim.contact import ContactPoint

    far = Plane(
        KelvinVoigt(K),
        normal=(-1.0, 0.0, 0.0),
        point=(5.0, 0.0, 0.0),
        points=[ContactPoint(), ContactPoint(offset=(0.0, 0.01, 0.0))],
    )
    floor = Plane(KelvinVoigt(K), normal=(0.0, 0.0, 1.0), point=(0.0, 0.0, DEPTH), friction=MU, slip_velocity=SLIP)
    res, warned = _quiet(
        slider(MASS),
        OpenLoop(lambda t: np.array([PUSH])),
        armctl.Reference.hold([0.0]),
        0.05,
        environment=[far, floor],
        dt=1e-3,
        energy=False,
    )
    (item,) = res.info["unstable_friction"]
    assert item["points"] == [(1, 0)] and item["normal_force"] == pytest.approx(FN, rel=1e-9)
    assert item["rate_dt"] == pytest.approx(RATE * 1e-3, rel=1e-6)
    assert any("slip_velocity >=" in str(w.message) for w in warned)


@pytest.mark.steps_may_differ("a plane's friction too stiff for the step, on purpose")
def test_euler_friction_limit_is_where_one_minus_a_h_leaves_the_unit_disc() -> None:
    """Explicit Euler on v̇ = −a v + b maps v ↦ (1 − a h) v + h b: stable while a h ≤ 2. The creeping slider at a
    h = 2.27 is reported; at a h = 1.92 it creeps at the closed form v = τ v_slip / (μ f_n) unreported."""
    res, warned = _creep(1e-3 / 11, "euler")
    (item,) = res.info["unstable_friction"]
    assert item["rate_dt"] == pytest.approx(RATE * 1e-3 / 11, rel=1e-6) and item["limit"] == 2.0
    assert any("slip_velocity >=" in str(w.message) for w in warned)
    res, warned = _creep(1e-3 / 13, "euler")
    assert warned == [] and "unstable_friction" not in res.info
    np.testing.assert_allclose(res.qd[-20:, 0], PUSH * SLIP / (MU * FN), rtol=1e-3)


def test_friction_of_a_point_that_can_only_move_along_the_normal_is_not_judged() -> None:
    """A vertical slider resting on a floor with friction: its tangential Jacobian is zero, so the friction law
    has no slope to integrate (the normal direction alone would give a h = μ m g h / (m v_slip) = 4.9 at 1 ms). It
    rests at the static depth m g / k, unreported."""
    model = slider(MASS, vertical=True)
    weight = float(armctl.Dynamics(model).gravity_torque(np.zeros(1))[0])  # m g
    floor = Plane(KelvinVoigt(K), friction=MU, slip_velocity=SLIP)
    res, warned = _quiet(
        model, OpenLoop(lambda t: np.zeros(1)), armctl.Reference.hold([-weight / K]), 0.05, environment=floor
    )
    assert weight == pytest.approx(MASS * 9.81, rel=1e-3)
    assert warned == [] and "unstable_friction" not in res.info
    np.testing.assert_allclose(res.q[:, 0], -weight / K, rtol=1e-9)


def test_a_run_starting_inside_a_wall_may_take_back_its_spring_energy() -> None:
    """The vertical slider released 1 cm deep in an undamped floor: the floor's work on it, once it has left, is
    the spring energy ½ k δ₀² it started with — positive, and not an instability (it is not judged)."""
    model = slider(MASS, vertical=True)
    depth = 0.01
    res, warned = _quiet(
        model, OpenLoop(lambda t: np.zeros(1)), armctl.Reference.hold([-depth]), 0.1, environment=Plane(KelvinVoigt(K))
    )
    assert warned == [] and "environment_work" not in res.info
    flying = res.q[:, 0] > 0.0
    assert flying[-20:].all()
    np.testing.assert_allclose(res.work_external[flying], 0.5 * K * depth**2, rtol=1e-3)


def test_a_disturbance_pushing_into_a_wall_is_not_taken_for_the_wall_s_work() -> None:
    """The slider pushed by a 50 N external wrench (h_d = −F: what the arm exerts) into a damped wall: the
    disturbance's work is booked in work_external too, so that is not judged; the slider settles at the static
    depth F / k."""
    push, zeta = 50.0, 0.5
    wall = Plane(KelvinVoigt(K, 2.0 * zeta * np.sqrt(K * MASS)), normal=(-1.0, 0.0, 0.0), point=(DEPTH, 0.0, 0.0))
    res, warned = _quiet(
        slider(MASS),
        OpenLoop(lambda t: np.zeros(1)),
        armctl.Reference.hold([0.0]),
        1.0,
        environment=wall,
        disturbance=lambda t: np.array([-push, 0.0, 0.0, 0.0, 0.0, 0.0]),
    )
    assert warned == [] and "environment_work" not in res.info
    assert res.work_external.max() > 0.8 * push * DEPTH  # the push's work up to the wall, F × 1 cm
    assert res.q[-1, 0] == pytest.approx(DEPTH + push / K, rel=1e-6)


@pytest.mark.steps_may_differ("a plane's friction too stiff for the step, on purpose")
def test_friction_is_judged_on_the_contact_samples_of_a_run_mostly_out_of_contact() -> None:
    """The slider pushed from 0.2 m away onto a floor tilted by 45° along its axis (it touches for about a third
    of the run) comes to rest on it with its friction below v_slip = 0.2 mm/s. There the tangential block of J M⁻¹
    Jᵀ is cos²45° / m, so the friction's decay rate is a = μ f_n cos²45° / (m v_slip): a h ≈ 8 > 2.785."""
    slip, tilt = 2e-4, math.radians(45.0)
    floor = Plane(
        KelvinVoigt(K),
        normal=(-math.sin(tilt), 0.0, math.cos(tilt)),
        point=(0.0, 0.0, 0.0),
        friction=MU,
        slip_velocity=slip,
    )
    res, warned = _quiet(
        slider(MASS),
        OpenLoop(lambda t: np.array([PUSH])),
        armctl.Reference.hold([-0.2]),
        1.0,
        environment=floor,
        energy=False,
    )
    touching = np.abs(res.contact_force_on_environment).max(axis=(1, 2)) > 0.0
    assert 0 < touching.sum() < 0.5 * len(res.t)
    (item,) = res.info["unstable_friction"]
    rate = MU * item["normal_force"] * math.cos(tilt) ** 2 / (MASS * slip)
    assert item["rate_dt"] == pytest.approx(rate * 1e-3, rel=1e-6) and item["rate_dt"] > 2.785
    assert any("slip_velocity >=" in str(w.message) for w in warned)


def test_a_first_order_run_that_stays_in_contact_is_judged_against_its_first_order_error() -> None:
    """The slider pushed by 10 N from 1 cm onto a damped Hunt–Crossley wall (p = 1.5: not judged before the run)
    stays in contact once it touches. Semi-implicit Euler at 1 ms (ω h ≈ 0.13 at rest) ends with the O(h) energy
    error of a compressed contact, some percent of the energy exchanged: no gain to report. It rests at the static
    depth of the law, k δᵖ = F."""
    k, exponent = 1e6, 1.5
    wall = Plane(HuntCrossley(k, 20.0, exponent), normal=(-1.0, 0.0, 0.0), point=(0.0, 0.0, 0.0))
    res, warned = _quiet(
        slider(MASS),
        OpenLoop(lambda t: np.array([PUSH])),
        armctl.Reference.hold([-0.01]),
        0.5,
        environment=wall,
        integrator="semi-implicit-euler",
    )
    touching = np.abs(res.contact_force_on_environment).max(axis=(1, 2)) > 0.0
    first = int(np.argmax(touching))
    assert 0 < first and touching[first:].all()
    assert warned == [] and res.info["energy_gain"] > 0.0
    assert res.q[-1, 0] == pytest.approx((PUSH / k) ** (1.0 / exponent), rel=1e-6)
