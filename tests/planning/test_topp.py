"""time_optimal against independent references: the analytic bang-bang durations (with Coulomb friction,
asymmetric), the exact viscous bang-bang, dense re-checks with the library's inverse dynamics, the uniform
time scaling, infeasibility reports and toppra's failure modes."""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np
import pytest
from scipy.optimize import brentq

import armctl
import armctl.planning._toppra as toppra_adapter
from armctl.errors import InfeasibleError, SolverError
from armctl.planning import (
    LinePath,
    PolynomialTiming,
    SplinePath,
    Trajectory,
    grid_convergence,
    plot_convergence,
    time_optimal,
    uniform_time_scaling,
)
from tests.planning._common import PANDA_WAYPOINTS, PENDULUM_GRAVITY, PENDULUM_INERTIA, flat_pendulum, panda

START = np.array([0.0, 0.0, 0.0, -1.5, 0.0, 1.5, 0.0])  # within the Panda's joint ranges, as is END
END = START + np.array([1.0, -0.5, 0.3, 0.2, 1.0, 0.5, -0.7])


def test_converges_to_the_bang_bang_duration(tmp_path) -> None:
    # straight line, |q̇_j| ≤ 1 rad/s and |q̈_j| ≤ 2.3 rad/s²: joints 0 and 4 (|Δ| = 1) bind, so in path
    # coordinates ṡ ≤ 1, |s̈| ≤ 2.3 and the trapezoid takes 1/V + V/A (V² = 1 < A = 2.3)
    analytic = 1.0 / 1.0 + 1.0 / 2.3
    study = grid_convergence(panda(), START, END, 1.0, 2.3, grids=(10, 20, 50, 100, 200, 500, 1000), repeat=1)
    assert study.reference == pytest.approx(analytic, rel=1e-15)
    errors = np.abs(study.durations - analytic) / analytic
    assert errors[-1] < 1e-5
    assert (errors[3:] < errors[0] / 50).all()  # from N = 100 on, far below the coarse grid's
    assert (study.durations >= analytic * (1 - 1e-9)).all()  # never faster than the optimum
    fig = plot_convergence(study)
    assert len(fig.axes) == 2
    fig.savefig(tmp_path / "topp_convergence.png")
    assert (tmp_path / "topp_convergence.png").stat().st_size > 0


@pytest.mark.parametrize("distance", [1.5, -1.5])
def test_coulomb_friction_is_exact_asymmetric_bang_bang(distance: float) -> None:
    # gravity off: M q̈ + F_c(sgn q̇) = τ, |τ| ≤ 2. Moving up (F_c⁺ = 0.5) the arm accelerates at (2 − F_c)/M and
    # brakes at (2 + F_c)/M; moving down F_c⁻ = 0.8 plays that role
    fc = 0.5 if distance > 0 else 0.8
    dyn = flat_pendulum(coulomb=0.5, coulomb_negative=0.8)
    a1, a2 = (2.0 - fc) / PENDULUM_INERTIA, (2.0 + fc) / PENDULUM_INERTIA
    v = math.sqrt(2 * abs(distance) * a1 * a2 / (a1 + a2))
    analytic = v / a1 + v / a2
    traj = time_optimal(dyn, LinePath([0.0], [distance]), torque_limit=2.0, grid=200)
    assert traj.duration == pytest.approx(analytic, rel=1e-5)
    assert traj.check.ok(1e-9)


def _viscous_bang_bang(distance: float, tau: float, fv: float, inertia: float, help_braking: bool = True) -> float:
    """Minimum time with M q̈ = τ − F_v q̇ at full torque forward, then full torque back to rest, braking with
    M q̈ = −τ − F_v q̇ (the true dynamics) or, help_braking=False, −τ alone (the planner's conservative model,
    which does not count on viscous friction to help it brake). Closed form per phase, switch by root finding."""
    k, a = fv / inertia, tau / inertia

    def speed(t: float) -> float:  # accelerating from rest
        return a / k * (1 - math.exp(-k * t))

    def travelled(t: float) -> float:
        return a / k * (t - (1 - math.exp(-k * t)) / k)

    def braking(v0: float) -> tuple[float, float]:  # time and distance to stop from v0
        if not help_braking:
            return v0 / a, v0 * v0 / (2 * a)
        ts = math.log(1 + k * v0 / a) / k
        return ts, (v0 + a / k) * (1 - math.exp(-k * ts)) / k - a / k * ts

    t1 = brentq(lambda t: travelled(t) + braking(speed(t))[1] - distance, 1e-9, 100.0, xtol=1e-14)
    return t1 + braking(speed(t1))[0]


