"""Benchmark: the cost of ``armctl.planning.time_optimal`` against toppra called directly.

Panda, 6 waypoints, 100 grid intervals, velocity and torque limits (the model's). The reference is what a user
would write with toppra alone: a ``SplineInterpolator`` through the same waypoints (same knots), a
``JointVelocityConstraint`` and a ``SecondOrderConstraint.joint_torque_constraint`` whose inverse dynamics is a
raw ``pinocchio.rnea`` callback, ``TOPPRA(..., solver_wrapper="seidel")`` and ``compute_trajectory(0, 0)``.
armctl's call does more — it builds the constraints from its Dynamics (friction terms included), checks its
inputs, verifies the result on 10 samples per stage with the full inverse dynamics (:data:`TARGET` on the ratio is
the benchmark's own check). Rounds alternate between the two so that a noisy shared machine slows both alike;
medians are reported.

Run: ``python -m armctl.bench.topp_speed [--rounds R] [--number K] [--chart PATH]``; with ``--chart`` it also
writes the grid-convergence chart (duration error against the analytic bang-bang duration, and compute time,
against the grid size) of a straight-line panda move with velocity and acceleration limits.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

import numpy as np

TARGET = 1.2


def waypoints(model: Any, count: int = 6, seed: int = 0) -> np.ndarray:
    """``count`` random waypoints in the middle half of the panda's joint ranges, drawn again (from the next
    seed) until the spline through them stays within the ranges (the first draw's overshoots joint 6's)."""
    from armctl.errors import InfeasibleError
    from armctl.planning import SplinePath, check_range

    mid, half = 0.5 * (model.upper + model.lower), 0.5 * (model.upper - model.lower)
    for attempt in range(100):
        w = mid + 0.5 * half * np.random.default_rng(seed + attempt).uniform(-1.0, 1.0, (count, model.n))
        try:
            check_range(model, SplinePath(w))
        except InfeasibleError:
            continue
        return w  # type: ignore[no-any-return]
    raise RuntimeError(f"no {count} random waypoints from seeds {seed}…{seed + 99} give a path within the ranges")


def cases(grid: int = 100) -> tuple[Callable[[], float], Callable[[], float]]:
    """(armctl, toppra-direct) callables, each returning the duration it found."""
    import pinocchio as pin
    import toppra as ta
    import toppra.algorithm as algo
    import toppra.constraint as tc

    import armctl
    from armctl.planning import SplinePath, time_optimal

    model = armctl.models.panda()
    dyn = armctl.Dynamics(model)
    w = waypoints(model)
    knots = SplinePath(w).breakpoints  # the same spline for both
    n = model.n
    vlim = np.stack([-model.velocity_limit, model.velocity_limit], axis=1)
    tlim = np.stack([-model.effort_limit, model.effort_limit], axis=1)
    pm, pd = dyn.pin_model, dyn.pin_data
    grid_s = np.linspace(0.0, 1.0, grid + 1)

    def direct() -> float:
        path = ta.SplineInterpolator(knots, w)
        pc_vel = tc.JointVelocityConstraint(vlim)
        pc_tau = tc.SecondOrderConstraint.joint_torque_constraint(
            lambda q, qd, qdd: pin.rnea(pm, pd, q, qd, qdd), tlim, np.zeros(n), discretization_scheme=1
        )
        inst = algo.TOPPRA([pc_vel, pc_tau], path, gridpoints=grid_s, solver_wrapper="seidel")
        traj = inst.compute_trajectory(0.0, 0.0)
        return float(traj.duration)

    def wrapped() -> float:
        return time_optimal(dyn, w, vel_limit="model", torque_limit="model", grid=grid).duration

    return wrapped, direct


def measure(rounds: int = 15, number: int = 5, grid: int = 100) -> dict[str, float]:
    """Median seconds per call of both, in alternating rounds, and their ratio."""
    from armctl.bench.timing import interleaved

    wrapped, direct = cases(grid)
    med = interleaved({"armctl": wrapped, "toppra": direct}, number, rounds)
    return {
        "armctl_s": med["armctl"],
        "toppra_s": med["toppra"],
        "ratio": med["armctl"] / med["toppra"],
        "duration_armctl": wrapped(),
        "duration_toppra": direct(),
    }


def convergence_chart(path: str) -> Any:
    """Write the grid-convergence chart to ``path`` and return the study."""
    import armctl
    from armctl.planning import grid_convergence, plot_convergence

    dyn = armctl.Dynamics(armctl.models.panda())
    start = np.array([0.0, 0.0, 0.0, -1.5, 0.0, 1.5, 0.0])  # within the joint ranges, as the move below
    end = start + np.array([1.0, -0.5, 0.3, 0.2, 1.0, 0.5, -0.7])
    study = grid_convergence(dyn, start, end, 1.0, 2.3, grids=(10, 20, 50, 100, 200, 500, 1000, 2000))
    plot_convergence(study).savefig(path, dpi=120)
    return study


def main(argv: list[str] | None = None) -> dict[str, float]:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rounds", type=int, default=15)
    p.add_argument("--number", type=int, default=5)
    p.add_argument("--grid", type=int, default=100)
    p.add_argument("--chart", default=None, help="also write the grid-convergence chart (PNG) here")
    args = p.parse_args(argv)
    if args.chart:
        study = convergence_chart(args.chart)
        print(f"grid convergence (bang-bang T = {study.reference:.6f} s), chart in {args.chart}")
        for n, err, t in zip(study.grids, study.errors, study.compute_times, strict=True):
            print(f"  N = {int(n):5d}   |T_N - T|/T = {err:.2e}   {1e3 * t:7.2f} ms")
    r = measure(args.rounds, args.number, args.grid)
    print(
        f"panda, 6 waypoints, {args.grid} grid intervals, velocity + torque limits "
        f"(median of {args.rounds} rounds x {args.number} calls)"
    )
    print(f"  armctl.planning.time_optimal : {1e3 * r['armctl_s']:8.2f} ms   duration {r['duration_armctl']:.4f} s")
    print(f"  toppra direct (pinocchio.rnea): {1e3 * r['toppra_s']:8.2f} ms   duration {r['duration_toppra']:.4f} s")
    print(f"  ratio {r['ratio']:.3f}")
    return r


if __name__ == "__main__":
    main()
