"""Conversions between :class:`~armctl.RobotModel` and ``pinocchio.Model`` (private to the model package)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from armctl._checks import FloatArray, scalar
from armctl.errors import InvalidParameterError, ModelLoadError, NonFiniteError, ShapeError, UnknownNameError
from armctl.model.parts import Frame, Joint, JointFriction, JointLimits, Link, rot, transform

if TYPE_CHECKING:
    import pinocchio

    from armctl.model.robot import RobotModel

_AXES: dict[tuple[float, ...], str] = {(1.0, 0.0, 0.0): "X", (0.0, 1.0, 0.0): "Y", (0.0, 0.0, 1.0): "Z"}


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
            i,
            _joint_model(j),
            pin.SE3(j.placement[:3, :3].copy(), j.placement[:3, 3].copy()),
            j.name,
            np.array([min(lim.effort, big)]),
            np.array([min(lim.velocity, big)]),
            np.array([max(lim.lower, -big)]),
            np.array([min(lim.upper, big)]),
        )
        pm.appendBodyToJoint(
            jid, pin.Inertia(j.link.mass, j.link.com.copy(), j.link.inertia.copy()), pin.SE3.Identity()
        )
        pm.addFrame(pin.Frame(j.name, jid, 0, pin.SE3.Identity(), pin.FrameType.JOINT), False)
    for f in model.frames:
        pm.addFrame(
            pin.Frame(
                f.name,
                f.joint,
                0,
                pin.SE3(f.placement[:3, :3].copy(), f.placement[:3, 3].copy()),
                pin.FrameType.OP_FRAME,
            ),
            False,
        )
    pm.armature = np.array([j.motor.reflected_inertia if j.motor is not None else 0.0 for j in model.joints])
    return pm


def joints_from_pinocchio(pm: pinocchio.Model, source: str, physical: bool = True) -> tuple[list[Joint], list[Frame]]:
    """Read a serial, one-dof-per-joint pinocchio.Model back into joints and frames (motors not included).
    ``physical=False`` accepts inertias that violate the triangle inequality (see :class:`Link`).

    Every named Pinocchio frame becomes a :class:`Frame` (the first of equal names wins), frames fixed to the
    world (parent joint 0: a URDF's base link, the links merged into the world by locking the first joint)
    included, except Pinocchio's ``"universe"`` and the joint frames (a joint's name is already a frame).
    ``"world"`` names the model's own world frame: a Pinocchio frame called ``"world"`` (e.g. a URDF root
    link of that name) is skipped if it is that frame (fixed to the world at the identity), and raises
    :class:`~armctl.errors.ModelLoadError` otherwise."""
    import pinocchio as pin

    if pm.nq != pm.nv:
        raise ModelLoadError(
            f"{source}: joints with nq != nv (continuous or floating joints) are not "
            f"supported; joint types: {[jt.shortname() for jt in pm.joints[1:]]}",
            value=source,
        )
    data = pm.createData()
    pin.forwardKinematics(pm, data, pin.neutral(pm))
    joints: list[Joint] = []
    for jid in range(1, pm.njoints):
        if pm.joints[jid].nv != 1:
            raise ModelLoadError(
                f"{source}: only one-dof joints are supported; joint {pm.names[jid]!r} is a "
                f"{pm.joints[jid].shortname()} with {pm.joints[jid].nv} degrees of freedom (lock it "
                f"with lock=[{pm.names[jid]!r}] if it may stay fixed)",
                value=source,
            )
        if pm.parents[jid] != jid - 1:
            parent = pm.parents[jid]
            beyond = [pm.names[k] for k in range(parent + 1, pm.njoints)]  # every joint past the branching one
            raise ModelLoadError(
                f"{source}: only serial chains of one-dof joints are supported (joint "
                f"{pm.names[jid]!r} has parent {pm.names[parent]!r}, which already has a child "
                f"joint). Lock the joints of the extra branches, e.g. "
                f"RobotModel.from_urdf(..., lock={beyond!r}) to keep the chain up to "
                f"{pm.names[parent]!r}",
                value=source,
            )
        s = np.asarray(data.joints[jid].S).reshape(6)
        kind = "prismatic" if np.linalg.norm(s[:3]) > 0.5 else "revolute"
        axis = s[:3] if kind == "prismatic" else s[3:]
        inert = pm.inertias[jid]
        pl = pm.jointPlacements[jid]
        idx = jid - 1
        try:
            lim = JointLimits(
                lower=float(pm.lowerPositionLimit[idx]) if pm.lowerPositionLimit[idx] > -1e10 else -np.inf,
                upper=float(pm.upperPositionLimit[idx]) if pm.upperPositionLimit[idx] < 1e10 else np.inf,
                velocity=float(pm.velocityLimit[idx]) if 0 < pm.velocityLimit[idx] < 1e10 else np.inf,
                effort=float(pm.effortLimit[idx]) if 0 < pm.effortLimit[idx] < 1e10 else np.inf,
            )
            fric = JointFriction(viscous=float(pm.damping[idx]), coulomb=float(pm.friction[idx]))
            link = Link(inert.mass, inert.lever, inert.inertia, physical)
        except (InvalidParameterError, NonFiniteError, ShapeError) as e:  # name the joint and its links
            links = [f.name for f in pm.frames if f.parentJoint == jid and f.type == pin.FrameType.BODY]
            carried = f"link{'s' if len(links) > 1 else ''} {', '.join(map(repr, links))}"
            raise type(e)(f"{source}: joint {pm.names[jid]!r} ({carried}): {e}", value=e.value) from None
        joints.append(Joint(pm.names[jid], kind, axis, transform(pl.rotation, pl.translation), link, None, fric, lim))
    names = set(pm.names)
    frames = [
        Frame(f.name, int(f.parentJoint), transform(f.placement.rotation, f.placement.translation))
        for f in pm.frames
        if f.name not in names and f.name != "universe"
    ]
    for f in frames:
        if f.name == "world" and (f.joint != 0 or not np.allclose(f.placement, np.eye(4), rtol=0, atol=1e-12)):
            where = f"on joint {pm.names[f.joint]!r}" if f.joint else "fixed to the world away from its origin"
            raise ModelLoadError(
                f"{source}: a frame called 'world' {where}; 'world' is reserved for the world frame (rename the link)",
                value=source,
            )
    frames = [f for f in frames if f.name != "world"]
    unique: list[Frame] = []  # the first frame of each name
    for f in frames:
        if all(u.name != f.name for u in unique):
            unique.append(f)
    return joints, unique


def _joint_motion(j: Joint, value: float) -> FloatArray:
    """4×4 motion of joint ``j`` at position ``value`` (rotation about / translation along its axis)."""
    t = np.eye(4)
    if j.kind == "revolute":
        t[:3, :3] = rot(j.axis, value)
    else:
        t[:3, 3] = j.axis * value
    return t


def lock_positions(lock: Any, names: Sequence[str]) -> dict[str, float]:
    """``lock`` (one joint name, names locked at 0, a mapping name → position, or None) as {name: position}, the
    names checked against ``names`` (:class:`~armctl.errors.UnknownNameError`) and the positions finite real
    numbers (:class:`~armctl.errors.NonFiniteError`, :class:`~armctl.errors.InvalidParameterError`)."""
    if lock is None:
        return {}
    if isinstance(lock, str):
        lock = (lock,)  # one name, not its letters
    if isinstance(lock, Mapping):
        items = list(lock.items())
    else:
        try:
            if isinstance(lock, bytes):
                raise TypeError("bytes")
            items = [(name, 0.0) for name in lock]
        except TypeError:
            raise InvalidParameterError(
                f"lock must be a joint name, joint names or a mapping joint name → position, got {lock!r}", value=lock
            ) from None
    positions: dict[str, float] = {}
    for name, value in items:
        if not isinstance(name, str) or name not in names:
            raise UnknownNameError("joint", name, list(names))
        positions[name] = scalar(value, f"lock position of joint {name!r}")
    return positions


def lock_joints(model: RobotModel, positions: Mapping[str, float]) -> RobotModel:
    """``model`` with the joints of ``positions`` (checked by :func:`lock_positions`: name → position) held
    fixed: links merged by pinocchio.buildReducedModel; motors, friction,
    limits carried over from ``model``, with a motor's explicit spin axis re-expressed in the link its rotor
    now rides on; every frame (the locked joints' frames included) re-attached to the joint that now carries
    it."""
    import pinocchio as pin

    if len(positions) == model.n:
        raise InvalidParameterError(
            f"cannot lock every joint of {model.name!r} ({sorted(positions)}): a model "
            "needs at least one free joint; leave one out of lock",
            value=positions,
        )
    q = np.zeros(model.n)
    for name, v in positions.items():
        q[model.joint_index(name)] = v
    ids = sorted(model.joint_index(name) + 1 for name in positions)
    # motion of each locked joint (1-based index) at its lock position: its link in the previous link's frame
    locked = {i: model.joints[i - 1].placement @ _joint_motion(model.joints[i - 1], q[i - 1]) for i in ids}
    new_index: dict[int, int] = {}  # old 1-based joint index (0: world) → index in the reduced model
    for i in range(model.n + 1):
        new_index[i] = 0 if i == 0 else new_index[i - 1] + (i not in locked)

    def carried(joint: int, placement: FloatArray) -> tuple[int, FloatArray]:
        """A pose on link ``joint`` (1-based, 0: world) as (reduced joint index, pose on that link)."""
        while joint in locked:
            placement = locked[joint] @ placement
            joint -= 1
        return new_index[joint], placement

    pm = build_pinocchio(model)
    reduced = pin.buildReducedModel(pm, ids, q)
    joints, _ = joints_from_pinocchio(reduced, model.name, all(j.link.physical for j in model.joints))
    source = {j.name: (i, j) for i, j in enumerate(model.joints, start=1)}
    out = []
    for j in joints:
        i, old = source[j.name]
        motor = old.motor
        if motor is not None and motor.axis is not None and i - 1 in locked:  # rides on a merged link
            # (an axis of None follows the joint axis, which moved with the placement pinocchio composed)
            _, pose = carried(i - 1, transform(None, None))
            motor = replace(motor, axis=pose[:3, :3] @ motor.axis)
        out.append(replace(j, motor=motor, friction=old.friction, limits=old.limits))
    frames = [Frame(model.joints[i - 1].name, *carried(i, np.eye(4))) for i in ids]
    frames += [Frame(f.name, *carried(f.joint, f.placement)) for f in model.frames]
    tool = model.tool_frame
    if tool is None and model.n in locked:  # the default tool frame (last joint's) must not move
        tool = model.joints[-1].name
    kept = [i - 1 for i in range(1, model.n + 1) if i not in locked]  # a named pose keeps the free joints' entries
    poses = {name: pose[kept] for name, pose in model.named_poses.items()}
    return replace(model, joints=tuple(out), frames=tuple(frames), tool_frame=tool, named_poses=poses)