def test_viscous_friction_is_conservative_and_close() -> None:
    dyn = flat_pendulum(viscous=1.5)
    exact = _viscous_bang_bang(1.5, 2.0, 1.5, PENDULUM_INERTIA)
    modelled = _viscous_bang_bang(1.5, 2.0, 1.5, PENDULUM_INERTIA, help_braking=False)
    traj = time_optimal(dyn, LinePath([0.0], [1.5]), torque_limit=2.0, grid=200)
    assert exact < modelled <= traj.duration <= modelled * 1.01
    assert traj.check.ok(0.0)  # conservative: the true torque never exceeds the bound


def _swing_bang_bang(distance: float, tau: float, fv: float, help_braking: bool, start: float = 0.0) -> float:
    """Rest-to-rest minimum time of the pendulum with gravity, I q̈ = ±τ − G sin q − F_v q̇ (closed-form model
    from its published data), full torque forward then full torque back, the switch found by shooting;
    help_braking=False brakes without the viscous term (the planner's conservative model)."""
    from scipy.integrate import solve_ivp

    def phase(sign: float, viscous: float) -> Any:
        return lambda t, y: [y[1], (sign * tau - PENDULUM_GRAVITY * math.sin(y[0]) - viscous * y[1]) / PENDULUM_INERTIA]

    def stop(t: float, y: np.ndarray) -> float:
        return float(y[1])

    stop.terminal, stop.direction = True, -1  # type: ignore[attr-defined]

    def run(t_switch: float) -> tuple[float, float]:
        a = solve_ivp(phase(1.0, fv), [0.0, t_switch], [start, 0.0], rtol=1e-11, atol=1e-12, events=stop)
        if a.status == 1:  # stalled below the gravity peak
            return -math.inf, math.inf
        b = solve_ivp(
            phase(-1.0, fv if help_braking else 0.0),
            [t_switch, t_switch + 10.0],
            a.y[:, -1],
            rtol=1e-11,
            atol=1e-12,
            events=stop,
        )
        return float(b.y[0, -1]) - start, float(b.t[-1])

    t_switch = brentq(lambda ts: max(run(ts)[0], -1.0) - distance, 0.05, 3.0, xtol=1e-12)
    return run(t_switch)[1]


@pytest.mark.parametrize(("tau", "grid", "within"), [(4.8, 100, 0.02), (4.8, 400, 0.005), (4.5, 200, 0.012)])
def test_viscous_swing_through_a_pose_it_cannot_hold(tau: float, grid: int, within: float) -> None:
    # the torque bound is below the gravity peak G = 4.905 N·m: the arm must carry its speed through, which a
    # viscous line fitted for slow motion forbids (it planned 5.7× the optimum, or found no timing at all)
    dyn = armctl.Dynamics(armctl.models.pendulum().with_friction(viscous=0.3, coulomb=0.0))
    exact = _swing_bang_bang(2.2, tau, 0.3, help_braking=True)
    modelled = _swing_bang_bang(2.2, tau, 0.3, help_braking=False)
    traj = time_optimal(dyn, LinePath([0.0], [2.2]), torque_limit=tau, grid=grid)
    assert exact < modelled <= traj.duration <= modelled * (1 + within)


@pytest.mark.parametrize(("fv", "tau", "start", "end"), [(1.0, 6.0, 1.0, 2.5), (1.0, 5.0, 0.2, 1.2)])
def test_viscous_moves_end_within_half_a_percent_of_the_bang_bang(
    fv: float, tau: float, start: float, end: float
) -> None:
    # moves where the steeper viscous line beats the tangent (planned with the tangent alone they took 3-5 %
    # longer than the optimum of the planner's own model at every grid)
    dyn = armctl.Dynamics(armctl.models.pendulum().with_friction(viscous=fv, coulomb=0.0))
    exact = _swing_bang_bang(end - start, tau, fv, help_braking=True, start=start)
    modelled = _swing_bang_bang(end - start, tau, fv, help_braking=False, start=start)
    traj = time_optimal(dyn, LinePath([start], [end]), torque_limit=tau, grid=400)
    assert exact < modelled <= traj.duration <= modelled * 1.005


def test_viscous_infeasibility_says_the_plan_is_conservative() -> None:
    # with F_v = 1 the swing cannot carry its speed through the gravity peak: every bang-bang stalls
    with pytest.raises(ValueError, match="f\\(a\\) and f\\(b\\) must have different signs"):
        _swing_bang_bang(2.2, 4.5, 1.0, help_braking=True)
    dyn = armctl.Dynamics(armctl.models.pendulum().with_friction(viscous=1.0, coulomb=0.0))
    with pytest.raises(
        InfeasibleError,
        match=r"gravity alone needs 4\.905 N·m.*Viscous friction is planned with a "
        r"line above F_v q̇",
    ):
        time_optimal(dyn, LinePath([0.0], [2.2]), torque_limit=4.5)


