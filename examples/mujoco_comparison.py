"""
armctl and MuJoCo side by side
==============================

armctl and MuJoCo side by side: an MJCF arm read into armctl, the same closed loop on both simulators, joint
friction held below breakaway, and the Panda pressing its collision meshes on a table of a MuJoCo scene.

Needs MuJoCo: ``pip install "armctl[mujoco]"``.

Run: ``python examples/mujoco_comparison.py [--out DIR]``
"""

from __future__ import annotations

import argparse
from pathlib import Path

import mujoco
import numpy as np

import armctl
from armctl.controllers import ComputedTorque, Controller
from armctl.references import Sinusoid
from armctl.sim import MujocoPlant, simulate

ARM = """
<mujoco model="two_link">
  <compiler angle="radian"/>
  <worldbody>
    <body name="upper" pos="0 0 0.5">
      <joint name="shoulder" axis="0 1 0" damping="0.2" armature="0.01" frictionloss="0.1" range="-2 2"/>
      <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.04"/>
      <body name="fore" pos="0.4 0 0">
        <joint name="elbow" axis="0 1 0" damping="0.1" armature="0.005" frictionloss="0.05"/>
        <inertial pos="0.15 0 0.01" mass="1.2" fullinertia="0.002 0.012 0.011 0 0.0004 0"/>
        <site name="tip" pos="0.3 0 0"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor joint="shoulder" gear="20" ctrlrange="-3 3"/>
    <motor joint="elbow" gear="10" ctrlrange="-3 3"/>
  </actuator>
</mujoco>
"""


class PressDown(Controller):
    """τ = g(q) + Jᵀ f + K_p (q_r − q) − K_d q̇: gravity compensation, a force f [N] at the tool, a soft posture."""

    def __init__(self, dyn: armctl.Dynamics, force: np.ndarray, kp: float, kd: float) -> None:
        super().__init__(dyn)
        self.force, self.kp, self.kd = force, kp, kd

    def compute(self, t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        jac = self.dynamics.jacobian(q)[:3]
        return self.dynamics.gravity_torque(q) + jac.T @ self.force + self.kp * (ref.q - q) - self.kd * qd


def mjcf_in() -> None:
    model = armctl.RobotModel.from_mjcf(ARM, tool_frame="tip")
    print(model)
    for j in model.joints:
        print(
            f"  {j.name}: viscous {j.friction.viscous:g} N·m·s/rad, Coulomb {j.friction.coulomb:g} N·m, armature "
            f"{j.motor.reflected_inertia:g} kg·m², effort limit {j.limits.effort:g} N·m"
        )
    m = mujoco.MjModel.from_xml_string(ARM)
    d = mujoco.MjData(m)
    dyn = armctl.Dynamics(model)
    worst = 0.0
    for q in np.random.default_rng(0).uniform(-2, 2, (20, 2)):
        d.qpos[:] = q
        mujoco.mj_forward(m, d)
        full = np.zeros((2, 2))
        mujoco.mj_fullM(m, d, full)
        worst = max(worst, np.abs(full - dyn.mass_matrix(q)).max(), np.abs(d.qfrc_bias - dyn.gravity_torque(q)).max())
    print(f"  M(q) and g(q) against MuJoCo's mj_fullM and qfrc_bias at 20 random poses: largest gap {worst:.1e}")


def same_loop() -> None:
    panda = armctl.Dynamics(armctl.models.panda())
    ref = Sinusoid(center=[0, -0.4, 0, -2, 0, 1.6, 0.8], amplitude=[0.3] * 7, frequency=[0.5] * 7)
    ctrl = ComputedTorque(panda, 100.0, 20.0)
    q0 = ref(0.0).q + 0.05
    native = simulate(panda, ctrl, ref, 1.0, q0=q0, integrator="rk4")
    print("\nThe Panda under computed torque for 1 s, RK4 at 1 ms:")
    for integrator in ("rk4", "implicitfast"):
        res = simulate(panda, ctrl, ref, 1.0, q0=q0, integrator=integrator, engine="mujoco")
        print(
            f"  MuJoCo {integrator:12s} max |q − q_native| = {np.abs(res.q - native.q).max():.1e} rad "
            f"(wall time {res.info['wall_time']:.3f} s; native {native.info['wall_time']:.3f} s)"
        )


def stiction() -> None:
    model = armctl.RobotModel.from_mjcf(ARM, tool_frame="tip")
    dyn = armctl.Dynamics(model)
    q0 = np.array([0.3, -0.6])
    hold = dyn.gravity_torque(q0) + 0.5 * np.array([0.1, 0.05])  # half the Coulomb level on both joints

    def holding(t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        return hold

    print("\nHeld by g(q0) + half the Coulomb level for 1 s (the exact motion: none):")
    for engine in ("native", "mujoco"):
        res = simulate(model, holding, armctl.Reference.hold(q0), 1.0, engine=engine)
        print(f"  {engine:6s} creep {np.abs(res.q - q0).max():.1e} rad")


def mesh_contact(out: Path) -> None:
    panda = armctl.models.panda()  # to_mjcf brings the URDF's collision meshes
    dyn = armctl.Dynamics(panda)
    home = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
    tcp = dyn.frame_pose(home)[:3, 3]
    table = f'<geom name="table" type="box" pos="{tcp[0]:.3f} 0 {tcp[2] - 0.08:.3f}" size="0.1 0.2 0.05"/>'
    scene = panda.to_mjcf().replace("<worldbody>", "<worldbody>\n    " + table, 1)
    (out / "panda_table.xml").write_text(scene)
    plant = MujocoPlant(scene, model=panda)
    ctrl = PressDown(dyn, np.array([0.0, 0.0, -15.0]), kp=10.0, kd=3.0)
    res = simulate(plant, ctrl, armctl.Reference.hold(home), 2.0, q0=home, engine="mujoco", integrator="implicitfast")
    touching = np.flatnonzero(np.abs(res.contact_force_on_environment).sum(axis=(1, 2)) > 0)
    q, h = res.q[-1], res.wrench[-1]
    jac = dyn.jacobian(q)
    statics = res.tau_applied[-1] - dyn.gravity_torque(q) + res.tau_friction[-1]
    print(f"\nThe Panda's meshes on a table of a MuJoCo scene (wrote {out / 'panda_table.xml'}):")
    print(f"  first touch at t = {res.t[touching[0]]:.3f} s; force on the table at the end {np.round(h[:3], 2)} N")
    print(f"  statics J_toolᵀ h − (τ − g + τ_f) = {np.linalg.norm(jac.T @ h - statics):.1e} N·m (zero at rest)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("example-out"),
        help="folder for the MuJoCo scene it writes (default: example-out)",
    )
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    mjcf_in()
    same_loop()
    stiction()
    mesh_contact(args.out)


if __name__ == "__main__":
    main()
