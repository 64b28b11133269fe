"""The discretised problem: path coefficients against the library's inverse dynamics, the friction terms,
the velocity bound, and the batched dynamics."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.planning import SplinePath, build_problem, joint_limits
from armctl.planning._batch import friction_torques, rigid_torques
from tests.helpers.arms import dynamics
from tests.planning.helpers import PANDA_WAYPOINTS, PENDULUM_GRAVITY, PENDULUM_INERTIA, panda


def _torque_rows(problem):
    n = problem.dyn.n
    k = [r for r, lab in enumerate(problem.labels) if lab.kind == "torque"]
    return k[:n], k[n:]


@pytest.mark.parametrize("name", ["panda", "planar_2r-lagrange"])
def test_rows_reproduce_inverse_dynamics_along_the_path(name: str) -> None:
    # τ(s) = a u + b x + c + F_v q' ṡ + F_c(sgn q') must be dyn.inverse_dynamics(q, q' ṡ, q' u + q'' ṡ²)
    if name == "panda":
        dyn, waypoints = panda(friction=True), PANDA_WAYPOINTS
    else:
        model = armctl.models.planar_2r().with_friction(
            viscous=[3.0, 2.0], coulomb=[4.0, 2.0], coulomb_negative=[5.0, 1.0]
        )
        dyn = armctl.Dynamics(model, backend="lagrange", rotor_coupling=False)
        waypoints = np.array([[0.0, 0.3], [0.6, -0.4], [1.2, 0.5]])
    path = SplinePath(waypoints)
    problem = build_problem(dyn, path, joint_limits(dyn.model, torque_limit=1e4), grid=40)
    up, down = _torque_rows(problem)
    rng = np.random.default_rng(1)
    fr = [j.friction for j in dyn.model.joints]
    fv = np.array([f.viscous for f in fr])
    for i in rng.choice(problem.grid + 1, 8, replace=False):
        sd, u = rng.uniform(0.1, 2.0), rng.uniform(-3, 3)
        q, dq, ddq = problem.q[i], problem.dq[i], problem.ddq[i]
        expected = dyn.inverse_dynamics(q, dq * sd, dq * u + ddq * sd**2)
        exact = problem.a[i, up] * u + problem.b[i, up] * sd**2 + problem.gravity[i] + fv * dq * sd
        coulomb = np.where(dq > 0, [f.coulomb for f in fr], -np.array([f.coulomb_neg for f in fr]))
        # away from a reversal the Coulomb torque is exact
        steady = np.sign(problem.dq[max(i - 1, 0)]) * np.sign(problem.dq[min(i + 1, problem.grid)]) > 0
        np.testing.assert_allclose((exact + coulomb)[steady], expected[steady], rtol=1e-9, atol=1e-9)
        # the upper rows (tangent of the viscous term at x0 = ṡ²) are exact there, the lower rows likewise
        a, b, c = problem.linearized(np.full(problem.grid + 1, sd**2))
        upper = a[i, up] * u + b[i, up] * sd**2 + c[i, up]
        lower = -(a[i, down] * u + b[i, down] * sd**2 + c[i, down])
        assert (upper >= expected - 1e-9).all() and (lower <= expected + 1e-9).all()
        np.testing.assert_allclose(upper[steady & (dq > 0)], expected[steady & (dq > 0)], rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(lower[steady & (dq < 0)], expected[steady & (dq < 0)], rtol=1e-9, atol=1e-9)


def test_viscous_tangent_over_estimates_at_every_speed() -> None:
    dyn = panda(friction=True)
    problem = build_problem(dyn, SplinePath(PANDA_WAYPOINTS), joint_limits(dyn.model, torque_limit="model"), 30)
    up, down = _torque_rows(problem)
    for x0 in (np.full(problem.grid + 1, 0.04), np.full(problem.grid + 1, 400.0)):
        for keep in (None, 0.5):  # the tangent, and the steeper line solve_problem tries as well
            _check_viscous_line(problem, *problem.linearized(x0, keep)[1:], up, down)
    # at x₀ = 400 the tangent's intercept takes more than half the slack of some rows: the steep line differs
    assert (problem.linearized(x0)[2] != problem.linearized(x0, 0.5)[2]).any()


def _check_viscous_line(problem, b, c, up, down) -> None:  # type: ignore[no-untyped-def]
    fv = np.array([j.friction.viscous for j in problem.dyn.model.joints])
    for x in (0.0, 1e-4, 0.01, 0.04, 0.3, 3.0):
        true_visc = fv * problem.dq * np.sqrt(x)
        rows_up = b[:, up] * x + c[:, up] - problem.b[:, up] * x - problem.c[:, up]
        rows_down = -(b[:, down] * x + c[:, down]) + problem.b[:, down] * x + problem.c[:, down]
        assert (rows_up >= true_visc - 1e-12).all()  # upper bound side: never below the true term
        assert (rows_down <= true_visc + 1e-12).all()  # lower bound side: never above it


def test_coulomb_takes_both_values_around_a_reversal() -> None:
    # joint 0 goes 0 → 1 → 0: it reverses at the middle waypoint
    dyn = armctl.Dynamics(armctl.models.planar_2r().with_friction(coulomb=[4.0, 0.0], coulomb_negative=[6.0, 0.0]))
    path = SplinePath([[0.0, 0.0], [1.0, 0.5], [0.0, 1.0]])
    problem = build_problem(dyn, path, joint_limits(dyn.model, torque_limit=1e4), grid=51)  # reversal inside a stage
    lo, hi = problem.coulomb[:, 0, 0], problem.coulomb[:, 0, 1]
    sign = np.sign(problem.dq[:, 0])
    flips = np.flatnonzero(sign[:-1] != sign[1:])
    assert flips.size == 1
    i = flips[0]
    assert (lo[i : i + 2] == -6.0).all() and (hi[i : i + 2] == 4.0).all()
    far = np.r_[0 : i - 1, i + 3 : problem.grid + 1]
    np.testing.assert_array_equal(lo[far], hi[far])  # exact elsewhere
    np.testing.assert_array_equal(hi[far], np.where(sign[far] > 0, 4.0, -6.0))


def test_velocity_bound_holds_on_whole_stages() -> None:
    dyn = panda()
    path = SplinePath(PANDA_WAYPOINTS)
    limits = joint_limits(dyn.model, vel_limit="model")
    problem = build_problem(dyn, path, limits, grid=60)
    # any x linear on a stage and within x_max at both ends keeps |q' ṡ| within the limit all along it
    frac = np.linspace(0, 1, 41)
    for i in range(problem.grid):
        s = problem.s[i] + (problem.s[i + 1] - problem.s[i]) * frac
        for xa, xb in ((problem.x_max[i], problem.x_max[i + 1]), (problem.x_max[i], 0.0), (0.0, problem.x_max[i + 1])):
            x = xa + (xb - xa) * frac
            qd = path(s, 1) * np.sqrt(x)[:, None]
            assert (np.abs(qd) <= dyn.model.velocity_limit * (1 + 1e-3)).all()


def test_batched_dynamics_equal_the_public_api() -> None:
    dyn = panda(friction=True)
    rng = np.random.default_rng(2)
    q, qd, qdd = (rng.normal(size=(25, 7)) for _ in range(3))
    qd[3] = 0.0
    tau = rigid_torques(dyn, q, qd, qdd) + friction_torques(dyn, qd)
    ref = np.array([dyn.inverse_dynamics(q[k], qd[k], qdd[k]) for k in range(25)])
    np.testing.assert_allclose(tau, ref, rtol=1e-12, atol=1e-10)
    lag = dynamics("planar_2r", "lagrange", rotor_coupling=False)
    q2, qd2, qdd2 = (np.ascontiguousarray(a[:, :2]) for a in (q, qd, qdd))
    expected = [lag.inverse_dynamics(a, b, c) for a, b, c in zip(q2, qd2, qdd2, strict=True)]
    np.testing.assert_allclose(rigid_torques(lag, q2, qd2, qdd2), expected)


@pytest.mark.parametrize("i", [2, 5])
@pytest.mark.parametrize("x", [0.5, 5.0, 60.0])
def test_least_violation_lp_imposes_the_rows_at_the_stage_end(i: int, x: float) -> None:
    """The failed-stage diagnosis LP (interpolation): with x = ṡ² fixed at s_i, the least normalised violation
    over u is min_u max(|τ(s_i)|, |τ(s_{i+1})|)/L − 1, the torques from the closed-form pendulum
    I q̈ + m g ℓ_c sin q with q̈ = q' u + q'' x at s_i and q' u + q'' (x + 2Δu) at s_{i+1} (x_{i+1} = x + 2Δu);
    the minimum of that convex piecewise-linear function is found exactly among its kinks. The curved path
    (uniform knots, q'' = 2) makes the stage end depend on u through q'' as well."""
    from armctl.planning.infeasibility import _stage_lp

    dyn = armctl.Dynamics(armctl.models.pendulum().with_friction(viscous=0.0, coulomb=0.0))
    path = SplinePath([[0.0], [0.5], [1.5]], knots="uniform")
    limit = 4.0
    problem = build_problem(dyn, path, joint_limits(dyn.model, torque_limit=limit), grid=8)
    t, (u_star, _), _ = _stage_lp(problem, problem.linearized(None), i, None, x)

    s = problem.s[i : i + 2]
    q, dq, ddq = (d[:, 0] for d in path.derivatives(s))
    assert np.all(ddq == pytest.approx(2.0))
    two_delta = np.array([0.0, 2.0 * (s[1] - s[0])])
    alpha = PENDULUM_INERTIA * ddq * x + PENDULUM_GRAVITY * np.sin(q)  # τ = α + β u at s_i, s_{i+1}
    beta = PENDULUM_INERTIA * (dq + ddq * two_delta)

    def violation(u: float) -> float:
        return float(np.abs(alpha + beta * u).max()) / limit - 1.0

    kinks = [
        -alpha[0] / beta[0],
        -alpha[1] / beta[1],
        -(alpha[0] - alpha[1]) / (beta[0] - beta[1]),
        -(alpha[0] + alpha[1]) / (beta[0] + beta[1]),
    ]
    expected = min(violation(u) for u in kinks)
    assert t == pytest.approx(expected, rel=1e-7, abs=1e-9)
    assert violation(u_star) == pytest.approx(expected, rel=1e-7, abs=1e-9)
