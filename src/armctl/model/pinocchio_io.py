"""Conversions between :class:`~armctl.RobotModel` and ``pinocchio.Model`` (private to the model package)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from armctl.errors import ModelLoadError, UnknownNameError
from armctl.model.parts import Frame, Joint, JointFriction, JointLimits, Link, transform

if TYPE_CHECKING:
    import pinocchio

    from armctl.model.robot import RobotModel

_AXES = {(1.0, 0.0, 0.0): "X", (0.0, 1.0, 0.0): "Y", (0.0, 0.0, 1.0): "Z"}


def _joint_model(j: Joint) -> pinocchio.JointModel:
    import pinocchio as pin

    letter = _AXES.get(tuple(float(round(a, 15)) for a in j.axis))
    if j.kind == "revolute":
        return getattr(pin, f"JointModelR{letter}")() if letter else pin.JointModelRevoluteUnaligned(j.axis)
    return getattr(pin, f"JointModelP{letter}")() if letter else pin.JointModelPrismaticUnaligned(j.axis)


def build_pinocchio(model: RobotModel) -> pinocchio.Model:
    """A new pinocchio.Model: same chain, augmented link inertias, armature = k_r²·I_m, named frames."""
    import pinocchio as pin

    pm = pin.Model()
    pm.name = model.name
    pm.gravity = pin.Motion(np.concatenate([model.gravity, np.zeros(3)]))
    for i, j in enumerate(model.joints):
        lim = j.limits
        big = 1e300
        jid = pm.addJoint(
            i, _joint_model(j), pin.SE3(j.placement[:3, :3].copy(), j.placement[:3, 3].copy()), j.name,
            np.array([min(lim.effort, big)]), np.array([min(lim.velocity, big)]),
            np.array([max(lim.lower, -big)]), np.array([min(lim.upper, big)]))
        pm.appendBodyToJoint(jid, pin.Inertia(j.link.mass, j.link.com.copy(), j.link.inertia.copy()),
                             pin.SE3.Identity())
        pm.addFrame(pin.Frame(j.name, jid, 0, pin.SE3.Identity(), pin.FrameType.JOINT), False)
    for f in model.frames:
        pm.addFrame(pin.Frame(f.name, f.joint, 0, pin.SE3(f.placement[:3, :3].copy(),
                                                          f.placement[:3, 3].copy()),
                              pin.FrameType.OP_FRAME), False)
    pm.armature = np.array([j.motor.reflected_inertia if j.motor is not None else 0.0 for j in model.joints])
    return pm


def joints_from_pinocchio(pm: pinocchio.Model, source: str, physical: bool = True
                          ) -> tuple[list[Joint], list[Frame]]:
    """Read a serial, one-dof-per-joint pinocchio.Model back into joints and frames (motors not included).
    ``physical=False`` accepts inertias that violate the triangle inequality (see :class:`Link`)."""
    import pinocchio as pin

    if pm.nq != pm.nv:
        raise ModelLoadError(f"{source}: joints with nq != nv (continuous or floating joints) are not "
                             f"supported; joint types: {[jt.shortname() for jt in pm.joints[1:]]}", value=source)
    data = pm.createData()
    pin.forwardKinematics(pm, data, pin.neutral(pm))
    joints: list[Joint] = []
    for jid in range(1, pm.njoints):
        if pm.parents[jid] != jid - 1 or pm.joints[jid].nv != 1:
            raise ModelLoadError(f"{source}: only serial chains of one-dof joints are supported (joint "
                                 f"{pm.names[jid]!r} has parent {pm.names[pm.parents[jid]]!r})", value=source)
        s = np.asarray(data.joints[jid].S).reshape(6)
        kind = "prismatic" if np.linalg.norm(s[:3]) > 0.5 else "revolute"
        axis = s[:3] if kind == "prismatic" else s[3:]
        inert = pm.inertias[jid]
        pl = pm.jointPlacements[jid]
        idx = jid - 1
        lim = JointLimits(
            lower=float(pm.lowerPositionLimit[idx]) if pm.lowerPositionLimit[idx] > -1e10 else -np.inf,
            upper=float(pm.upperPositionLimit[idx]) if pm.upperPositionLimit[idx] < 1e10 else np.inf,
            velocity=float(pm.velocityLimit[idx]) if 0 < pm.velocityLimit[idx] < 1e10 else np.inf,
            effort=float(pm.effortLimit[idx]) if 0 < pm.effortLimit[idx] < 1e10 else np.inf)
        fric = JointFriction(viscous=float(pm.damping[idx]), coulomb=float(pm.friction[idx]))
        joints.append(Joint(pm.names[jid], kind, axis, transform(pl.rotation, pl.translation),
                            Link(inert.mass, inert.lever, inert.inertia, physical), None, fric, lim))
    names = set(pm.names)
    frames = [Frame(f.name, int(f.parentJoint), transform(f.placement.rotation, f.placement.translation))
              for f in pm.frames if f.name not in names and f.name != "universe" and f.parentJoint > 0]
    seen: set[str] = set()
    unique = [f for f in frames if not (f.name in seen or seen.add(f.name))]
    return joints, unique


def lock_joints(model: RobotModel, lock: Sequence[str] | Mapping[str, float]) -> RobotModel:
    """``model`` with some joints held fixed, through pinocchio.buildReducedModel."""
    import pinocchio as pin

    positions = dict(lock) if isinstance(lock, Mapping) else {name: 0.0 for name in lock}
    q = np.zeros(model.n)
    ids = []
    for name, value in positions.items():
        i = model.joint_index(name)
        q[i] = float(value)
        ids.append(i + 1)
    pm = build_pinocchio(model)
    reduced = pin.buildReducedModel(pm, ids, q)
    joints, frames = joints_from_pinocchio(reduced, model.name, all(j.link.physical for j in model.joints))
    kept = {j.name: j for j in model.joints}
    joints = [replace(j, motor=kept[j.name].motor, friction=kept[j.name].friction, limits=kept[j.name].limits)
              for j in joints]
    tool = model.tool_frame
    if tool is not None and tool in positions:
        raise UnknownNameError("frame", tool, [j.name for j in joints] + [f.name for f in frames])
    extra = [f for f in frames if f.name not in kept or f.name in positions]
    return replace(model, joints=tuple(joints), frames=tuple(extra))
