"""Speed of one operational-space QP control step on the Panda, against a bare proxsuite solve of the same QPs.

Run: ``python -m armctl.bench.osc_speed [--quick]``.

Set-up: pose task on the tool frame (weight 1) + posture task (weight 1e-3) + torque limits, one priority
level; the x = [q̈, τ] QP has 14 variables, 7 equality and 7 inequality rows. A sequence of states is made by
running the controller on its own model along a 10 cm circle (so the QPs change from step to step as in a
real loop); the circle is sampled at the control instants beforehand, so that a step pays a table lookup for
its target (still checked by the task) instead of the trajectory's own arithmetic. Measured, as medians of
interleaved rounds over that sequence (CPU time of this process):

* ``step``: ``controller(t, q, q̇, ref)`` — model terms, QP build, warm-started proxsuite solve, τ;
* ``bare_solve``: proxsuite dense ``update`` + ``solve`` of the very same QPs (H, g, A, b, C, l, u), warm-started
  from the previous one — the solver alone;
* ``closed_form``: the closed-form OSC baseline (Λ = (J M⁻¹ Jᵀ)⁻¹) on the same states;
* ``cold_solve``: proxsuite's one-shot ``dense.solve`` of the same QPs (no warm start), for reference.

Target: step / bare_solve ≤ 4.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import time
from typing import Any

import numpy as np

import armctl
from armctl.bench.timing import interleaved_samples
from armctl.controllers.osc import (
    ClosedFormOSC,
    FramePoseTask,
    OperationalSpaceQP,
    PostureTask,
    TorqueLimit,
)

TARGET_RATIO = 4.0


Q_HOME = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])


def _circle(center: np.ndarray, rot: np.ndarray, radius: float = 0.05, freq: float = 0.5) -> Any:
    """Pose trajectory t -> (pose, twist, acceleration): a horizontal circle through ``center``, constant
    orientation ``rot``."""
    w = 2 * math.pi * freq
    base = np.eye(4)
    base[:3, :3] = rot
    base[:3, 3] = center
    base[0, 3] -= radius

    def fn(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        c, s = math.cos(w * t), math.sin(w * t)
        pose = base.copy()
        pose[0, 3] += radius * c
        pose[1, 3] += radius * s
        twist = np.array([-radius * w * s, radius * w * c, 0.0, 0.0, 0.0, 0.0])
        acc = np.array([-radius * w * w * c, -radius * w * w * s, 0.0, 0.0, 0.0, 0.0])
        return pose, twist, acc

    return fn


class _Sampled:
    """A trajectory t -> (pose, twist, acceleration) sampled at the control instants k·dt (a table lookup per
    call), so that the step time counts the controller, not the user's trajectory code."""

    def __init__(self, fn: Any, dt: float, count: int) -> None:
        self.dt = dt
        self.table = [fn(k * dt) for k in range(count)]

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.table[min(round(t / self.dt), len(self.table) - 1)]


def states(count: int, dt: float = 1e-3) -> tuple[list[tuple[float, np.ndarray, np.ndarray]], Any, Any]:
    """``count`` (t, q, q̇) along the circle, from the controller acting on its own model (semi-implicit
    Euler), and the two controllers to time."""
    dyn = armctl.Dynamics(armctl.models.panda())
    pose0 = dyn.frame_pose(Q_HOME)
    pose = FramePoseTask(kp=400.0)
    pose.set_trajectory(_Sampled(_circle(pose0[:3, 3], pose0[:3, :3]), dt, count))
    posture = PostureTask(dyn.n, kp=100.0, weight=1e-3)
    ctrl = OperationalSpaceQP(dyn, [pose, posture], limits=[TorqueLimit()])
    closed = ClosedFormOSC(dyn, pose, posture)
    ref = armctl.Reference(Q_HOME)
    q, qd = Q_HOME.copy(), np.zeros(dyn.n)
    seq = []
    for k in range(count):
        t = k * dt
        seq.append((t, q.copy(), qd.copy()))
        tau = ctrl(t, q, qd, ref)
        qd = qd + dt * dyn.forward_dynamics(q, qd, tau)
        q = q + dt * qd
    ctrl.reset()
    return seq, ctrl, closed


