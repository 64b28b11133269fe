"""
Interaction control: pressing and wiping with impedance, admittance and force control
=====================================================================================

The Panda presses 10 N on a table that is 1 cm lower than its controllers believe (``panda_press``), then wipes
a table that slopes down by 2° along a 15 cm path against surface friction (``panda_wipe``). Cartesian impedance
and admittance press with the force their stiffness gives at the depth they reach — the closed form
k_e k_d/(k_e + k_d)·(δ_c − Δz), half the force wanted here; parallel force/position and force control read a
force/torque sensor and find 10 N wherever the table is. On the sloping table force control and parallel
force/position control keep the force within about 1 N where impedance loses 2.7 N, and parallel force/position
control pays for the surface friction with 1.5 cm of path error.

Run: python examples/interaction_control.py [--out DIR] [--show]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib.pyplot as plt

from armctl.scenes import normal_force, panda_press, panda_wipe
from armctl.scenes.panda_press import TABLE_STIFFNESS


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=Path, default=Path("example-out"), help="where the figures go")
    parser.add_argument("--show", action="store_true", help="open the figures in a window")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    press = panda_press(offset=0.01)
    fig, (ax_f, ax_z) = plt.subplots(1, 2, figsize=(10, 3.5), layout="constrained")
    print(f"panda_press: the table is {(press.z_believed - press.z_table) * 100:.0f} cm lower than believed")
    for method, style in zip(press.methods, ("-", "--", "-"), strict=True):  # impedance and admittance coincide
        res = press.run(method)
        m = press.metrics(res, method, timing_rounds=0)
        line = f"  {method:24s} force at rest {m['force_at_rest']:6.2f} N (10 N wanted)"
        if method != "parallel_force_position":
            kz = float(press.gains(method)["stiffness"][2])
            series = TABLE_STIFFNESS * kz / (TABLE_STIFFNESS + kz)
            predicted = series * (press.force / series - (press.z_believed - press.z_table))
            line += f"; closed form k_e k_d/(k_e + k_d)(δ_c − Δz) = {predicted:.2f} N"
        print(line)
        ax_f.plot(res.t, normal_force(res), style, label=method.replace("_", " "))
        ax_z.plot(res.t, (press.tool_path(res)[:, 2] - press.z_table) * 1e3, style, label=method.replace("_", " "))
    ax_f.axhline(press.force, color="k", lw=0.8, ls="--")
    ax_f.set(xlabel="t [s]", ylabel="normal force [N]", title="force trace (sensor)")
    ax_z.axhline(press.z_believed * 1e3 - press.z_table * 1e3, color="grey", lw=0.8, ls=":", label="believed table")
    ax_z.set(xlabel="t [s]", ylabel="tool height above the table [mm]", title="motion")
    ax_f.legend()
    ax_z.legend()
    fig.suptitle("panda_press: a table 1 cm lower than believed")
    path = args.out / "interaction_press.png"
    fig.savefig(path)
    print(f"  figure: {path}")

    wipe = panda_wipe(slope=2.0)
    fig, (ax_f, ax_p) = plt.subplots(1, 2, figsize=(10, 3.5), layout="constrained")
    print("panda_wipe: 10 N over 15 cm, table sloping 2° (unknown), surface friction μ = 0.3")
    for method, style in zip(wipe.methods, ("-", "--", "-"), strict=True):
        res = wipe.run(method)
        m = wipe.metrics(res, method, timing_rounds=0)
        print(
            f"  {method:24s} force over the slide {m['force_min']:5.2f}…{m['force_max']:5.2f} N, RMS error "
            f"{m['rms_error']:.2f} N; path RMS error {m['path_rms_error'] * 1e3:.2f} mm"
        )
        path_xy = wipe.tool_path(res)
        ax_f.plot(res.t, normal_force(res, wipe.normal), style, label=method.replace("_", " "))
        ax_p.plot(res.t, path_xy[:, 0], style, label=method.replace("_", " "))
    ax_f.axhline(wipe.force, color="k", lw=0.8, ls="--")
    ax_f.set(xlabel="t [s]", ylabel="normal force [N]", title="force trace (sensor)")
    target = wipe.path(0.0)
    ax_p.plot(res.t, [target(float(t))[0][0, 3] for t in res.t], "k--", lw=0.8, label="path")
    ax_p.set(xlabel="t [s]", ylabel="tool x [m]", title="motion along the table")
    ax_f.legend()
    ax_p.legend()
    fig.suptitle("panda_wipe: wiping a sloping table with friction")
    path = args.out / "interaction_wipe.png"
    fig.savefig(path)
    print(f"  figure: {path}")
    if args.show:
        plt.show()


if __name__ == "__main__":
    main()
