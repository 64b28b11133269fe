"""
Time-optimal planning, then tracking
====================================

Plan the fastest timing of a path through six Panda waypoints within velocity and torque limits
(TOPP-RA with the arm's own dynamics and friction, 10 % of the torque range left for feedback), compare it
with the classic uniform time scaling, then track it in closed loop against joint friction with stiction.

Run: ``python examples/topp_tracking.py [--out DIR] [--show]`` (writes its figures under DIR, default example-out/)
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import armctl
from armctl.controllers import ComputedTorque
from armctl.planning import PolynomialTiming, SplinePath, Trajectory, time_optimal, uniform_time_scaling
from armctl.scenes.panda_topp import WAYPOINTS, panda_with_friction
from armctl.sim import simulate


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        "--out", type=Path, default=Path("example-out"), help="folder for the figures (default: example-out)"
    )
    parser.add_argument("--show", action="store_true", help="also show the figures in windows")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    model = panda_with_friction()
    dyn = armctl.Dynamics(model)
    traj = time_optimal(dyn, WAYPOINTS, vel_limit="model", torque_limit="model", grid=100, torque_margin=0.1)
    print(
        f"time-optimal duration {traj.duration:.3f} s; dense check: worst normalised excess "
        f"{traj.check.worst_excess:.2e} (≤ 0 means within every limit)"
    )
    # the classic baseline: the same spline with a quintic rest-to-rest timing, uniformly scaled to fit
    base = uniform_time_scaling(
        dyn,
        Trajectory(SplinePath(WAYPOINTS), PolynomialTiming(1.0)),
        vel_limit="model",
        torque_limit="model",
        torque_margin=0.1,
    )
    print(
        f"uniform time scaling: {base.duration:.3f} s, bound by {model.joint_names[base.joint]} {base.kind} "
        f"(TOPP is {base.duration / traj.duration:.2f}× faster)"
    )
    wn = np.array([30.0, 30.0, 30.0, 30.0, 60.0, 60.0, 100.0])  # higher on the light wrist joints
    controller = ComputedTorque(dyn, wn**2, 2 * wn)
    res = simulate(dyn, controller, traj, duration=round(traj.duration + 0.3, 3), q0=WAYPOINTS[0])
    err = np.abs(res.error)  # the reference the controller was given, minus q, at every sample
    usage = np.abs(res.tau_applied).max(axis=0) / model.effort_limit
    print(
        f"closed loop: diverged {res.diverged}; max tracking error {err.max() * 1e3:.2f} mrad; peak torque "
        f"{usage.max():.0%} of the limit ({model.joint_names[int(usage.argmax())]})"
    )
    fig = res.plot(("qd", "error", "tau_applied"))  # a matplotlib Figure: the reference overlaid, the joints named
    path = args.out / "topp_tracking.png"
    fig.savefig(path, dpi=100)
    print("wrote", path)
    if args.show:
        plt.figure(fig)  # a Figure of the library's, handed to pyplot to show
        plt.show()


if __name__ == "__main__":
    main()
