"""MuJoCo models of armctl's built-in arms, loaded from the same URDF files (test helper).

MuJoCo is an engine nobody here wrote: it is the independent reference for forward dynamics and simulated
trajectories. The URDF is loaded with meshes stripped (visual and collision geometry play no part in the
dynamics), static bodies not fused, inertias not rebalanced, the Panda's fingers fixed, and no joint damping,
armature, limits or contacts, so that MuJoCo sees the same rigid-body model as armctl.
"""

from __future__ import annotations

import re

import mujoco
import numpy as np

import armctl


def panda_mujoco() -> tuple[object, object]:
    """(mjModel, mjData) of the Panda, the 7 arm joints in armctl's order."""
    path = armctl.models.robot_description("panda_description/urdf/panda.urdf")
    text = path.read_text()
    text = re.sub(r"<visual>.*?</visual>", "", text, flags=re.S)
    text = re.sub(r"<collision>.*?</collision>", "", text, flags=re.S)
    text = re.sub(r'(<joint name="panda_finger_joint[12]"[^>]*type=)"prismatic"', r'\1"fixed"', text)
    text = re.sub(r"<dynamics[^>]*/>", "", text)
    text = re.sub(
        r"(<robot[^>]*>)",
        r'\1<mujoco><compiler discardvisual="true" fusestatic="false" '
        r'balanceinertia="false" angle="radian"/></mujoco>',
        text,
        count=1,
    )
    m = mujoco.MjModel.from_xml_string(text)
    m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONSTRAINT | mujoco.mjtDisableBit.mjDSBL_CONTACT
    m.dof_damping[:] = 0.0
    m.dof_armature[:] = 0.0
    m.dof_frictionloss[:] = 0.0
    m.opt.gravity[:] = [0.0, 0.0, -9.81]
    assert m.nv == 7, f"expected 7 arm joints in MuJoCo, got {m.nv}"
    return m, mujoco.MjData(m)


def mujoco_forward(m: object, d: object, q: np.ndarray, qd: np.ndarray, tau: np.ndarray) -> np.ndarray:
    d.qpos[:] = q
    d.qvel[:] = qd
    d.qfrc_applied[:] = tau
    d.ctrl[:] = 0.0
    mujoco.mj_forward(m, d)
    return np.array(d.qacc)
