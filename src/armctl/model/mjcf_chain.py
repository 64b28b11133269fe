"""The serial chain of a compiled ``mjModel``, read into the parts of a :class:`~armctl.RobotModel` (see
:mod:`armctl.model.mjcf` for what is read and how)."""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from armctl._checks import FloatArray
from armctl._mujoco import require_mujoco
from armctl.errors import ModelLoadError, UnknownNameError
from armctl.model.parts import Frame, Joint, JointFriction, JointLimits, Link, Motor, rot, transform

_KINDS = {"hinge": "revolute", "slide": "prismatic"}


@dataclass(frozen=True)
class MjcfChain:
    """A serial chain read from a compiled ``mjModel``: the parts of its RobotModel, and where they are in MuJoCo.

    Attributes
    ----------
    joints : tuple of Joint
        The chain's joints, from the base.
    frames : tuple of Frame
        The named bodies and sites as frames.
    gravity : ndarray, shape (3,)
        g [m/s²] in world axes.
    name : str
        The model's name.
    joint_ids : tuple of int
        The MuJoCo joint id of each armctl joint, in chain order.
    body_joint : dict of int to int
        MuJoCo body id → the 1-based armctl joint whose link it belongs to (0: fixed to the world), for every body
        of the chain.
    """

    joints: tuple[Joint, ...]
    frames: tuple[Frame, ...]
    gravity: FloatArray
    name: str
    joint_ids: tuple[int, ...]
    body_joint: dict[int, int]


def _name(m: Any, kind: str, i: int) -> str:
    adr = getattr(m, f"name_{kind}adr")[i]
    return m.names[adr:].split(b"\0", 1)[0].decode()


def joint_name(m: Any, j: int) -> str:
    """The name of MuJoCo joint j ("" if it has none)."""
    return _name(m, "jnt", j)


def _pose(pos: Any, quat: Any) -> FloatArray:
    w, x, y, z = (float(v) for v in quat)
    r = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )
    return transform(r, np.asarray(pos, dtype=float))


def _shift(p: Any) -> FloatArray:
    return transform(None, np.asarray(p, dtype=float))


def _body_link(m: Any, b: int, where: FloatArray) -> Link:
    """Body b's inertia (MuJoCo's principal moments in the frame ``body_iquat``) in the frame where the body's frame
    is the pose ``where``."""
    inertial = _pose(m.body_ipos[b], m.body_iquat[b])
    r = inertial[:3, :3]
    tensor = r @ np.diag(m.body_inertia[b]) @ r.T
    return Link(float(m.body_mass[b]), m.body_ipos[b], 0.5 * (tensor + tensor.T)).transformed(
        where[:3, :3], where[:3, 3]
    )


def _effort(m: Any, mj: Any, j: int) -> float:
    """The effort limit [N·m or N] of joint j from its actuators (see the module), inf if nothing limits it."""
    limits = []
    if bool(m.jnt_actfrclimited[j]):
        lo, hi = m.jnt_actfrcrange[j]
        limits.append(min(-lo, hi))
    total, every = 0.0, False
    for a in range(m.nu):
        if m.actuator_trntype[a] != mj.mjtTrn.mjTRN_JOINT or m.actuator_trnid[a, 0] != j:
            continue
        gear = abs(float(m.actuator_gear[a, 0]))
        plain_motor = (
            m.actuator_gaintype[a] == mj.mjtGain.mjGAIN_FIXED
            and m.actuator_biastype[a] == mj.mjtBias.mjBIAS_NONE
            and m.actuator_dyntype[a] == mj.mjtDyn.mjDYN_NONE
        )
        if bool(m.actuator_forcelimited[a]):
            lo, hi = m.actuator_forcerange[a]
            total, every = total + gear * min(-lo, hi), True
        elif plain_motor and bool(m.actuator_ctrllimited[a]):
            lo, hi = m.actuator_ctrlrange[a]
            total, every = total + gear * abs(float(m.actuator_gainprm[a, 0])) * min(-lo, hi), True
        else:  # an actuator of this joint without a force bound: the sum is not bounded
            total, every = math.inf, True
    if every:
        limits.append(total)
    effort = min(limits, default=math.inf)
    return effort if effort > 0 else math.inf


