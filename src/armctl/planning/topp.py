"""`time_optimal`: the fastest rest-to-rest timing of a path under joint velocity, acceleration and torque limits.

TOPP-RA (Pham & Pham, "A new approach to time-optimal path parameterization based on reachability analysis",
IEEE T-RO 2018) through toppra, on the problem built by :func:`~armctl.planning.problem.build_problem` from the
arm's own dynamics (friction included, see there). Every result is then verified densely
(:func:`~armctl.planning.verify.check_trajectory`); when a limit is exceeded by more than ``tol`` the grid is
refined (doubled) and the problem solved again, and if that does not help a
:class:`~armctl.errors.SolverError` is raised — a violating result never reaches the caller silently.
Infeasible problems raise :class:`~armctl.errors.InfeasibleError` naming the binding constraint and where it
binds (:mod:`~armctl.planning.infeasibility`).

toppra's known failure modes (its issue tracker) and what happens to each here:

* the default ``ParametrizeSpline`` output overshoots the limits between gridpoints (#41, #56, #150): not used;
  the output is :class:`~armctl.planning.timing.GridTiming`, TOPP-RA's own constant-s̈ model;
* a failed solve returns None with a log warning (#26): return codes are read and turned into
  :class:`~armctl.errors.InfeasibleError` (a real infeasibility) or :class:`~armctl.errors.SolverError`;
* NaN controllable sets on feasible problems, forward-pass failures (#14, #17, #226): the failing stage is
  re-solved as a small LP; if it is feasible the error says the failure was numerical;
* velocity bounds imposed at gridpoints only are exceeded between them on curved paths (several %): the bound
  is tightened by its sag over each stage (:func:`~armctl.planning.problem.velocity_bound`);
* paths with q'(s) = 0 inside give unbounded path velocities (#104): refused with the place;
* a stage crossed at zero speed would take "5 s" in toppra's parametrizer: refused (:class:`GridTiming`);
* toppra only requires ṡ = 0 at the ends and may brake (s̈ ≠ 0) at the last gridpoint, "throwing" the arm
  into an end pose it cannot hold: the rest states at both ends (before 0, after T) are required to fit the
  torque bounds before solving, and are part of the dense check;
* every profile is checked (finite, ≥ 0, within its velocity bound, at rest at both ends) and every trajectory
  densely re-verified with the full inverse dynamics.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, check_memory, scalar, whole_number
from armctl.dynamics.base import Dynamics
from armctl.errors import InfeasibleError, InvalidParameterError, NonFiniteError, SolverError
from armctl.model.robot import RobotModel
from armctl.planning.infeasibility import diagnose, no_motion, rest_overload
from armctl.planning.limits import joint_limits
from armctl.planning.path import Path, as_path
from armctl.planning.problem import TimeScalingProblem, build_problem, gridpoints
from armctl.planning.timing import GridTiming
from armctl.planning.trajectory import Trajectory
from armctl.planning.verify import check_trajectory

#: the fraction of a torque row's slack at rest that the fallback viscous line may take (see
#: :meth:`~armctl.planning.problem.TimeScalingProblem.linearized`)
VISCOUS_KEEP = 0.5


def solve_problem(problem: TimeScalingProblem, viscous_passes: int = 2) -> Trajectory:
    """Solve a time-scaling problem with TOPP-RA (rest to rest).

    With viscous friction, a first pass drops it (optimistic, never returned); each of the ``viscous_passes``
    further passes replaces F_v q' √x by a line over it, in two solves: the tangent at the previous pass's x, and a
    steeper line that leaves slow motion more torque (see
    :meth:`~armctl.planning.problem.TimeScalingProblem.linearized`; each wins on some paths: the tangent where the
    path must carry its speed through a pose it cannot hold, the steep line elsewhere by a few %). Every solve is
    conservative; the fastest is returned and seeds the next pass (a pass that finds no timing leaves the earlier
    ones standing).

    Parameters
    ----------
    problem : TimeScalingProblem
        From :func:`~armctl.planning.problem.build_problem`.
    viscous_passes : int, optional
        The passes over the viscous term.

    Returns
    -------
    Trajectory
        With a :class:`~armctl.planning.timing.GridTiming` (not yet verified densely).

    Raises
    ------
    InfeasibleError
        First of all if the arm cannot be held at rest at the start or end pose within the torque bounds
        (:func:`~armctl.planning.infeasibility.rest_overload`): the trajectory rests there before 0 and after T,
        which toppra, free to brake at the last gridpoint, ignores; or if no timing meets the limits.
    SolverError
        A numerical failure.
    """
    from armctl.planning._toppra import run_toppra

    viscous_passes = whole_number(viscous_passes, "viscous_passes", 1)
    t0 = time.perf_counter()
    at_rest = rest_overload(problem)
    if at_rest is not None:
        raise at_rest
    x0 = None
    best: GridTiming | None = None  # the fastest conservative pass
    passes = 0
    for _ in range(1 + (viscous_passes if problem.has_viscous else 0)):
        found: list[FloatArray] = []
        for keep in (None,) if x0 is None else (None, VISCOUS_KEEP):  # with x₀: both lines, the faster kept
            rows = problem.linearized(x0, keep)
            out = run_toppra(problem, rows)
            if out.ok and out.x is not None:
                found.append(_checked_profile(problem, out.x))
        if not found:
            if best is not None:
                break
            raise _viscous_note(diagnose(problem, rows, out.code, out.x, out.K), x0 is not None)
        # a profile with a stage never crossed (ṡ = 0 at both ends) is no timing: the limits forbid moving there
        still = [(x[:-1] <= 0.0) & (x[1:] <= 0.0) for x in found]
        if all(st.any() for st in still):
            raise no_motion(problem, int(np.flatnonzero(still[0])[0]))
        timing = min(
            (GridTiming(problem.s, x) for x, st in zip(found, still, strict=True) if not st.any()),
            key=lambda g: g.duration,
        )
        passes += 1
        if (x0 is not None or not problem.has_viscous) and (best is None or timing.duration < best.duration):
            best = timing
        x0 = np.maximum(timing.x, 1e-9 * max(float(timing.x.max()), 1e-12))
    assert best is not None
    return Trajectory(
        problem.path, best, info={"grid": problem.grid, "passes": passes, "solve_time": time.perf_counter() - t0}
    )


def check_range(model: RobotModel, path: Path) -> None:
    """Check that a path stays within the model's joint ranges (its finite lower/upper limits).

    Checked at the path's :meth:`~armctl.planning.Path.range_points` (a spline's exact extrema; other paths densely
    sampled).

    Parameters
    ----------
    model : RobotModel
        The arm.
    path : Path
        The path.

    Raises
    ------
    InfeasibleError
        The path leaves a range: the error names the joint, the worst point (a waypoint outside first, else where
        the path overshoots between two) and the range.
    """
    lo, hi = model.lower, model.upper
    if not (np.isfinite(lo).any() or np.isfinite(hi).any()):
        return
    knots = path.breakpoints
    s = path.range_points()
    q = path(s)
    with np.errstate(invalid="ignore"):
        excess = np.maximum(q - hi, lo - q)  # > 0 outside; inf limits give −inf
    on_knot = np.isin(s, knots)
    if (excess[on_knot] > 1e-12).any():  # a waypoint outside: the cause to name first
        excess = np.where(on_knot[:, None], excess, -np.inf)
    i, j = (int(v) for v in np.unravel_index(int(np.argmax(excess)), excess.shape))
    if not excess[i, j] > 1e-12:
        return
    k = path.piece(float(s[i]))
    at_knot = np.isclose(knots, s[i], rtol=0.0, atol=1e-12)
    where = (
        f"at waypoint {int(np.flatnonzero(at_knot)[0])}"
        if at_knot.any()
        else f"between waypoints {k} and {k + 1}: the path overshoots there; add a waypoint or move them"
    )
    unit = "m" if model.joints[j].kind == "prismatic" else "rad"
    raise InfeasibleError(
        f"joint {j} ({model.joint_names[j]!r}) leaves its range [{lo[j]:.4g}, {hi[j]:.4g}] {unit} along the path: "
        f"{q[i, j]:.4g} at s = {s[i]:.4g}, {where} (a timing cannot change the path; position_limit=None plans it "
        "anyway)",
        value={"joint": j, "s": float(s[i]), "q": float(q[i, j]), "lower": float(lo[j]), "upper": float(hi[j])},
    )


def _viscous_note(error: Exception, viscous: bool) -> Exception:
    """``error`` (an InfeasibleError from a pass with the viscous term linearized) with a note that the plan's
    over-estimate of viscous friction, not the limits themselves, may be what leaves no timing."""
    if not viscous or not isinstance(error, InfeasibleError):
        return error
    return InfeasibleError(
        f"{error} (Viscous friction is planned with a line above F_v q̇ at every speed, and "
        "without it toppra found a timing: one may exist that this conservative plan misses; "
        "a different grid may find it.)",
        value=error.value,
        problem=error.problem,
    )


def _checked_profile(problem: TimeScalingProblem, x: FloatArray) -> FloatArray:
    """toppra's x = ṡ², checked: finite, ≥ 0, within the velocity bound, zero at both ends."""
    if not np.isfinite(x).all():
        i = int(np.flatnonzero(~np.isfinite(x))[0])
        raise SolverError(
            f"toppra returned a non-finite path velocity at s = {problem.s[i]:.4g}", value=x, problem=problem
        )
    scale = max(float(x.max()), 1e-12)
    if x.min() < -1e-9 * scale or (x > problem.x_max * (1 + 1e-6) + 1e-12).any() or max(x[0], x[-1]) > 1e-9 * scale:
        raise SolverError(
            "toppra returned a path velocity profile outside its own bounds (negative, above the "
            "velocity bound or not at rest at the ends)",
            value=x,
            problem=problem,
        )
    x = np.clip(x, 0.0, problem.x_max)
    x[0] = x[-1] = 0.0
    return x


