"""Bad input to the planners, the paths, check_trajectory, time_optimal and the timing laws raises an ArmctlError
subclass that names the value (and derives from the matching builtin): not a raw ValueError, IndexError or
AttributeError, and never no error at all."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

import armctl
from armctl.errors import ArmctlError, InfeasibleError, InvalidParameterError, NonFiniteError, ShapeError
from armctl.planning import (
    LinePath,
    PolynomialTiming,
    SplinePath,
    Trajectory,
    bang_bang_duration,
    check_trajectory,
    grid_convergence,
    joint_limits,
    line_min_time,
    time_optimal,
    uniform_time_scaling,
)
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
    # the pendulum moving down with q̇ ∈ [0, 1], or up from rest with q̈ ∈ [−1, 0]: no timing moves it (named as
    # such, not as a SolverError about a "degenerate" zero-speed stage)
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


@pytest.mark.parametrize(
    ("args", "error", "match"),
    [
        (([np.nan, 0.0], [1.0, 1.0], 1.0, 1.0), NonFiniteError, r"^start holds NaN or inf: array\(\[nan,  0\.\]\)"),
        (([np.inf, 0.0], [1.0, 1.0], 1.0, 1.0), NonFiniteError, r"^start holds NaN or inf: array\(\[inf,  0\.\]\)"),
        (([0.0, 0.0], [1.0, np.nan], 1.0, 1.0), NonFiniteError, r"^end holds NaN or inf: array\(\[ 1., nan\]\)"),
        (([1.0, 1.0], [1.0, 1.0], 1.0, 1.0), InvalidParameterError, r"^start and end coincide \(\[1\.0, 1\.0\]\)"),
        (
            (0.0, [1.0, 1.0], 1.0, 1.0),
            ShapeError,
            r"^start and end must be vectors of the same length, got start 0\.0 \(shape \(\)\) and end \[1\.0, 1\.0\]",
        ),
        (
            ([0.0, 0.0], [1.0, 1.0], [1.0, 1.0, 1.0], 1.0),
            ShapeError,
            r"^vel_limit must be a scalar or an \(2,\) vector, got shape \(3,\)",
        ),
        (([0.0, 0.0], [1.0, 1.0], 1.0, [[1.0]]), ShapeError, r"^acc_limit must be a scalar or an \(2,\) vector"),
        (
            ([0.0, 0.0], [1.0, 1.0], [1.0, 0.0], 1.0),
            InvalidParameterError,
            r"^vel_limit of joint 1 is 0; a limit must be > 0",
        ),
        (([0.0, 0.0], [1.0, 1.0], 1.0, -2.0), InvalidParameterError, r"^acc_limit must be >= 0, got \[-2\.0, -2\.0\]"),
        (
            ([0.0, 0.0], [1.0, 1.0], "fast", 1.0),
            InvalidParameterError,
            r"^vel_limit must hold real numbers, got 'fast'",
        ),
        ((["a", "b"], [1.0, 1.0], 1.0, 1.0), InvalidParameterError, r"^start must hold real numbers, got \['a', 'b'\]"),
    ],
)
def test_line_min_time_rejects_bad_input(args: tuple[Any, ...], error: type[ArmctlError], match: str) -> None:
    # a NaN in start must not give 2.0, nor an inf "v_max must be > 0, got 0.0"
    with pytest.raises(error, match=match):
        line_min_time(*args)


def test_line_min_time_of_valid_input() -> None:
    assert line_min_time(0.0, 1.0, 1.0, 1.0) == bang_bang_duration(1.0, 1.0, 1.0) == 2.0  # one joint, scalars
    # the slowest joint sets the time; a joint that does not move imposes nothing
    # (ṡ ≤ min(1/2, 1/1) = 0.5, s̈ ≤ min(4/2, 1/1) = 1: a trapezoid)
    assert math.isclose(
        line_min_time([0.0, 0.0, 0.3], [2.0, 1.0, 0.3], [1.0, 1.0, 1e-3], [4.0, 1.0, 1e-3]),
        bang_bang_duration(1.0, 0.5, 1.0),
    )


@pytest.mark.parametrize(
    ("build", "error", "match"),
    [
        (lambda: SplinePath("ab"), InvalidParameterError, r"^waypoints must hold real numbers, got 'ab'"),
        (
            lambda: SplinePath([["a", "b"], ["c", "d"]]),
            InvalidParameterError,
            r"^waypoints must hold real numbers, got \[\['a', 'b'\], \['c', 'd'\]\]",
        ),
        (lambda: SplinePath([[0j, 1.0], [1.0, 2.0]]), InvalidParameterError, r"^waypoints must hold real numbers"),
        (lambda: LinePath("ab", [1.0, 2.0]), InvalidParameterError, r"^start must hold real numbers, got 'ab'"),
        (lambda: LinePath(None, [1.0, 2.0]), InvalidParameterError, r"^start must hold real numbers, got None"),
        (
            lambda: LinePath([0.0, 1.0], ["a", "b"]),
            InvalidParameterError,
            r"^end must hold real numbers, got \['a', 'b'\]",
        ),
        (
            lambda: LinePath([0.0, 1.0], [0.0, 1.0]),
            InvalidParameterError,
            r"^start and end coincide \(\[0\.0, 1\.0\]\)",
        ),
        (lambda: LinePath([0.0, 1.0], [[0.0, 1.0]]), ShapeError, r"^start and end must be vectors of the same length"),
        (
            lambda: LinePath([0.0, 0.0], [1.0, 1.0])("a"),
            InvalidParameterError,
            r"^path parameter s must hold real numbers, got 'a'",
        ),
        (
            lambda: LinePath([0.0, 0.0], [1.0, 1.0]).derivatives(["0.5"]),
            InvalidParameterError,
            r"^path parameter s must hold real numbers, got \['0\.5'\]",
        ),
        (
            lambda: LinePath([0.0, 0.0], [1.0, 1.0]).at("0.5"),
            InvalidParameterError,
            r"^path parameter s must be a real number, got '0\.5'",
        ),
        (
            lambda: SplinePath(PANDA_WAYPOINTS)("a"),
            InvalidParameterError,
            r"^path parameter s must hold real numbers, got 'a'",
        ),
        (
            lambda: SplinePath(PANDA_WAYPOINTS).at("0.5"),
            InvalidParameterError,
            r"^path parameter s must be a real number, got '0\.5'",
        ),
        (
            lambda: SplinePath(PANDA_WAYPOINTS).at(None),
            InvalidParameterError,
            r"^path parameter s must be a real number, got None",
        ),
        (
            lambda: SplinePath(PANDA_WAYPOINTS)(0.5j),
            InvalidParameterError,
            r"^path parameter s must hold real numbers, got 0\.5j",
        ),
        (lambda: SplinePath(PANDA_WAYPOINTS)(np.nan), NonFiniteError, r"^path parameter s holds NaN or inf: nan"),
    ],
)
def test_paths_name_what_is_not_a_number(build: Callable[[], Any], error: type[ArmctlError], match: str) -> None:
    with pytest.raises(error, match=match):
        build()


def test_paths_of_valid_input_are_unchanged() -> None:
    line = LinePath(0.0, 2.0)  # scalars: one joint
    assert line.n == 1 and line(0.25).tolist() == [0.5]
    start = np.array([0.0, 1.0])
    line = LinePath(start, [1.0, 1.0])
    start[0] = 5.0  # the caller's array is not shared
    assert line.start.tolist() == [0.0, 1.0] and line.at(np.float64(0.5))[0].tolist() == [0.5, 1.0]
    spline = SplinePath(PANDA_WAYPOINTS)
    for s in (0.3, np.float64(0.3), np.array(0.3)):
        assert np.allclose(spline.at(s)[0], spline(0.3))


def _trajectory() -> Trajectory:
    return Trajectory(LinePath(PANDA_WAYPOINTS[0], PANDA_WAYPOINTS[1]), PolynomialTiming(1.0))


def test_check_trajectory_names_bad_arguments() -> None:
    dyn, traj = panda(), _trajectory()
    limits = joint_limits(dyn.model, torque_limit="model")
    with pytest.raises(
        InvalidParameterError,
        match=r"^limits must be an armctl\.planning\.JointLimits, got 'model'; "
        r"build one with armctl\.planning\.joint_limits",
    ):
        check_trajectory(dyn, traj, "model")  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match=r"^dyn must be an armctl\.Dynamics, got RobotModel"):
        check_trajectory(dyn.model, traj, limits)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match=r"^traj must be an armctl\.planning\.Trajectory, got ndarray"):
        check_trajectory(dyn, PANDA_WAYPOINTS, limits)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match=r"^samples must be None or armctl\.planning\.Samples"):
        check_trajectory(dyn, traj, limits, samples=np.zeros(3))  # type: ignore[arg-type]
    short = Trajectory(LinePath([0.0, 0.0], [1.0, 1.0]), PolynomialTiming(1.0))
    with pytest.raises(ShapeError, match=r"^the trajectory has 2 joints, the arm 7"):
        check_trajectory(dyn, short, limits)
    pendulum_limits = joint_limits(armctl.models.pendulum(), vel_limit=1.0)
    with pytest.raises(ShapeError, match=r"^the velocity limits are for 1 joints, the arm has 7"):
        check_trajectory(dyn, traj, pendulum_limits)
    for bad in ("a", 2.7, 0, True):
        with pytest.raises(InvalidParameterError, match=rf"^oversample must be a whole number >= 1, got {bad!r}"):
            check_trajectory(dyn, traj, limits, bad)  # type: ignore[arg-type]
    assert check_trajectory(dyn, traj, limits, 3.0).samples == check_trajectory(dyn, traj, limits, 3).samples


@pytest.mark.parametrize("grid", ["a", [0.0, "x", 1.0]])
def test_a_grid_that_is_not_numbers_is_named(grid: object) -> None:
    with pytest.raises(InvalidParameterError, match=r"^grid must be an integer N >= 2 or an array of gridpoints"):
        time_optimal(panda(), PANDA_WAYPOINTS, torque_limit="model", grid=grid)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"tol": "a"}, InvalidParameterError, r"^tol must be a real number, got 'a'"),
        ({"tol": float("nan")}, NonFiniteError, r"^tol must be a number >= 0 or float\('inf'\).*got nan"),
        ({"tol": -0.1}, InvalidParameterError, r"^tol must be >= 0, got -0\.1"),
        ({"oversample": "a"}, InvalidParameterError, r"^oversample must be a whole number >= 1, got 'a'"),
        ({"oversample": 2.7}, InvalidParameterError, r"^oversample must be a whole number >= 1, got 2\.7"),
        ({"max_grid": "many"}, InvalidParameterError, r"^max_grid must be a whole number >= 2, got 'many'"),
        ({"viscous_passes": 1.5}, InvalidParameterError, r"^viscous_passes must be a whole number >= 1, got 1\.5"),
    ],
)
def test_time_optimal_names_bad_settings(kwargs: dict[str, Any], error: type[ArmctlError], match: str) -> None:
    # tol="a" and oversample="a": not a raw ValueError; oversample=2.7: not run with 2
    with pytest.raises(error, match=match):
        time_optimal(panda(), PANDA_WAYPOINTS, torque_limit="model", grid=20, **kwargs)


def test_time_optimal_settings_of_valid_input() -> None:
    # tol=inf accepts any result (documented); integral floats and NumPy integers are whole numbers
    traj = time_optimal(
        panda(), PANDA_WAYPOINTS, torque_limit="model", grid=20, tol=float("inf"), oversample=np.int64(3), max_grid=40.0
    )
    assert traj.check is not None and len(traj.info["history"]) == 1


def test_timing_and_sampling_name_bad_times_and_counts() -> None:
    traj = _trajectory()
    with pytest.raises(InvalidParameterError, match=r"^t must be a real number, got '0\.5'"):
        traj.timing.at("0.5")  # type: ignore[arg-type]  # float() would parse the text
    with pytest.raises(NonFiniteError, match=r"^t must be finite, got inf"):
        traj.timing.at(np.float64("inf"))
    with pytest.raises(InvalidParameterError, match=r"^t must be a real number, got array\(\[0\.1, 0\.2\]\)"):
        traj(np.array([0.1, 0.2]))  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match=r"^t must hold real numbers, got \['0\.1', '0\.2'\]"):
        traj.timing.evaluate(["0.1", "0.2"])
    with pytest.raises(InvalidParameterError, match=r"^t must hold real numbers, got \['a'\]"):
        traj.sample(["a"])
    with pytest.raises(NonFiniteError, match=r"^t holds NaN or inf: array\(\[0\.1, nan\]\)"):
        traj.sample([0.1, np.nan])
    with pytest.raises(InvalidParameterError, match=r"^num must be a whole number >= 2, got 2\.5"):
        traj.sample(num=2.5)  # type: ignore[arg-type]
    assert len(traj.sample(num=5.0)) == 5  # type: ignore[arg-type]
    assert np.array_equal(traj(np.float64(0.4)).q, traj(0.4).q) and np.array_equal(traj(1).q, traj(1.0).q)
    with pytest.raises(InvalidParameterError, match=r"^samples must be a whole number >= 2, got 50\.5"):
        uniform_time_scaling(panda(), traj, torque_limit="model", samples=50.5)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"repeat": 1.5}, r"^repeat must be a whole number >= 1, got 1\.5"),
        ({"grids": [10.5]}, r"^grids\[0\] must be a whole number >= 2, got 10\.5"),
        ({"grids": [10, "x"]}, r"^grids\[1\] must be a whole number >= 2, got 'x'"),
        ({"grids": []}, r"^grids must hold at least one grid size, got none"),
    ],
)
def test_grid_convergence_counts_are_whole_numbers(kwargs: dict[str, Any], match: str) -> None:
    dyn = armctl.Dynamics(armctl.models.pendulum())
    with pytest.raises(InvalidParameterError, match=match):
        grid_convergence(dyn, [0.0], [1.0], 1.0, 1.0, **{"grids": [10], "repeat": 1, **kwargs})
