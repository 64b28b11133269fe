"""
Strict priorities against weights in the operational-space QP
=============================================================

The Panda moves its tool 25 cm along a straight line while a posture task asks every joint to stay at the
ready pose. The two tasks conflict: 6 pose rows and 7 posture rows on 7 joints. Three controllers share the
same tasks and gains:

* **strict priorities**: the pose task at priority 0, the posture at priority 1 — the posture gets only what
  the pose leaves free (the arm's one redundant direction), and the tool follows its target as if the posture
  task were not there;
* **one level, light posture**: both at priority 0, the posture weighted 10⁻³ — a compromise that favours the
  pose;
* **one level, equal weights**: both at priority 0 with weight 1 — the pose gives way to the posture.

Each controller runs in closed loop at 1 kHz on the Panda's own model; the chart shows the tool's position
error and the posture error over time, and the script prints each task's residual J q̈ + J̇ q̇ − ẍ* at the end of
the move (``ctrl.last_solution.residuals``) and each level's status.

Run: ``python examples/osc_priorities.py [--out DIR] [--show]`` (writes its figures under DIR, default example-out/)
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import armctl
from armctl.controllers.osc import FramePoseTask, OperationalSpaceQP, PostureTask, TorqueLimit
from armctl.sim import simulate

Q_READY = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
MOVE = np.array([0.0, 0.25, -0.10])  # [m], world axes
DURATION, T_MOVE = 2.0, 1.5


def line_target(start: np.ndarray) -> Callable[[float], tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """The tool pose along a minimum-jerk straight line: t → (pose, twist, acceleration)."""

    def at(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        s = min(max(t / T_MOVE, 0.0), 1.0)
        shape = 10 * s**3 - 15 * s**4 + 6 * s**5
        rate = (30 * s**2 - 60 * s**3 + 30 * s**4) / T_MOVE if 0.0 < t < T_MOVE else 0.0
        accel = (60 * s - 180 * s**2 + 120 * s**3) / T_MOVE**2 if 0.0 < t < T_MOVE else 0.0
        pose = start.copy()
        pose[:3, 3] += shape * MOVE
        return pose, np.concatenate([rate * MOVE, np.zeros(3)]), np.concatenate([accel * MOVE, np.zeros(3)])

    return at


def controller(dyn: armctl.Dynamics, levels: bool, posture_weight: float) -> OperationalSpaceQP:
    pose = FramePoseTask(kp=100.0, name="pose")
    pose.set_trajectory(line_target(dyn.frame_pose(Q_READY)))
    posture = PostureTask(dyn.n, kp=100.0, weight=posture_weight, priority=1 if levels else 0, name="posture")
    posture.set_target(Q_READY)
    return OperationalSpaceQP(dyn, [pose, posture], limits=[TorqueLimit()])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        "--out", type=Path, default=Path("example-out"), help="folder for the figures (default: example-out)"
    )
    parser.add_argument("--show", action="store_true", help="also show the figures in windows")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    dyn = armctl.Dynamics(armctl.models.panda())
    start = dyn.frame_pose(Q_READY)
    target = line_target(start)
    cases = {
        "strict priorities": controller(dyn, levels=True, posture_weight=1.0),
        "one level, posture weight 1e-3": controller(dyn, levels=False, posture_weight=1e-3),
        "one level, equal weights": controller(dyn, levels=False, posture_weight=1.0),
    }
    fig, (ax_pose, ax_posture) = plt.subplots(1, 2, figsize=(10, 3.8), layout="constrained")
    for name, ctrl in cases.items():
        res = simulate(dyn, ctrl, armctl.Reference(Q_READY), DURATION, q0=Q_READY)
        tool = np.array([dyn.frame_pose(q)[:3, 3] for q in res.q])
        wanted = np.array([target(t)[0][:3, 3] for t in res.t])
        pose_error = np.linalg.norm(wanted - tool, axis=1)
        posture_error = np.linalg.norm(res.q - Q_READY, axis=1)
        sol = ctrl.last_solution
        print(
            f"{name:31s} tool error: max {pose_error.max() * 1e3:6.2f} mm, final {pose_error[-1] * 1e3:6.2f} mm; "
            f"posture ‖q − q_ready‖ final {posture_error[-1]:.3f} rad; levels {sol.level_status}"
        )
        print(
            f"{'':31s} residuals at the end: pose {np.linalg.norm(sol.residuals['pose']):.2e}, "
            f"posture {np.linalg.norm(sol.residuals['posture']):.2e}"
        )
        ax_pose.plot(res.t, pose_error * 1e3, label=name)
        ax_posture.plot(res.t, posture_error, label=name)
    ax_pose.set(xlabel="t [s]", ylabel="tool position error [mm]", yscale="symlog", title="pose task")
    ax_posture.set(xlabel="t [s]", ylabel="‖q − q_ready‖ [rad]", title="posture task")
    ax_pose.legend(fontsize=8)
    fig.suptitle("Panda: a 25 cm tool move against a posture task")
    path = args.out / "osc_priorities.png"
    fig.savefig(path, dpi=100)
    print("wrote", path)
    if args.show:
        plt.show()


if __name__ == "__main__":
    main()