def read_chain(
    m: Any, base: str | None = None, source: str = "the MJCF model", lock: Mapping[str, float] | None = None
) -> MjcfChain:
    """The serial chain of a compiled ``mjModel``, from the body ``base`` to its last joint.

    Parameters
    ----------
    m : mujoco.MjModel
        The compiled model.
    base : str, optional
        The body the chain starts from (None: the one subtree of the world with joints).
    source : str, optional
        What the model was read from, for the error messages.
    lock : mapping of str to float, optional
        Joints held fixed, name → position (MuJoCo's ``qpos`` [rad or m], names already checked): each is welded
        at that position, its body carried by the joint before it, so that a branch whose joints are all locked
        (a gripper's fingers) no longer moves.

    Returns
    -------
    MjcfChain

    Raises
    ------
    ModelLoadError
        No chain, a chain that branches, or a joint armctl cannot model.
    """
    mj = require_mujoco("reading an MJCF model")
    lock = dict(lock or {})
    locked = {j for j in range(m.njnt) if _name(m, "jnt", j) in lock}
    parent = m.body_parentid
    moving = np.zeros(m.nbody, dtype=bool)  # the body's subtree has free joints (MuJoCo numbers parents first)
    for b in range(m.nbody - 1, 0, -1):
        adr = int(m.body_jntadr[b])
        moving[b] |= any(j not in locked for j in range(adr, adr + int(m.body_jntnum[b])))
        moving[parent[b]] |= moving[b]
    children: list[list[int]] = [[] for _ in range(m.nbody)]
    for b in range(1, m.nbody):
        children[parent[b]].append(b)
    bodies = [_name(m, "body", b) for b in range(m.nbody)]
    start, pose = 0, np.eye(4)
    if base is not None and base != "world":
        if base not in bodies:
            raise UnknownNameError("body", base, [b for b in bodies if b])
        start = bodies.index(base)
        up = int(parent[start])
        while up != 0:  # the base must be fixed to the world
            if m.body_jntnum[up] > 0:
                raise ModelLoadError(
                    f"{source}: body {base!r} is carried by the joints of body {bodies[up]!r}; choose as base a body "
                    "fixed to the world",
                    value=base,
                )
            up = int(parent[up])
        chain = [start]
        while chain[-1] != 0:
            chain.append(int(parent[chain[-1]]))
        for b in reversed(chain[1:-1]):
            pose = pose @ _pose(m.body_pos[b], m.body_quat[b])
    elif sum(moving[c] for c in children[0]) > 1:
        roots = [bodies[c] or f"body {c}" for c in children[0] if moving[c]]
        raise ModelLoadError(
            f"{source}: the world carries several bodies with joints ({', '.join(map(repr, roots))}); give base= "
            "the body where the arm starts",
            value=roots,
        )
    if not moving[start]:
        raise ModelLoadError(f"{source}: no hinge or slide joint below {base or 'the world'!r}", value=base)
    reader = _ChainReader(m, mj, source, bodies, moving, children, lock)
    if start == 0:
        reader.sites(0, 0, np.eye(4))
        reader.walk_children(0, 0, np.eye(4))
    else:
        reader.body(start, 0, pose)
    for b in range(1, m.nbody):
        if m.body_gravcomp[b] != 0 and b in reader.body_joint:
            warnings.warn(
                f"{source}: body {bodies[b]!r} has gravcomp={m.body_gravcomp[b]:g}; the RobotModel has full gravity "
                "(MuJoCo's gravity compensation is a force its simulation applies, not part of the arm)",
                UserWarning,
                stacklevel=3,
            )
    disabled = m.opt.disableflags & mj.mjtDisableBit.mjDSBL_GRAVITY
    gravity = np.zeros(3) if disabled else np.array(m.opt.gravity, dtype=float)
    joints = tuple(
        Joint(nm, kind, axis, pl, link, motor, fr, lim)
        for (nm, kind, axis, pl, motor, fr, lim), link in zip(reader.joints, reader.links, strict=True)
    )
    return MjcfChain(
        joints,
        tuple(reader.frames),
        gravity,
        m.names.split(b"\0", 1)[0].decode(),
        tuple(reader.joint_ids),
        dict(reader.body_joint),
    )