def _dense_torque_utilisation(dyn: armctl.Dynamics, traj: Trajectory, limit: np.ndarray, num: int) -> float:
    """max |τ_j| / limit_j over num samples strictly inside (0, T), τ from dyn.inverse_dynamics."""
    smp = traj.sample(np.linspace(0, traj.duration, num + 2)[1:-1])
    tau = np.array([dyn.inverse_dynamics(q, qd, qdd) for q, qd, qdd in zip(smp.q, smp.qd, smp.qdd, strict=True)])
    return float((np.abs(tau) / limit).max())


def test_panda_with_friction_respects_torque_limits_and_beats_uniform_scaling() -> None:
    dyn = panda(friction=True)
    limit = dyn.model.effort_limit
    traj = time_optimal(dyn, PANDA_WAYPOINTS, vel_limit="model", torque_limit="model", grid=100, tol=1e-2)
    assert traj.check.ok(1e-2)
    assert _dense_torque_utilisation(dyn, traj, limit, 2000) <= 1.01  # our own re-check, 20 samples per stage
    vel = np.abs(traj.sample(num=2001).qd) / dyn.model.velocity_limit
    assert vel.max() <= 1.01
    nominal = Trajectory(SplinePath(PANDA_WAYPOINTS), PolynomialTiming(1.0))
    uniform = uniform_time_scaling(dyn, nominal, vel_limit="model", torque_limit="model")
    assert traj.duration <= uniform.duration


def test_torque_margin_is_kept() -> None:
    dyn = panda()
    limit = dyn.model.effort_limit
    full = time_optimal(dyn, PANDA_WAYPOINTS, torque_limit="model")
    kept = time_optimal(dyn, PANDA_WAYPOINTS, torque_limit="model", torque_margin=0.1)
    assert kept.duration > full.duration
    assert _dense_torque_utilisation(dyn, kept, limit, 2000) <= 0.9 * 1.01


def test_refinement_until_within_tolerance() -> None:
    dyn = panda()
    traj = time_optimal(dyn, PANDA_WAYPOINTS, torque_limit="model", grid=25, tol=1e-3)
    grids = [h["grid"] for h in traj.info["history"]]
    assert grids[0] == 25 and grids == sorted(grids) and len(grids) > 1
    assert traj.check.worst_excess <= 1e-3 < traj.info["history"][0]["worst_excess"]
    with pytest.raises(SolverError, match="exceeds a limit") as err:
        time_optimal(dyn, PANDA_WAYPOINTS, torque_limit="model", grid=25, tol=1e-3, refine=False)
    assert isinstance(err.value.result, Trajectory)  # the violating result is handed over, never silently


def test_collocation_converges_to_first_order_and_its_failure_says_so() -> None:
    # collocation imposes the rows at each stage's start only: the constant s̈ of a stage exceeds a limit by its
    # end by O(Δ), so the excess halves per doubling of the grid (interpolation's falls ~4× per doubling)
    dyn = panda()
    with pytest.raises(SolverError, match=r"collocation imposes .* discretization='interpolation'") as err:
        time_optimal(
            dyn, PANDA_WAYPOINTS, vel_limit="model", acc_limit=5.0, grid=100, max_grid=800, discretization="collocation"
        )
    excess = [h["worst_excess"] for h in err.value.result.info["history"]]
    assert len(excess) == 4 and excess[-1] > 1e-2
    for coarse, fine in itertools.pairwise(excess):
        assert 0.35 < fine / coarse < 0.7
    traj = time_optimal(dyn, PANDA_WAYPOINTS, vel_limit="model", acc_limit=5.0, grid=100, max_grid=800)
    assert traj.check.worst_excess <= 1e-2


def test_reference_at_the_ends_and_consistent_derivatives() -> None:
    # called with the documented keywords: time_optimal(dyn, waypoints, vel_limit=..., ...)
    traj = time_optimal(dyn=panda(), waypoints=PANDA_WAYPOINTS, vel_limit="model", torque_limit="model")
    start, end = traj(0.0), traj(traj.duration)
    np.testing.assert_allclose(start.q, PANDA_WAYPOINTS[0], atol=1e-12)
    np.testing.assert_allclose(end.q, PANDA_WAYPOINTS[-1], atol=1e-12)
    np.testing.assert_allclose(start.qd, 0, atol=1e-12)
    np.testing.assert_allclose(end.qd, 0, atol=1e-12)
    np.testing.assert_allclose(traj(traj.duration + 1.0).qdd, 0)
    t = np.linspace(0.1, traj.duration - 0.1, 23)
    h = 1e-6
    fd = (traj.sample(t + h).q - traj.sample(t - h).q) / (2 * h)
    np.testing.assert_allclose(fd, traj.sample(t).qd, atol=1e-5)
    ref = traj(1.0)
    np.testing.assert_allclose(ref.qdd, traj.sample(np.array([1.0])).qdd[0])


