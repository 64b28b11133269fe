"""
Pressing and sliding on a table with the operational-space QP
=============================================================

Contact with the operational-space QP: the Panda approaches a table, presses with 10 N and slides 10 cm
against surface friction (μ = 0.3, compliant table), with the QP regulating the normal force through a
sliding contact — and Khatib's closed-form controller doing the same motion by pose stiffness alone.

Run: ``python examples/contact_qp.py [--out DIR] [--show]`` (writes its figures under DIR, default example-out/)
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from armctl.scenes import scene


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        "--out", type=Path, default=Path("example-out"), help="folder for the figures (default: example-out)"
    )
    parser.add_argument("--show", action="store_true", help="also show the figures in windows")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    sc = scene("panda_contact")
    fig, ax = plt.subplots(figsize=(8, 3.5), layout="constrained")
    for method in sc.methods:
        res = sc.run(method)
        m = sc.metrics(res, method)
        fn = res.contact_force_on_robot[:, 0, 2]
        late = res.t >= 1.2
        # the QP regulates the force towards 10 N; the closed form has no force target: its force is whatever
        # its pose stiffness gives, pushing its target 1 cm below the table
        aim = "target 10 N" if method == "osc_qp" else "no force target; 10 N wanted"
        print(
            f"{method:16s} normal force after settling {fn[late].min():5.2f}…{fn[late].max():5.2f} N "
            f"({aim}, RMS error {m['force_rms_error']:.2f} N); in-plane position RMS "
            f"{m['rms_error'] * 1e3:.2f} mm; contact lost: {m['contact_lost']}; peak torque "
            f"{np.max(np.abs(res.tau_applied) / sc.plant.effort_limit):.0%} of the limit"
        )
        ax.plot(res.t, fn, label=method.replace("_", " "))
    ax.axhline(10.0, color="k", lw=0.8, ls="--", label="10 N wanted")
    ax.set(xlabel="t [s]", ylabel="normal force on the table [N]", title="Panda pressing and sliding on a table")
    ax.legend()
    path = args.out / "contact_qp.png"
    fig.savefig(path, dpi=100)
    print("wrote", path)
    if args.show:
        plt.show()


if __name__ == "__main__":
    main()
