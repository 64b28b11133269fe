"""
A contact program from scratch: press on a table with 10 N
==========================================================

The whole recipe for force control with the operational-space QP, without a scene: a table (a compliant
:class:`~armctl.sim.Plane`), a :class:`~armctl.controllers.osc.Contact` declared off and switched on when the tool
touches, a :class:`~armctl.controllers.osc.ContactForceTask` that ramps the normal force to 10 N, a
:class:`~armctl.sim.ForceSensor` at the tool, the simulation, and plots of the normal force, the sensor and the
tool's position error.

Signs: the contact's force, its task's target and ``res.contact_force_on_robot`` are the force the table exerts
on the arm (+10 N along the table's normal when pressing); ``res.wrench``, ``res.sensor`` and
``res.contact_force_on_environment`` are what the arm exerts (−10 N).

Run: ``python examples/contact_recipe.py [--out DIR] [--show]`` (writes its figures under DIR, default
example-out/)
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import armctl
from armctl.controllers import Controller
from armctl.controllers.osc import Contact, ContactForceTask, FramePoseTask, OperationalSpaceQP, PostureTask
from armctl.sim import Forces, ForceSensor, KelvinVoigt, Plane, Sensing, simulate

FORCE = 10.0  # the normal force wanted [N]


class PressOnTouch(Controller):
    """Lower the tool at 2 cm/s; when it reaches the table, switch the contact on, free the pose task's vertical
    row (the force task takes it over) and ramp the normal force to FORCE in 0.2 s."""

    def __init__(self, dyn: armctl.Dynamics, z_table: float, start: np.ndarray) -> None:
        super().__init__(dyn)
        self.z_table, self.start = z_table, start
        self.pose = FramePoseTask(kp=400.0)
        self.pose.set_trajectory(self.target)
        # off until the tool touches; "sliding": the tangential force is the table's Coulomb friction (μ as the
        # table's), not a force the QP may choose (a "fixed" contact's, which a compliant table gives only by creeping)
        self.contact = Contact(mode="sliding", mu=0.3, active=False)
        self.force = ContactForceTask(self.contact, 0.0, weight=1.0)  # on the normal force (sliding: normal_only)
        posture = PostureTask(dyn.n, kp=25.0, priority=1)
        self.qp = OperationalSpaceQP(dyn, [self.pose, self.force, posture], contacts=[self.contact])
        self.touched: float | None = None

    def target(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        pose, twist = self.start.copy(), np.zeros(6)
        pose[2, 3] = max(self.start[2, 3] - 0.02 * t, self.z_table - 0.01)
        twist[2] = -0.02 if pose[2, 3] > self.z_table - 0.01 else 0.0
        return pose, twist, np.zeros(6)

    def compute(self, t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        if self.touched is None and self.dynamics.frame_pose(q)[2, 3] <= self.z_table:
            self.touched = t
            self.contact.active = True
            self.pose.weight = [1, 1, 0, 1, 1, 1]  # the force task holds the normal direction
        if self.touched is not None:
            self.force.set_target(FORCE * min(1.0, (t - self.touched) / 0.2))
        tau = self.qp.compute(t, q, qd, ref)
        self.last_log = dict(self.qp.last_log)
        return tau

    def reset(self) -> None:
        super().reset()
        self.qp.reset()
        self.touched, self.contact.active, self.pose.weight = None, False, 1.0
        self.force.set_target(0.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        "--out", type=Path, default=Path("example-out"), help="folder for the figures (default: example-out)"
    )
    parser.add_argument("--show", action="store_true", help="also show the figures in windows")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    model = armctl.models.panda()
    dyn = armctl.Dynamics(model)
    q0 = model.named_poses["ready"]  # hand pointing down
    start = dyn.frame_pose(q0)
    z_table = float(start[2, 3]) - 0.005  # the table 5 mm below the tool
    table = Plane(KelvinVoigt(2e4, 50.0), normal=(0, 0, 1), point=(0, 0, z_table), friction=0.3)

    ctrl = PressOnTouch(dyn, z_table, start)
    res = simulate(
        model,
        ctrl,
        armctl.Reference.hold(q0),
        1.0,
        q0=q0,
        dt=2e-4,
        forces=Forces(environment=table),
        sensing=Sensing(sensors=[ForceSensor()]),
    )
    print(res)

    normal = res.contact_force_on_robot[:, 0] @ table.normal  # the table's push on the arm [N]
    print(f"touched at t = {ctrl.touched:.3f} s; normal force at the end {normal[-1]:.2f} N (wanted {FORCE:g} N)")
    print(f"the sensor reads f_z = {res.sensor[-1, 0, 2]:.2f} N in the hand's axes (the arm's push on the table)")

    fig, ax = plt.subplots(figsize=(8, 3), layout="constrained")
    ax.plot(res.t, normal, label="normal force on the arm")
    ax.axhline(FORCE, color="k", lw=0.8, ls="--", label=f"target {FORCE:g} N")
    ax.axvline(ctrl.touched, color="gray", lw=0.8, ls=":", label="touch: contact on")
    ax.set(xlabel="t [s]", ylabel="normal force [N]", title="Panda pressing on a table")
    ax.legend(loc="lower right")
    paths = [args.out / "contact_recipe_normal_force.png", args.out / "contact_recipe_run.png"]
    fig.savefig(paths[0], dpi=100)
    res.plot(("contact_force", "sensor", "position_error", "orientation_error")).savefig(paths[1], dpi=100)
    for path in paths:
        print("wrote", path)
    if args.show:
        plt.show()


if __name__ == "__main__":
    main()
