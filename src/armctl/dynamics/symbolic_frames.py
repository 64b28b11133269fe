"""The kinematics of a named frame in CasADi SX, with the model's numbers built in — for code generation.

For the frame of :meth:`armctl.RobotModel.frame` (rigidly attached to joint k with a constant placement), at
(q, q̇), with the same conventions as :meth:`armctl.Dynamics.jacobian` (world-aligned axes at the frame's origin,
rows [linear; angular]):

    (R, p)  = T_1(q_1) ⋯ T_k(q_k) · placement                 the frame's pose in the world
    J       columns j ≤ k:  [z_j × (p − o_j); z_j] (revolute),  [z_j; 0] (prismatic);  0 beyond k
    J̇ q̇    = ∂(J q̇)/∂q · q̇                                   the classical acceleration of the frame at q̈ = 0

with z_j, o_j joint j's axis and origin in the world, T_j the joint transforms of
:func:`armctl.dynamics.recursive.joint_transforms`. J̇ q̇ is the directional derivative of the frame's velocity
(a forward-mode product, exact): d/dt (J q̇) = J q̈ + J̇ q̇, what Pinocchio's ``getFrameClassicalAcceleration``
(LOCAL_WORLD_ALIGNED) returns.
"""

from __future__ import annotations

import casadi as cs

from armctl.dynamics.recursive import joint_transforms
from armctl.model.robot import RobotModel


def frame_kinematics(
    model: RobotModel,
    q: cs.SX,
    qd: cs.SX,
    frame: str | None = None,
    transforms: list[tuple[cs.SX, cs.SX]] | None = None,
) -> tuple[cs.SX, cs.SX, cs.SX, cs.SX]:
    """(p (3), R (3×3), J (6×n), J̇ q̇ (6)) of ``frame`` (default: the tool frame) at (q, q̇), see the module;
    ``transforms``: the joint transforms at q, if the caller has them."""
    f = model.frame(frame)
    tf = transforms if transforms is not None else joint_transforms(model, q)
    rot, pos = cs.SX.eye(3), cs.SX.zeros(3)
    axes: list[tuple[str, cs.SX, cs.SX]] = []  # per joint up to the frame's: (kind, world axis, world origin)
    for i in range(f.joint):
        r, t = tf[i]
        pos = pos + rot @ t
        joint = model.joints[i]
        if joint.kind == "revolute":  # the axis is the rotation's fixed direction: after or before it alike
            rot = rot @ r
            axes.append((joint.kind, rot @ cs.DM(joint.axis), pos))
        else:  # prismatic: t moves along the axis in the parent's frame rotated by the placement
            axes.append((joint.kind, rot @ r @ cs.DM(joint.axis), pos))
            rot = rot @ r
    p = pos + rot @ cs.DM(f.placement[:3, 3])
    rotation = rot @ cs.DM(f.placement[:3, :3])
    jac = cs.SX.zeros(6, model.n)
    for j, (kind, z, o) in enumerate(axes):
        if kind == "revolute":
            jac[:3, j] = cs.cross(z, p - o)
            jac[3:, j] = z
        else:
            jac[:3, j] = z
    drift = cs.jtimes(jac @ qd, q, qd)
    return p, rotation, jac, drift