def _refined(grid: int | ArrayLike) -> int | FloatArray:
    if isinstance(grid, (int, np.integer)):
        return 2 * int(grid)
    s = np.asarray(grid, dtype=float)
    return np.sort(np.concatenate((s, 0.5 * (s[1:] + s[:-1]))))


#: bytes a plan needs per stage and joint at least, besides those of the dense check (path derivatives, the
#: constraint rows of every limit, toppra's controllable sets), and per stage, joint and dense-check sample
PLAN_BYTES_PER_STAGE, CHECK_BYTES_PER_SAMPLE = 8 * 60, 8 * 10


def _check_grid_memory(grid: int | ArrayLike, n: int, oversample: int) -> None:
    """Refuse a grid too large to plan on this machine, before its gridpoints are made."""
    if isinstance(grid, int | np.integer) and not isinstance(grid, bool):
        stages = float(grid)
    else:
        stages = float(max(np.size(grid) - 1, 0))  # the user's own gridpoints
    check_memory(
        (stages + 1) * n * (PLAN_BYTES_PER_STAGE + CHECK_BYTES_PER_SAMPLE * oversample),
        f"a time-optimal plan on a grid of {stages:.4g} stages for {n} joints (oversample={oversample})",
        "use a smaller grid (a hundred to a few thousand stages is usual: refine doubles it where the dense "
        "check needs more, up to max_grid)",
        grid,
    )