def test_gravity_beyond_the_limit_is_named_with_its_place() -> None:
    # the pendulum's gravity torque is m g ℓ sin q (4.905 N·m at most); with 3 N·m it cannot hold itself
    # between asin(3/4.905) and π − asin(3/4.905), and lifting it to 3 rad needs more work than 3 N·m × 3 rad
    dyn = armctl.Dynamics(armctl.models.pendulum())
    with pytest.raises(InfeasibleError, match=r"joint 0 .*torque at s = .*gravity alone needs .*the limit is 3") as e:
        time_optimal(dyn, LinePath([0.0], [3.0]), torque_limit=3.0)
    v = e.value.value
    q = 3.0 * v["s"]
    assert math.asin(3 / PENDULUM_GRAVITY) <= q <= math.pi - math.asin(3 / PENDULUM_GRAVITY)
    assert v["gravity"] == pytest.approx(PENDULUM_GRAVITY * math.sin(q), rel=1e-9)
    assert v["limit"] == 3.0 and v["constraint"] == "torque" and v["joint"] == 0


def test_panda_infeasibility_names_the_joint() -> None:
    limits = np.array([87, 20, 87, 87, 12, 12, 12.0])
    with pytest.raises(InfeasibleError, match=r"panda_joint2.*gravity alone needs") as e:
        time_optimal(panda(), PANDA_WAYPOINTS, torque_limit=limits)
    assert e.value.value["joint"] == 1
    assert abs(e.value.value["gravity"]) > 20
    assert e.value.problem is not None


def test_toppra_failures_do_not_pass_silently(monkeypatch: pytest.MonkeyPatch) -> None:
    real = toppra_adapter.run_toppra
    dyn = panda()

    def forward_fails(*args, **kwargs):
        out = real(*args, **kwargs)
        x = out.x.copy()
        x[40:] = np.nan
        return toppra_adapter.ToppraOutput("ErrUnknown", x, out.K)

    monkeypatch.setattr(toppra_adapter, "run_toppra", forward_fails)
    with pytest.raises(SolverError, match="forward pass failed"):
        time_optimal(dyn, PANDA_WAYPOINTS, torque_limit="model")

    def spurious_uncontrollable(*args, **kwargs):  # toppra issues #14/#17: NaN sets on a feasible problem
        out = real(*args, **kwargs)
        K = out.K.copy()
        K[30] = np.nan
        return toppra_adapter.ToppraOutput("FailUncontrollable", None, K)

    monkeypatch.setattr(toppra_adapter, "run_toppra", spurious_uncontrollable)
    with pytest.raises(SolverError, match="numerical failure"):
        time_optimal(dyn, PANDA_WAYPOINTS, torque_limit="model")

    def overshoot(*args, **kwargs):  # a profile beyond its own velocity bound
        out = real(*args, **kwargs)
        return toppra_adapter.ToppraOutput("Ok", out.x * 1.5, out.K)

    monkeypatch.setattr(toppra_adapter, "run_toppra", overshoot)
    with pytest.raises(SolverError, match="outside its own bounds"):
        time_optimal(dyn, PANDA_WAYPOINTS, vel_limit="model")


def test_a_viscous_solve_that_stalls_is_dropped_when_the_other_moves(monkeypatch: pytest.MonkeyPatch) -> None:
    # each viscous pass solves twice (tangent, then the steep line): a steep-line profile that stops on a stage is
    # no timing, and the pass keeps the tangent's — the same result as a steep line that finds nothing at all
    real = toppra_adapter.run_toppra
    dyn = armctl.Dynamics(armctl.models.pendulum().with_friction(viscous=0.3, coulomb=0.0))
    calls = {"n": 0}

    def steep(stalls: bool):  # type: ignore[no-untyped-def]
        def run(*args, **kwargs):  # type: ignore[no-untyped-def]
            calls["n"] += 1
            out = real(*args, **kwargs)
            if calls["n"] % 2 == 1 and calls["n"] > 1:  # calls 3, 5: the steep line of each viscous pass
                if not stalls:
                    return toppra_adapter.ToppraOutput("FailUncontrollable", None, out.K)
                x = out.x.copy()
                x[40:42] = 0.0
                return toppra_adapter.ToppraOutput("Ok", x, out.K)
            return out

        return run

    durations = []
    for stalls in (True, False):
        calls["n"] = 0
        monkeypatch.setattr(toppra_adapter, "run_toppra", steep(stalls))
        durations.append(time_optimal(dyn, LinePath([0.0], [2.2]), torque_limit=4.8, grid=100).duration)
    assert calls["n"] == 5  # 1 optimistic + 2 passes × 2 lines
    assert durations[0] == durations[1]
    monkeypatch.setattr(toppra_adapter, "run_toppra", real)
    assert time_optimal(dyn, LinePath([0.0], [2.2]), torque_limit=4.8, grid=100).duration <= durations[0]
