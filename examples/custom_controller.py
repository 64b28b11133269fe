"""
Writing your own controller
===========================

A controller written in user code, simulated unchanged by armctl.

Subclass ``armctl.controllers.Controller`` and implement ``compute(t, q, qd, ref) -> tau``. The same object
runs in ``armctl.sim.simulate`` or in your own 1 kHz loop. This one is a PD with gravity and a model-based
feedforward of the reference acceleration (a common industrial compromise between PD+gravity and computed
torque): τ = M(q_d) q̈_d + g(q) + K_p e + K_d ė. It logs its feedback share each step.

Run: ``python examples/custom_controller.py [--out DIR] [--show]`` (writes its figures under DIR, default example-out/)
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import armctl
from armctl.controllers import Controller
from armctl.references import Sinusoid
from armctl.sim import simulate


class FeedforwardPD(Controller):
    def __init__(self, dynamics: armctl.Dynamics, kp: float, kd: float) -> None:
        super().__init__(dynamics)
        self.kp, self.kd = kp, kd

    def compute(self, t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        feedback = self.kp * (ref.q - q) + self.kd * (ref.qd - qd)
        feedforward = self.dynamics.mass_matrix(ref.q) @ ref.qdd + self.dynamics.gravity_torque(q)
        self.last_log = {"feedback": feedback}
        return feedforward + feedback


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        "--out", type=Path, default=Path("example-out"), help="folder for the figures (default: example-out)"
    )
    parser.add_argument("--show", action="store_true", help="also show the figures in windows")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    model = armctl.models.planar_2r()
    plant = armctl.Dynamics(model.with_friction(viscous=5.0, coulomb=2.0))  # the truth has friction
    controller = FeedforwardPD(armctl.Dynamics(model), kp=20000.0, kd=2000.0)
    reference = Sinusoid(center=[0.3, -0.4], amplitude=[0.4, 0.5], frequency=[0.5, 0.7])
    res = simulate(plant, controller, reference, duration=4.0)
    err = res.error  # reference.q − q at every sample
    print(
        f"diverged: {res.diverged}; RMS tracking error {np.sqrt((err**2).mean()):.2e} rad, "
        f"max {np.abs(err).max():.2e} rad; peak feedback torque {np.abs(res.logs['feedback']).max():.1f} N·m"
    )
    fig = res.plot(("q", "error", "tau_applied"))  # a matplotlib Figure: the reference overlaid, the joints named
    path = args.out / "custom_controller.png"
    fig.savefig(path, dpi=100)
    print("wrote", path)
    if args.show:
        plt.figure(fig)  # a Figure of the library's, handed to pyplot to show
        plt.show()


if __name__ == "__main__":
    main()
