"""Time scaling of paths: TOPP-RA on the arm's own dynamics, and the classic uniform time scaling.

    traj = armctl.planning.time_optimal(dyn, waypoints, vel_limit="model", torque_limit="model", grid=100)
    traj.duration, traj(t) -> Reference, traj.sample(dt=1e-3), traj.check  (the dense verification)

Paths (:class:`SplinePath`, :class:`LinePath`) are geometry q(s), s ∈ [0, 1]; timing laws s(t)
(:mod:`~armctl.planning.timing`) make them :class:`Trajectory` objects. :func:`build_problem` exposes the
discretised problem before it is solved (:func:`solve_problem`); :func:`time_optimal` does both, verifies the
result densely and refines the grid if needed. :func:`uniform_time_scaling` is Hollerbach's baseline.
"""

from armctl.planning.convergence import bang_bang_duration, grid_convergence, line_min_time, plot_convergence
from armctl.planning.limits import Bounds, JointLimits, joint_limits
from armctl.planning.path import LinePath, Path, SplinePath
from armctl.planning.problem import RowLabel, TimeScalingProblem, build_problem
from armctl.planning.time_scaling import UniformScaling, uniform_time_scaling
from armctl.planning.timing import GridTiming, PolynomialTiming, ScaledTiming, Timing
from armctl.planning.topp import check_range, solve_problem, time_optimal
from armctl.planning.trajectory import Samples, Trajectory
from armctl.planning.verify import LimitCheck, LimitReport, check_trajectory

__all__ = [
    "Bounds",
    "GridTiming",
    "JointLimits",
    "LimitCheck",
    "LimitReport",
    "LinePath",
    "Path",
    "PolynomialTiming",
    "RowLabel",
    "Samples",
    "ScaledTiming",
    "SplinePath",
    "TimeScalingProblem",
    "Timing",
    "Trajectory",
    "UniformScaling",
    "bang_bang_duration",
    "build_problem",
    "check_range",
    "check_trajectory",
    "grid_convergence",
    "joint_limits",
    "line_min_time",
    "plot_convergence",
    "solve_problem",
    "time_optimal",
    "uniform_time_scaling",
]
