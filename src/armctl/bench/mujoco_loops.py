"""MuJoCo's side of :mod:`armctl.bench.sim_speed`: the same arms and scenes stepped by MuJoCo from a Python loop.

* :func:`joint_friction_model`: an arm of :func:`armctl.RobotModel.to_mjcf` (no geometry) with its joint friction as
  MuJoCo has it — ``damping`` F_v and ``frictionloss`` F_c, a soft constraint (MuJoCo has no breakaway level) —
  integrated by ``implicitfast``;
* :func:`contact_model`: the Panda of ``panda_contact`` with a 5 mm sphere at its tool frame and the scene's table
  as a plane (MuJoCo's default soft contact, friction μ of the scene);
* :func:`closed_loop`: the loop a user writes — read the state, call the controller, apply its torque, ``mj_step``
  (``substeps`` times a control period);
* :func:`replay`: the plant alone, a recorded torque sequence held over each control period.
"""

from __future__ import annotations

import time
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Callable
from typing import Any

import numpy as np

from armctl._checks import FloatArray
from armctl.model.robot import RobotModel


def _compile(root: ET.Element, dt: float) -> tuple[Any, Any]:
    import mujoco

    option = root.find("option")
    if option is None:
        option = ET.SubElement(root, "option")
    option.set("timestep", repr(dt))
    option.set("integrator", "implicitfast")
    m = mujoco.MjModel.from_xml_string(ET.tostring(root, encoding="unicode"))
    return m, mujoco.MjData(m)


def _mjcf(model: RobotModel) -> ET.Element:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # (MuJoCo's friction has no breakaway level: said in the doc)
        return ET.fromstring(model.to_mjcf(meshes=False, contacts=False))


def joint_friction_model(model: RobotModel, dt: float) -> tuple[Any, Any]:
    """(MjModel, MjData) of ``model`` with damping and frictionloss, ``implicitfast`` at step ``dt`` [s]."""
    return _compile(_mjcf(model), dt)


def contact_model(model: RobotModel, z_table: float, mu: float, dt: float, radius: float = 0.005) -> tuple[Any, Any]:
    """(MjModel, MjData): ``model`` with a sphere of ``radius`` [m] at its tool frame touching a plane whose top
    is at ``z_table`` [m] (world z), friction ``mu``; ``implicitfast`` at ``dt``."""
    root = _mjcf(model)
    tool = model.frame(None).name
    site = next(s for s in root.iter("site") if s.get("name") == tool)
    body = next(b for b in root.iter("body") if site in list(b))
    friction = f"{mu!r} 0.005 0.0001"
    ET.SubElement(
        body, "geom", type="sphere", size=repr(radius), pos=site.get("pos", "0 0 0"), contype="1", conaffinity="0",
        friction=friction,
    )  # fmt: skip
    world = root.find("worldbody")
    assert world is not None
    ET.SubElement(world, "geom", type="plane", size="2 2 0.1", pos=f"0 0 {z_table - radius!r}", friction=friction)
    return _compile(root, dt)


def closed_loop(
    m: Any,
    d: Any,
    controller: Callable[..., FloatArray],
    reference: Callable[[float], Any],
    q0: FloatArray,
    steps: int,
    control_dt: float,
    substeps: int = 1,
) -> tuple[float, float]:
    """(seconds, RMS tracking error [rad]) of ``steps`` control periods of ``substeps`` steps each (MjModel's
    timestep: control_dt / substeps): read q and q̇, call the controller, apply its torque, ``mj_step`` (q recorded,
    as ``simulate`` records it; the error computed after)."""
    import mujoco

    d.qpos[:] = q0
    d.qvel[:] = 0.0
    mujoco.mj_forward(m, d)
    step, qpos, qvel, qfrc = mujoco.mj_step, d.qpos, d.qvel, d.qfrc_applied
    record = np.zeros((steps, len(q0)))
    t0 = time.perf_counter()
    for k in range(steps):
        t = k * control_dt
        q = qpos.copy()
        record[k] = q
        qfrc[:] = controller(t, q, qvel.copy(), reference(t))
        for _ in range(substeps):
            step(m, d)
    wall = time.perf_counter() - t0
    err = [float(np.abs(reference(k * control_dt).q - record[k]).max()) for k in range(steps)]
    return wall, float(np.sqrt(np.mean(np.square(err))))


def replay(m: Any, d: Any, torques: FloatArray, q0: FloatArray, substeps: int) -> tuple[float, int]:
    """(seconds, contacts seen) of the plant alone: each torque of ``torques`` held over ``substeps`` steps."""
    import mujoco

    d.qpos[:] = q0
    d.qvel[:] = 0.0
    mujoco.mj_forward(m, d)
    step, qfrc = mujoco.mj_step, d.qfrc_applied
    touching = 0
    t0 = time.perf_counter()
    for tau in torques:
        qfrc[:] = tau
        for _ in range(substeps):
            step(m, d)
        touching += d.ncon > 0
    return time.perf_counter() - t0, touching
