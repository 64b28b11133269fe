"""Bad input to the planners raises an ArmctlError subclass that names the value (and a builtin base class)."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.errors import ArmctlError, InfeasibleError, InvalidParameterError, NonFiniteError, ShapeError
from armctl.planning import LinePath, PolynomialTiming, SplinePath, Trajectory, time_optimal, uniform_time_scaling
from tests.planning.helpers import PANDA_WAYPOINTS, panda

N = 7


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"waypoints": PANDA_WAYPOINTS[:, :6]}, ShapeError, r"6 joints .* the arm 7"),
        ({"waypoints": PANDA_WAYPOINTS[0]}, ShapeError, "waypoints must be an"),
        (
            {"waypoints": [PANDA_WAYPOINTS[0], PANDA_WAYPOINTS[1][:3]]},
            ShapeError,
            r"rows have different shapes \[\(7,\), \(3,\)\]",
        ),
        ({"waypoints": np.where(np.eye(5, 7) > 0, np.nan, PANDA_WAYPOINTS)}, NonFiniteError, "waypoint 0 joint 0"),
        ({"torque_limit": np.ones(6)}, ShapeError, "torque limit must be a scalar, an \\(7,\\)"),
        ({"torque_limit": np.ones((7, 3))}, ShapeError, "torque limit"),
        ({"torque_limit": -5.0}, InvalidParameterError, "must be > 0"),
        ({"vel_limit": np.r_[1.0, 1.0, 0.0, 1.0, 1.0, 1.0, 1.0]}, InvalidParameterError, "joint 2 is 0"),
        ({"acc_limit": np.nan}, NonFiniteError, "NaN"),
        ({"torque_limit": np.column_stack([np.full(N, 5.0), np.full(N, -5.0)])}, InvalidParameterError, "lower 5"),
        ({"vel_limit": np.column_stack([np.full(N, 0.5), np.full(N, 2.0)])}, InvalidParameterError, "contain 0"),
        ({"acc_limit": "model"}, InvalidParameterError, "acceleration limit"),
        ({"torque_limit": "lots"}, InvalidParameterError, "torque limit"),
        ({"torque_limit": None}, InvalidParameterError, "no limit given"),
        ({"torque_margin": 1.0}, InvalidParameterError, "torque_margin"),
        ({"torque_margin": 0.1, "torque_limit": None, "vel_limit": 1.0}, InvalidParameterError, "needs a torque_limit"),
        ({"grid": 1}, InvalidParameterError, "grid must be >= 2"),
        ({"grid": np.array([0.0, 0.6, 0.4, 1.0])}, InvalidParameterError, "increase strictly"),
        ({"grid": np.array([0.1, 0.5, 1.0])}, InvalidParameterError, "from 0 to 1"),
        ({"tol": -1.0}, InvalidParameterError, "tol"),
        ({"oversample": 0}, InvalidParameterError, "oversample"),
        ({"discretization": "spectral"}, InvalidParameterError, "discretization"),
    ],
)
def test_time_optimal_rejects_bad_input(kwargs: dict, error: type[ArmctlError], match: str) -> None:
    args = {"waypoints": PANDA_WAYPOINTS, "torque_limit": "model"}
    args.update(kwargs)
    waypoints = args.pop("waypoints")
    with pytest.raises(error, match=match) as e:
        time_optimal(panda(), waypoints, **args)
    assert isinstance(e.value, ValueError)


def test_dynamics_must_be_a_dynamics() -> None:
    with pytest.raises(InvalidParameterError, match=r"armctl\.Dynamics"):
        time_optimal(armctl.models.panda(), PANDA_WAYPOINTS, torque_limit="model")


def test_a_path_that_stops_is_refused() -> None:
    # q(s) = 4(s − ½)³: q'(½) = 0 inside the path, where the path velocity would be unbounded
    from armctl.planning import SplinePath

    s = np.linspace(0, 1, 9)
    path = SplinePath((4 * (s - 0.5) ** 3)[:, None], knots=s)
    dyn = armctl.Dynamics(armctl.models.pendulum())
    with pytest.raises(InvalidParameterError, match="stationary"):
        time_optimal(dyn, path, vel_limit=1.0, grid=8)


@pytest.mark.parametrize("grid", [50, 100, 101])
def test_a_stop_between_gridpoints_is_refused_and_located(grid: int) -> None:
    # three waypoints q₀, q₀ + 0.3, q₀ − 0.2 (every joint the same offset): the not-a-knot spline through three
    # points is one parabola; with chord knots (0, 0.375, 1) it is p(s) = −1.6 s² + 1.4 s per joint, so all
    # joints stop together at s = 1.4/3.2 = 0.4375, which none of these grids has as a gridpoint. Before the
    # check looked between gridpoints, the outcome depended on the grid: a plan (torque limits alone, or a
    # refinement that missed s = 0.4375), toppra's "uncontrollable" with a velocity limit (a SolverError
    # blaming the solver), or this error once a refinement put a gridpoint on the stop.
    q0 = np.array([0.0, -0.4, 0.0, -2.0, 0.0, 1.6, 0.8])
    with pytest.raises(InvalidParameterError, match=r"stationary .* at s = 0\.4375") as e:
        time_optimal(panda(), np.array([q0, q0 + 0.3, q0 - 0.2]), torque_limit="model", grid=grid)
    assert e.value.value == pytest.approx(0.4375, abs=1e-12)


def test_a_near_stop_is_not_refused() -> None:
    # the same move with one joint's middle offset changed: the joints no longer stop together, so the path
    # moves everywhere (its slowest point is a joint-2 stop, with the others moving) and is timed
    q0 = np.array([0.0, -0.4, 0.0, -2.0, 0.0, 1.6, 0.8])
    mid = q0 + 0.3
    mid[0] += 0.05
    traj = time_optimal(panda(), np.array([q0, mid, q0 - 0.2]), torque_limit="model", vel_limit="model")
    assert traj.check.ok


def test_uniform_time_scaling_rejects_bad_input() -> None:
    dyn = panda()
    with pytest.raises(InvalidParameterError, match="Trajectory"):
        uniform_time_scaling(dyn, PANDA_WAYPOINTS, torque_limit="model")
    short = Trajectory(LinePath([0.0, 0.0], [1.0, 1.0]), PolynomialTiming(1.0))
    with pytest.raises(InvalidParameterError, match="2 joints"):
        uniform_time_scaling(dyn, short, torque_limit="model")
    line = Trajectory(LinePath(PANDA_WAYPOINTS[0], PANDA_WAYPOINTS[1]), PolynomialTiming(1.0))
    with pytest.raises(ShapeError):
        uniform_time_scaling(dyn, line, torque_limit=np.ones(3))


# waypoints inside the Panda's ranges whose cubic spline overshoots joint 3's upper limit (−0.0698 rad) between
# waypoints 1 and 2, both at −0.08
OVERSHOOT = np.array(
    [
        [0.0, 0.0, 0.0, -2.0, 0.0, 1.5, 0.0],
        [0.3, 0.2, 0.0, -0.08, 0.0, 1.5, 0.0],
        [0.6, 0.4, 0.0, -0.08, 0.0, 1.5, 0.0],
        [0.9, 0.2, 0.0, -2.0, 0.0, 1.5, 0.0],
    ]
)


def test_a_path_leaving_the_joint_ranges_is_refused() -> None:
    dyn = armctl.Dynamics(armctl.models.panda())
    lower, upper = dyn.model.lower, dyn.model.upper
    assert ((OVERSHOOT >= lower) & (OVERSHOOT <= upper)).all()
    with pytest.raises(
        InfeasibleError,
        match=r"joint 3 \('panda_joint4'\) leaves its range .* between waypoints 1 and "
        r"2: the path overshoots",
    ):
        time_optimal(dyn, OVERSHOOT, vel_limit="model", torque_limit="model")
    # planned anyway, the trajectory does leave the range (sampled densely, against the model's limit)
    traj = time_optimal(dyn, OVERSHOOT, vel_limit="model", torque_limit="model", position_limit=None)
    assert traj.sample(num=20001).q[:, 3].max() > upper[3] + 1e-3
    beyond = OVERSHOOT.copy()
    beyond[1, 3] = 0.5  # a waypoint 0.57 rad beyond the range
    with pytest.raises(InfeasibleError, match=r"joint 3 .* 0\.5 at s = .*, at waypoint 1") as e:
        time_optimal(dyn, beyond, torque_limit="model")
    assert e.value.value["q"] == 0.5 and e.value.value["upper"] == upper[3]
    with pytest.raises(InvalidParameterError, match="position_limit must be \"model\" or None, got 'yes'"):
        time_optimal(dyn, PANDA_WAYPOINTS, torque_limit="model", position_limit="yes")  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("limits", "waypoints", "kind"),
    [
        ({"vel_limit": [[0.0, 1.0]]}, [[1.0], [0.0]], "velocity"),
        ({"acc_limit": [[-1.0, 0.0]]}, [[0.0], [1.0]], "acceleration"),
    ],
)
def test_bounds_that_forbid_the_direction_of_the_path_are_named(limits: dict, waypoints: list, kind: str) -> None:
    # the pendulum moving down with q̇ ∈ [0, 1], or up from rest with q̈ ∈ [−1, 0]: no timing moves it (it used to
    # raise a SolverError about a "degenerate" zero-speed stage)
    dyn = armctl.Dynamics(armctl.models.pendulum())
    with pytest.raises(InfeasibleError, match=rf"no motion along the path at s = 0 .*joint 0 \('joint1'\) {kind} "):
        time_optimal(dyn, waypoints, **limits)


def test_spline_range_points_hold_its_extreme_positions() -> None:
    # against dense sampling: no sample of the spline goes beyond what its range points reach
    rng = np.random.default_rng(3)
    path = SplinePath(np.cumsum(rng.uniform(-0.5, 0.5, (12, 4)), axis=0))
    dense = path(np.linspace(0.0, 1.0, 200001))
    at = path(path.range_points())
    assert (dense.max(axis=0) <= at.max(axis=0) + 1e-12).all() and (dense.min(axis=0) >= at.min(axis=0) - 1e-12).all()
    np.testing.assert_allclose(at.max(axis=0), dense.max(axis=0), atol=1e-8)  # and they are reached


def test_torque_margin_shrinks_asymmetric_bounds_about_their_midpoint() -> None:
    # bounds [5, 20] with a 10 % margin: midpoint 12.5, half-range 7.5 → [12.5 − 6.75, 12.5 + 6.75] = [5.75, 19.25]
    # (shrunk about zero instead, as a mutant did: [4.5, 18])
    from armctl.planning.limits import joint_limits

    model = armctl.models.pendulum()
    planned = joint_limits(model, torque_limit=np.array([[5.0, 20.0]]), torque_margin=0.1).planned_torque
    assert planned is not None
    np.testing.assert_allclose([planned.lower[0], planned.upper[0]], [5.75, 19.25], rtol=1e-12)