class _ChainReader:
    """Walks the chain body by body, collecting joints, links and frames (the state of :func:`read_chain`)."""

    def __init__(
        self,
        m: Any,
        mj: Any,
        source: str,
        bodies: list[str],
        moving: Any,
        children: list[list[int]],
        lock: Mapping[str, float],
    ):
        self.m, self.mj, self.source, self.bodies, self.moving, self.children = m, mj, source, bodies, moving, children
        self.lock = lock
        self.joints: list[tuple[Any, ...]] = []
        self.links: list[Link] = []
        self.frames: list[Frame] = []
        self.joint_ids: list[int] = []
        self.body_joint: dict[int, int] = {}
        self.names = {"world"}

    def frame(self, name: str, i: int, pose: FloatArray, kind: str) -> None:
        """A frame called ``name`` on joint i; a name already taken is skipped where it names the same frame (a
        body whose frame is its joint's), else renamed ``name_body`` / ``name_site``."""
        if not name:
            return
        if name in self.names:
            same_joint = i > 0 and self.joints[i - 1][0] == name
            if (same_joint or (name == "world" and i == 0)) and np.allclose(pose, np.eye(4), atol=1e-12):
                return
            name = f"{name}_{kind}"
            if name in self.names:
                return
        self.names.add(name)
        self.frames.append(Frame(name, i, pose))

    def sites(self, b: int, i: int, pose: FloatArray) -> None:
        m = self.m
        for s in np.flatnonzero(m.site_bodyid == b).tolist():
            self.frame(_name(m, "site", s), i, pose @ _pose(m.site_pos[s], m.site_quat[s]), "site")

    def body(self, b: int, i: int, parent_pose: FloatArray) -> None:
        """Body b, whose parent's frame is at ``parent_pose`` in the frame of joint i (0: the world)."""
        m = self.m
        pose = parent_pose @ _pose(m.body_pos[b], m.body_quat[b])
        adr = int(m.body_jntadr[b])
        for j in range(adr, adr + int(m.body_jntnum[b])):
            name = _name(m, "jnt", j)
            if name in self.lock:
                pose = pose @ self.held(j, self.lock[name])
                continue
            pose = self.joint(j, pose)
            i = len(self.joints)
        self.body_joint[b] = i
        if i > 0:
            self.links[i - 1] = self.links[i - 1].combined(_body_link(m, b, pose))
        self.frame(self.bodies[b], i, pose, "body")
        self.sites(b, i, pose)
        self.walk_children(b, i, pose)

    def walk_children(self, b: int, i: int, pose: FloatArray) -> None:
        moving = [c for c in self.children[b] if self.moving[c]]
        if len(moving) > 1:
            names = [self.bodies[c] or f"body {c}" for c in moving]
            raise ModelLoadError(
                f"{self.source}: body {self.bodies[b] or 'world'!r} carries several bodies with joints "
                f"({', '.join(map(repr, names))}); armctl reads one serial chain: hold the joints of the other "
                "branches with lock= (a gripper's fingers, for instance), or weld or remove them",
                value=names,
            )
        for c in self.children[b]:
            if not self.moving[c]:
                self.body(c, i, pose)
        for c in moving:
            self.body(c, i, pose)

    def held(self, j: int, position: float) -> FloatArray:
        """The motion of joint j held at ``position`` (its ``qpos``): about (along) its axis through its ``pos``,
        from the body's frame at ``qpos0``."""
        m = self.m
        axis = np.array(m.jnt_axis[j], dtype=float)
        offset = position - float(m.qpos0[m.jnt_qposadr[j]])
        hinge = int(m.jnt_type[j]) == int(self.mj.mjtJoint.mjJNT_HINGE)
        if not hinge and int(m.jnt_type[j]) != int(self.mj.mjtJoint.mjJNT_SLIDE):
            name = _name(m, "jnt", j)
            raise ModelLoadError(
                f"{self.source}: joint {name!r} is not a hinge or a slide joint and cannot be locked at a position; "
                "weld it in the MJCF instead",
                value=name,
            )
        motion = transform(rot(axis, offset)) if hinge else _shift(offset * axis)
        return _shift(m.jnt_pos[j]) @ motion @ _shift(-np.asarray(m.jnt_pos[j], dtype=float))

    def joint(self, j: int, body_pose: FloatArray) -> FloatArray:
        """Joint j of a body whose frame (before this joint moves it) is ``body_pose``; appends the joint and
        returns the body's frame in the new joint's frame."""
        m, mj = self.m, self.mj
        name = _name(m, "jnt", j) or f"joint{len(self.joints) + 1}"
        kind = {int(mj.mjtJoint.mjJNT_HINGE): "hinge", int(mj.mjtJoint.mjJNT_SLIDE): "slide"}.get(int(m.jnt_type[j]))
        if kind is None:
            what = "free joint (a floating base)" if m.jnt_type[j] == mj.mjtJoint.mjJNT_FREE else "ball joint"
            raise ModelLoadError(
                f"{self.source}: joint {name!r} is a {what}; armctl reads serial chains of hinge and slide joints "
                "(give base= a body below it, or weld it)",
                value=name,
            )
        if m.jnt_stiffness[j] != 0:
            raise ModelLoadError(
                f"{self.source}: joint {name!r} has a spring (stiffness={m.jnt_stiffness[j]:g}), which a RobotModel "
                "cannot hold; remove it (stiffness=0) or model it in the controller",
                value=name,
            )
        dof = int(m.jnt_dofadr[j])
        if hasattr(m, "dof_dampingpoly") and np.any(m.dof_dampingpoly[dof]):
            raise ModelLoadError(
                f"{self.source}: joint {name!r} has polynomial damping, which a RobotModel cannot hold",
                value=name,
            )
        while name in self.names:
            name = f"{name}_"
        self.names.add(name)
        axis = np.array(m.jnt_axis[j], dtype=float)
        q0 = float(m.qpos0[m.jnt_qposadr[j]])
        motion = transform(rot(axis, -q0)) if kind == "hinge" else _shift(-q0 * axis)
        placement = body_pose @ _shift(m.jnt_pos[j]) @ motion
        armature = float(m.dof_armature[dof])
        motor = Motor(armature, 1.0, gyroscopic=False) if armature > 0 else None
        friction = JointFriction(viscous=float(m.dof_damping[dof]), coulomb=float(m.dof_frictionloss[dof]))
        lower, upper = m.jnt_range[j] if m.jnt_limited[j] else (-math.inf, math.inf)
        limits = JointLimits(float(lower), float(upper), effort=_effort(m, mj, j))
        self.joints.append((name, _KINDS[kind], axis, placement, motor, friction, limits))
        self.links.append(Link(0.0))  # the body's mass goes to the link of its last joint (see body())
        self.joint_ids.append(j)
        return _shift(-np.asarray(m.jnt_pos[j], dtype=float))