def run(count: int = 400, rounds: int = 15, quick: bool = False) -> dict[str, Any]:
    """Measure; returns a dict of figures (seconds per step and ratios). ``quick``: 100 states, 5 rounds."""
    from proxsuite import proxqp

    if quick:
        count, rounds = 100, 5

    seq, ctrl, closed = states(count)
    ref = armctl.Reference(Q_HOME)
    qps = []
    for t, q, qd in seq:
        step = ctrl.build(t, q, qd, ref)
        qps.append(tuple(np.array(a) for a in step.arrays(0)))
    H, g, A, b, C, l, u = qps[0]  # noqa: E741
    bare = proxqp.dense.QP(H.shape[0], b.shape[0], l.shape[0])
    bare.settings.eps_abs = ctrl.solver.eps_abs
    bare.settings.eps_rel = 0.0
    bare.init(H, g, A, b, C, l, u)
    bare.solve()
    bare.settings.initial_guess = proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
    idx = {"step": 0, "bare": 0, "closed": 0, "cold": 0}

    def cycle(name: str) -> int:
        i = idx[name]
        idx[name] = (i + 1) % count
        return i

    def step() -> None:
        t, q, qd = seq[cycle("step")]
        ctrl(t, q, qd, ref)

    def bare_solve() -> None:
        bare.update(*qps[cycle("bare")])
        bare.solve()

    def closed_form() -> None:
        t, q, qd = seq[cycle("closed")]
        closed(t, q, qd, ref)

    def cold_solve() -> None:
        proxqp.dense.solve(*qps[cycle("cold")], eps_abs=ctrl.solver.eps_abs, eps_rel=0.0)

    # CPU time (process_time) rather than wall time: on a shared machine a long Python step is preempted more
    # often than a short C++ solve, which would inflate their ratio
    samples = interleaved_samples(
        {"step": step, "bare_solve": bare_solve, "closed_form": closed_form, "cold_solve": cold_solve},
        number=count,
        rounds=rounds,
        clock=time.process_time,
    )
    t = {k: statistics.median(v) for k, v in samples.items()}
    # ratios round by round (each round runs every candidate once, back to back), then their median
    ratios = [a / b for a, b in zip(samples["step"], samples["bare_solve"], strict=True)]
    closed_ratios = [a / b for a, b in zip(samples["closed_form"], samples["bare_solve"], strict=True)]
    q1, ratio, q3 = statistics.quantiles(ratios, n=4)
    iters = []
    for tt, q, qd in seq:
        ctrl(tt, q, qd, ref)
        iters.append(ctrl.last_solution.iterations)  # type: ignore[union-attr]
    return {
        "model": "panda",
        "qp_size": {"variables": int(H.shape[0]), "equalities": int(b.shape[0]), "inequalities": int(l.shape[0])},
        "states": count,
        "step_s": t["step"],
        "bare_solve_s": t["bare_solve"],
        "closed_form_s": t["closed_form"],
        "cold_solve_s": t["cold_solve"],
        "ratio": ratio,
        "ratio_iqr": (q1, q3),
        "closed_form_ratio": statistics.median(closed_ratios),
        "median_iterations": float(np.median(iters)),
    }


def report(fig: dict[str, Any]) -> str:
    us = 1e6
    s = fig["qp_size"]
    return "\n".join(
        [
            f"OSC QP step on {fig['model']}: pose + posture + torque limits; QP {s['variables']} variables, "
            f"{s['equalities']} equalities, {s['inequalities']} inequalities; {fig['states']} states, "
            f"median {fig['median_iterations']:.0f} solver iterations",
            f"  step (model terms + build + solve)  {fig['step_s'] * us:8.1f} µs",
            f"  bare proxsuite update+solve (warm)  {fig['bare_solve_s'] * us:8.1f} µs",
            f"  ratio step / bare                   {fig['ratio']:8.2f}   [{fig['ratio_iqr'][0]:.2f}, "
            f"{fig['ratio_iqr'][1]:.2f}] (median of per-round ratios [quartiles])",
            f"  closed-form OSC baseline            {fig['closed_form_s'] * us:8.1f} µs   "
            f"({fig['closed_form_ratio']:.2f} x bare)",
            f"  proxsuite one-shot dense.solve      {fig['cold_solve_s'] * us:8.1f} µs   (cold, for reference)",
        ]
    )


def beyond_targets(fig: dict[str, Any]) -> list[str]:
    """The step's ratio to the bare solve if above :data:`TARGET_RATIO` (the benchmark's tests check it)."""
    return [f"step / bare solve: {fig['ratio']:.2f} > {TARGET_RATIO:g}"] if fig["ratio"] > TARGET_RATIO else []


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer states and rounds")
    ap.add_argument("--json", help="also write the figures to this file")
    a = ap.parse_args(argv)
    fig = run(quick=a.quick)
    print(report(fig))
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(fig, fh, indent=2)


if __name__ == "__main__":
    main()
