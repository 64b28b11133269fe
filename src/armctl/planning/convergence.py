"""Grid convergence of the time-optimal scaling against the analytic bang-bang duration.

On a straight line q(s) = q₀ + s Δ with symmetric joint limits v_j, a_j, the path limits are constants,
ṡ ≤ V = min_j v_j/|Δ_j| and |s̈| ≤ A = min_j a_j/|Δ_j|, and the minimum rest-to-rest time over s ∈ [0, 1] is the
bang-bang one:

    T = 2 √(1/A)          if V² ≥ A (the top speed is never reached: a triangle),
    T = 1/V + V/A         otherwise (a trapezoid).

:func:`grid_convergence` solves the same move on grids of increasing size and records the duration error and
the compute time; :func:`plot_convergence` draws both (matplotlib is imported there only). The error falls
until about 1e-6 and stays there: toppra's forward pass shaves every x_{i+1} by max(1e-8, 0.01 %) to keep it
inside the controllable set, which sets that floor.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, nonnegative_vector, readonly, scalar, whole_number
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError
from armctl.planning.path import LinePath


def bang_bang_duration(distance: float, v_max: float, a_max: float) -> float:
    """Minimum time to move a distance from rest to rest under velocity and acceleration limits.

    Parameters
    ----------
    distance : float
        [rad or m], ≥ 0.
    v_max : float
        |v| ≤ v_max [rad/s], > 0.
    a_max : float
        |a| ≤ a_max [rad/s²], > 0.

    Returns
    -------
    float
        The time [s]: triangular (2√(d/a)) or trapezoidal (d/v + v/a) profile.
    """
    d = abs(scalar(distance, "distance"))
    v, a = scalar(v_max, "v_max", positive=True), scalar(a_max, "a_max", positive=True)
    if v * v >= a * d:
        return 2.0 * math.sqrt(d / a)
    return d / v + v / a


def line_min_time(start: ArrayLike, end: ArrayLike, vel_limit: ArrayLike, acc_limit: ArrayLike) -> float:
    """Minimum rest-to-rest time along the straight joint-space line between two poses.

    Parameters
    ----------
    start, end : array_like, shape (n,)
        Distinct finite poses [rad], checked as :class:`LinePath` checks them.
    vel_limit, acc_limit : array_like
        Symmetric joint limits > 0 [rad/s, rad/s²]: scalars or (n,) vectors.

    Returns
    -------
    float
        [s].
    """
    line = LinePath(start, end)
    delta = np.abs(line.delta)
    moving = delta > 0
    v, a = (_positive_limit(x, line.n, name) for x, name in ((vel_limit, "vel_limit"), (acc_limit, "acc_limit")))
    return bang_bang_duration(1.0, float(np.min(v[moving] / delta[moving])), float(np.min(a[moving] / delta[moving])))


def _positive_limit(x: ArrayLike, n: int, name: str) -> FloatArray:
    lim = nonnegative_vector(x, n, name)
    if not lim.all():
        j = int(np.argmin(lim))
        raise InvalidParameterError(f"{name} of joint {j} is 0; a limit must be > 0, got {lim.tolist()}", value=x)
    return lim


@dataclass(frozen=True)
class ConvergenceStudy:
    """Durations [s], relative errors |T_N − T|/T and compute times [s] of the time-optimal scaling for
    each grid size N, against the analytic duration ``reference`` T."""

    grids: FloatArray
    durations: FloatArray
    errors: FloatArray
    compute_times: FloatArray
    reference: float


def grid_convergence(
    dyn: Dynamics,
    start: ArrayLike,
    end: ArrayLike,
    vel_limit: ArrayLike,
    acc_limit: ArrayLike,
    grids: Sequence[int] = (10, 20, 50, 100, 200, 500, 1000),
    repeat: int = 3,
    position_limit: str | None = "model",
) -> ConvergenceStudy:
    """Solve the straight-line move on each grid and compare with :func:`line_min_time`.

    Velocity and acceleration limits only; the compute time is the least of ``repeat`` calls (after one warm-up
    call, which pays for importing toppra).

    Parameters
    ----------
    dyn : Dynamics
        The arm.
    start, end : array_like, shape (n,)
        The line's ends [rad].
    vel_limit, acc_limit : array_like
        Symmetric joint limits > 0 [rad/s, rad/s²].
    grids : sequence of int, optional
        The stage counts.
    repeat : int, optional
        Timed calls per grid.
    position_limit : str or None, optional
        As in :func:`~armctl.planning.time_optimal`.

    Returns
    -------
    ConvergenceStudy
    """
    from armctl.planning.topp import time_optimal

    sizes = [whole_number(n, f"grids[{i}]", 2) for i, n in enumerate(np.ravel(np.asarray(grids, dtype=object)))]
    if not sizes:
        raise InvalidParameterError("grids must hold at least one grid size, got none", value=grids)
    repeat = whole_number(repeat, "repeat", 1)
    path = LinePath(start, end)
    ref = line_min_time(start, end, vel_limit, acc_limit)

    def solve(n: int) -> float:
        return time_optimal(
            dyn, path, vel_limit=vel_limit, acc_limit=acc_limit, grid=n, position_limit=position_limit
        ).duration

    solve(sizes[0])
    durations, times = [], []
    for n in sizes:
        best = math.inf
        for _ in range(repeat):
            t0 = time.perf_counter()
            duration = solve(n)
            best = min(best, time.perf_counter() - t0)
        times.append(best)
        durations.append(duration)
    dur = np.array(durations)
    return ConvergenceStudy(
        readonly(np.array(sizes, dtype=float)),
        readonly(dur),
        readonly(np.abs(dur - ref) / ref),
        readonly(np.array(times)),
        ref,
    )


def plot_convergence(study: ConvergenceStudy) -> Any:
    """A matplotlib Figure: relative duration error and compute time against the grid size (log-log).

    Parameters
    ----------
    study : ConvergenceStudy
        From :func:`grid_convergence`.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(9.0, 3.6), layout="constrained")
    ax_err, ax_time = fig.subplots(1, 2)
    ax_err.loglog(study.grids, np.maximum(study.errors, 1e-16), "o-")
    ax_err.set(
        xlabel="grid size N (stages)",
        ylabel="|T_N − T| / T",
        title=f"duration error (bang-bang T = {study.reference:.4g} s)",
    )
    ax_time.loglog(study.grids, 1e3 * study.compute_times, "s-", color="C1")
    ax_time.set(xlabel="grid size N (stages)", ylabel="compute time [ms]", title="time_optimal compute time")
    for ax in (ax_err, ax_time):
        ax.grid(True, which="both", alpha=0.3)
    return fig
