"""
Model views: bounds, stability conditions, the operational space
================================================================

Views of the dynamic model: bounds over the joint ranges, the stability conditions they give, the
operational-space model and the dynamic manipulability ellipsoid.

Run: ``python examples/model_views.py [--out DIR] [--show]`` (writes its figures under DIR, default example-out/)
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import armctl
from armctl.dynamics.manipulability_plot import plot_dynamic_manipulability
from armctl.tuning import (
    computed_torque_condition,
    model_bounds,
    pd_desired_gravity_condition,
    pid_condition,
    robust_inertia_estimate,
    sampled_data_condition,
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        "--out", type=Path, default=Path("example-out"), help="folder for the figures (default: example-out)"
    )
    parser.add_argument("--show", action="store_true", help="also show the figures in windows")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    dyn = armctl.Dynamics(armctl.models.planar_2r())

    # 1. λ_m, λ_M, k_g, k_C, k_M over the joint ranges: certified for this all-revolute arm, each bound
    #    beside the extreme met at a configuration
    bounds = model_bounds(dyn)
    print(bounds.summary())

    # 2. will these gains be stable? The textbook conditions, before any simulation
    print(pd_desired_gravity_condition(bounds, kp=1.2 * bounds.k_g))
    print(pid_condition(bounds, kp=1.5 * bounds.k_g, kd=800.0, ki=200.0))
    c, alpha = robust_inertia_estimate(bounds)
    print(f"constant inertia estimate M̂ = {c:.4g} I keeps ‖I − M⁻¹M̂‖ ≤ {alpha:.3f} over the ranges")
    ct = computed_torque_condition(bounds, c, kp=100.0, kd=20.0, max_acceleration=5.0)
    print(ct, f"\n  tracking error bound: {ct.details['error_bound']:.4f} rad")
    sd = sampled_data_condition(bounds, kp=100.0, kd=20.0, period=0.005, delay=1, inertia_estimate=c)
    print(sd)

    # 3. the operational-space model of the tip in the arm's plane (rows x and z)
    q, qd = np.array([0.3, 1.2]), np.array([0.5, -0.4])
    osm = dyn.operational_space_model(q, qd, rows="xz")
    print("Λ [kg] =\n", np.round(osm.Lambda, 3), "\nμ [N] =", np.round(osm.mu, 3), " p [N] =", np.round(osm.p, 3))

    # 4. the dynamic manipulability ellipsoid along a path, drawn and its measure printed
    path = np.column_stack([np.linspace(-0.2, 1.2, 8), np.linspace(2.3, 0.3, 8)])
    for qi in path[::3]:
        ell = dyn.dynamic_manipulability(qi, rows="xz")
        print(f"q = {np.round(qi, 2)}: semi-axes {np.round(ell.lengths, 5)} m/s² per N·m, measure {ell.measure:.3g}")
    ax = plot_dynamic_manipulability(dyn, path)
    path = args.out / "model_views.png"
    ax.figure.savefig(path, dpi=100)
    print("wrote", path)
    if args.show:
        plt.figure(ax.figure)  # a Figure of the library's, handed to pyplot to show
        plt.show()


if __name__ == "__main__":
    main()