def _tolerance(tol: Any) -> float:
    """``tol`` as a float >= 0, ``inf`` included (accept any result)."""
    if isinstance(tol, float | np.floating) and tol == math.inf:
        return math.inf
    try:
        return scalar(tol, "tol", nonnegative=True)
    except NonFiniteError:
        raise NonFiniteError(
            f"tol must be a number >= 0 or float('inf') (accept any result), got {tol!r}", value=tol
        ) from None


def _collocation_note(problem: TimeScalingProblem, history: list[dict[str, Any]]) -> str:
    """For a collocation plan that failed the check: its excess shrinks only in proportion to the stage width
    (the limits are imposed at each stage's start only, and the stage's constant s̈ carries on to its end),
    and how far the grid would have to go."""
    if problem.discretization != "collocation":
        return ""
    note = (
        "; collocation imposes the limits at the start of each stage only, so its excess shrinks only in "
        "proportion to the stage width"
    )
    excess = [h["worst_excess"] for h in history]
    if len(excess) >= 2 and 0.0 < excess[-1] < excess[-2]:
        note += f" (here ×{excess[-1] / excess[-2]:.2f} per doubling)"
    return note + ": discretization='interpolation' (the default) meets the limits on far coarser grids"


def time_optimal(
    dyn: Dynamics,
    waypoints: Path | ArrayLike,
    vel_limit: Any = None,
    acc_limit: Any = None,
    torque_limit: Any = None,
    grid: int | ArrayLike = 100,
    *,
    torque_margin: float = 0.0,
    tol: float = 1e-2,
    refine: bool = True,
    max_grid: int = 1600,
    oversample: int = 10,
    viscous_passes: int = 2,
    discretization: str = "interpolation",
    position_limit: str | None = "model",
) -> Trajectory:
    """The time-optimal rest-to-rest trajectory along waypoints within the given limits.

    The path speed is bounded by ṡ² ≤ 1e8 (:data:`~armctl.planning.problem.X_CAP`, toppra's own bound), so a move so
    short, or limits so loose, that its optimum would be faster than that gets the slower timing (a 1 nrad move at
    1 rad/s takes 2e-4 s).

    Parameters
    ----------
    dyn : Dynamics
        The arm (torques are τ = ``dyn.inverse_dynamics``, friction included).
    waypoints : array_like, shape (m, n), or Path
        Joint waypoints [rad] (through which a cubic :class:`SplinePath` is laid), or any
        :class:`~armctl.planning.Path`.
    vel_limit, acc_limit, torque_limit : optional
        [rad/s], [rad/s²], [N·m]: None (not imposed), ``"model"`` (the model's velocity / effort limits; not for
        acceleration), a scalar, an (n,) vector (symmetric) or (n, 2) bounds.
    grid : int or array_like, optional
        The number N of stages (evenly spaced in s), or the gridpoints (increasing from 0 to 1).
    torque_margin : float, optional
        Plan with the torque bounds shrunk by this fraction (0.1 → 90 % of the range), to leave room for feedback.
    tol : float, optional
        The largest normalised violation accepted by the dense check (0.01: 1 % of a limit).
    refine : bool, optional
        When ``tol`` is exceeded, double the grid (up to ``max_grid`` stages) and solve again; if it is still
        exceeded, raise :class:`~armctl.errors.SolverError` (pass ``tol=float("inf")`` to accept any result and read
        ``traj.check`` yourself).
    max_grid : int, optional
        The largest grid refinement tries.
    oversample : int, optional
        Dense-check samples per stage (≥ 10 recommended).
    viscous_passes : int, optional
        See :func:`solve_problem`.
    discretization : {"interpolation", "collocation"}, optional
        See :func:`~armctl.planning.problem.build_problem`.
    position_limit : {"model"} or None, optional
        ``"model"`` (default): the path must stay within the model's joint ranges — a timing cannot change the
        path, so one that leaves them (a waypoint outside, or the spline overshooting between two inside) raises
        :class:`~armctl.errors.InfeasibleError` naming the joint and where; None: not checked.

    Returns
    -------
    Trajectory
        With ``check`` (the dense verification) and ``info`` (grid, passes, the history of refinements, compute
        time).

    Raises
    ------
    InfeasibleError
        No timing meets the limits, naming the constraint and where it binds (in particular when the arm cannot be
        held at rest at the start or end pose: gravity and the Coulomb friction of the adjoining motion beyond the
        planned torque bound).
    SolverError
        A numerical failure, or the dense check still exceeds ``tol`` at ``max_grid``.
    ArmctlError
        Bad input, named.
    """
    t0 = time.perf_counter()
    if not isinstance(dyn, Dynamics):
        raise InvalidParameterError(f"dyn must be an armctl.Dynamics, got {type(dyn).__name__}", value=dyn)
    geo = as_path(waypoints, dyn.n)
    limits = joint_limits(dyn.model, vel_limit, acc_limit, torque_limit, torque_margin)
    if isinstance(position_limit, str) and position_limit == "model":
        check_range(dyn.model, geo)
    elif position_limit is not None:
        raise InvalidParameterError(
            f'position_limit must be "model" or None, got {position_limit!r}', value=position_limit
        )
    tol = _tolerance(tol)
    oversample = whole_number(oversample, "oversample", 1)
    max_grid = whole_number(max_grid, "max_grid", 2)
    viscous_passes = whole_number(viscous_passes, "viscous_passes", 1)
    history: list[dict[str, Any]] = []
    while True:
        _check_grid_memory(grid, dyn.n, oversample)
        problem = build_problem(dyn, geo, limits, grid, discretization)
        traj = solve_problem(problem, viscous_passes)
        check = check_trajectory(dyn, traj, limits, oversample)
        history.append({"grid": problem.grid, "duration": traj.duration, "worst_excess": check.worst_excess})
        if check.worst_excess <= tol:
            info = {**traj.info, "history": history, "compute_time": time.perf_counter() - t0}
            return Trajectory(geo, traj.timing, check, info)
        nxt = _refined(grid)
        if not refine or len(gridpoints(nxt)) - 1 > max_grid:
            worst = check.worst()
            raise SolverError(
                f"the time-optimal trajectory exceeds a limit by more than tol = {tol:g} on a grid of "
                f"{problem.grid} stages: {worst}"
                + ("" if refine else "; pass refine=True")
                + " (or raise max_grid or tol; the trajectory is in .result)"
                + _collocation_note(problem, history),
                value=check,
                problem=problem,
                result=Trajectory(geo, traj.timing, check, {"history": history}),
            )
        grid = nxt
