"""
Collision detection without a force sensor, and where force control fails
=========================================================================

The Panda swings its tool into a wall it does not know of (``panda_collision``). A momentum observer estimates
the external joint torques from the model, the measured q, q̇ and the torque applied over the last period; it
detects the hit within milliseconds, its estimate of the tool force follows the simulator's true one, and the
reaction (gravity compensation, or a reflex that backs away) stops the push that computed torque alone keeps up.

Then force control with one period of delay on tables of growing stiffness: the critical force gain that the
sampled-data model predicts (``armctl.tuning.force_stability``) against the one a bisection over closed-loop runs
finds.

Run: python examples/collision_detection.py [--out DIR] [--show]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from armctl.bench.interaction_borders import predicted_force_gain, simulated_force_gain
from armctl.scenes import panda_collision


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=Path, default=Path("example-out"), help="where the figures go")
    parser.add_argument("--show", action="store_true", help="open the figures in a window")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    sc = panda_collision()
    dyn = sc.dynamics("plant")
    fig, (ax_f, ax_y) = plt.subplots(1, 2, figsize=(11, 3.8), layout="constrained")
    print("panda_collision: computed torque swings the tool into a wall at y = 0.12 m")
    for method in sc.methods:
        res = sc.run(method)
        m = sc.metrics(res, method, timing_rounds=0)
        print(
            f"  {method:12s} contact at {m['contact_at']:.3f} s, detected {1e3 * m['detection_delay']:.0f} ms later; "
            f"peak force {m['peak_force']:5.1f} N, 0.3 s after detection {m['force_after']:5.2f} N"
        )
        force = np.linalg.norm(res.contact_force_on_environment[:, 0], axis=1)
        (line,) = ax_f.plot(res.t, force, label=f"{method.replace('_', ' ')}: true")
        estimate = np.linalg.norm(np.nan_to_num(res.logs["wrench_estimate"][:, :3]), axis=1)
        ax_f.plot(res.t, estimate, ":", color=line.get_color(), label="  observer's estimate")
        y = [dyn.frame_pose(q)[1, 3] for q in res.q]
        ax_y.plot(res.t, y, color=line.get_color(), label=method.replace("_", " "))
    ax_f.set(xlabel="t [s]", ylabel="|f| at the tool [N]", title="force trace", xlim=(0.9, 1.8))
    ax_y.axhline(0.12, color="k", lw=0.8, ls="--", label="the wall")
    ax_y.set(xlabel="t [s]", ylabel="tool y [m]", title="motion")
    ax_f.legend(fontsize=7)
    ax_y.legend(fontsize=7)
    path = args.out / "collision_detection.png"
    fig.savefig(path)
    print(f"  figure: {path}")

    print("force control with one period of delay: critical force gain K_F* [m/N]")
    stiffnesses = [3e3, 3e4, 3e5]
    predicted, simulated = [], []
    for k_e in stiffnesses:
        pred = predicted_force_gain(k_e)
        sim = simulated_force_gain(k_e, pred, steps=4)["border"]
        predicted.append(pred)
        simulated.append(sim)
        print(f"  k_e = {k_e:7.0e} N/m: predicted {pred:.3e}, closed loop {sim:.3e} ({sim / pred - 1:+.1%})")
    fig, ax = plt.subplots(figsize=(5, 3.8), layout="constrained")
    ax.loglog(stiffnesses, predicted, "k--", label="sampled-data prediction")
    ax.loglog(stiffnesses, simulated, "o", label="closed-loop bisection")
    ax.set(xlabel="table stiffness k_e [N/m]", ylabel="K_F* [m/N]", title="force control: stability border")
    ax.legend()
    path = args.out / "force_control_border.png"
    fig.savefig(path)
    print(f"  figure: {path}")
    if args.show:
        plt.show()


if __name__ == "__main__":
    main()
