"""What an arm looks like, for :func:`armctl.sim.playback.playback`: a list of :class:`Part`, each a shape
attached to a joint's frame.

Where the model is one of example-robot-data's arms (the built-in :func:`armctl.models.panda` and
:func:`armctl.models.ur5`, and their variants such as ``"panda+payload"``, by name) the parts are the
description's meshes, loaded through Pinocchio's URDF parser; that the kinematics agree is checked (the same
joint names and joint placements to 1e-9), and a model that does not agree is drawn with simple shapes. The
simple shapes: a cylinder along each joint's axis at the joint, a rod from each joint to the next one (and
from the last one to the tool frame), sized from the arm's reach.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any

import numpy as np

from armctl._checks import FloatArray
from armctl.model.robot import RobotModel

#: example-robot-data descriptions by model name: (URDF path in the package, joints locked at 0)
DESCRIPTIONS: dict[str, tuple[str, tuple[str, ...]]] = {
    "panda": ("panda_description/urdf/panda.urdf", ("panda_finger_joint1", "panda_finger_joint2")),
    "ur5": ("ur_description/urdf/ur5_robot.urdf", ()),
}
#: the kinematics of a description must match the model's to this [m, rad] for its meshes to be used
PLACEMENT_TOLERANCE = 1e-9
#: colours of the simple shapes (joints, links), as 0xRRGGBB
JOINT_COLOUR, LINK_COLOUR = 0xE07A1F, 0x8A9BB0
#: the colours given to the links of a mesh model in turn (collision meshes have none of their own)
MESH_COLOURS = (0xD8DDE3, 0x9AA5B1)
MESHES = ("visual", "collision", "shapes")


@dataclass(frozen=True)
class Part:
    """A shape riding on joint ``joint`` (1-based; 0: the world) at ``placement`` (4×4, in that joint's
    frame), drawn as ``geometry`` (a meshcat geometry, or a Pinocchio DaeMeshGeometry) with ``colour``
    (0xRRGGBB; None: the mesh's own), ``opacity`` and ``scale`` (the mesh's own scale)."""

    name: str
    joint: int
    placement: FloatArray
    geometry: Any
    colour: int | None = None
    opacity: float = 1.0
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)


def reach(model: RobotModel) -> float:
    """Sum of the distances between successive joint origins and to the tool frame [m] (at least 0.1)."""
    total = sum(float(np.linalg.norm(j.placement[:3, 3])) for j in model.joints[1:])
    if model.tool_frame is not None:
        total += float(np.linalg.norm(model.frame(model.tool_frame).placement[:3, 3]))
    return max(total, 0.1)


def parts(model: RobotModel, meshes: str = "visual") -> tuple[list[Part], str]:
    """The parts that draw ``model`` and where they come from ("example-robot-data <path>" or "simple
    shapes"). ``meshes``: "visual" (the description's visual meshes), "collision" (its collision meshes:
    coarser, far smaller files) or "shapes" (simple shapes whatever the model)."""
    base = re.split(r"[+~]", model.name, maxsplit=1)[0]  # a variant's name: "panda+payload", "ur5~perturbed"
    if meshes != "shapes" and base in DESCRIPTIONS:
        found = _description_parts(model, base, meshes)
        if found is not None:
            return found, f"example-robot-data {DESCRIPTIONS[base][0]} ({meshes} meshes)"
    return _shape_parts(model), "simple shapes"


def _description_parts(model: RobotModel, name: str, meshes: str) -> list[Part] | None:
    import meshcat.geometry as mg
    import pinocchio as pin
    from pinocchio.visualize.meshcat_visualizer import DaeMeshGeometry

    from armctl.models import robot_description

    relative, locked = DESCRIPTIONS[name]
    path = str(robot_description(relative))
    share = path.split("/example-robot-data/")[0]
    kind = pin.GeometryType.VISUAL if meshes == "visual" else pin.GeometryType.COLLISION
    full = pin.buildModelFromUrdf(path)
    geom = pin.buildGeomFromUrdf(full, path, kind, package_dirs=[share])
    if locked:
        ids = [full.getJointId(name) for name in locked]
        full, geom = pin.buildReducedModel(full, geom, ids, pin.neutral(full))
    own = model.to_pinocchio()
    if list(full.names) != list(own.names) or full.nq != own.nq:
        return None
    for a, b in zip(full.jointPlacements, own.jointPlacements, strict=True):
        if not np.allclose(a.homogeneous, b.homogeneous, rtol=0.0, atol=PLACEMENT_TOLERANCE):
            return None
    out = []
    for i, obj in enumerate(geom.geometryObjects):
        suffix = obj.meshPath.rsplit(".", 1)[-1].lower() if obj.meshPath else ""
        placement = obj.placement.homogeneous
        primitive = _primitive(obj.geometry)
        shape: Any
        if primitive is not None:
            shape, turn = primitive
            placement = placement @ turn
        elif suffix == "dae":
            shape = DaeMeshGeometry(obj.meshPath)
        elif suffix == "stl":
            shape = mg.StlMeshGeometry.from_file(obj.meshPath)
        elif suffix == "obj":
            shape = mg.ObjMeshGeometry.from_file(obj.meshPath)
        else:
            return None  # a primitive or an unknown format: draw the arm with shapes instead
        colour = None if suffix == "dae" and primitive is None else MESH_COLOURS[i % len(MESH_COLOURS)]
        out.append(
            Part(
                obj.name,
                int(obj.parentJoint),
                placement,
                shape,
                colour,
                scale=(float(obj.meshScale[0]), float(obj.meshScale[1]), float(obj.meshScale[2])),
            )
        )
    return out


def _primitive(geometry: Any) -> tuple[Any, FloatArray] | None:
    """A meshcat shape for a coal primitive (box, sphere, cylinder, capsule as a cylinder) and the rotation
    that turns meshcat's y axis onto coal's z axis; None for a mesh."""
    import meshcat.geometry as mg

    turn = np.eye(4)
    turn[:3, :3] = _rotation_y_to(np.array([0.0, 0.0, 1.0]))
    kind = type(geometry).__name__
    if kind == "Box":
        return mg.Box([2.0 * float(x) for x in geometry.halfSide]), np.eye(4)
    if kind == "Sphere":
        return mg.Sphere(float(geometry.radius)), np.eye(4)
    if kind in ("Cylinder", "Capsule"):
        return mg.Cylinder(2.0 * float(geometry.halfLength), float(geometry.radius)), turn
    return None


def _rotation_y_to(direction: FloatArray) -> FloatArray:
    """A rotation taking the y axis (meshcat's cylinder axis) to the unit vector ``direction``."""
    y = np.array([0.0, 1.0, 0.0])
    d = direction / np.linalg.norm(direction)
    axis = np.cross(y, d)
    s, c = float(np.linalg.norm(axis)), float(y @ d)
    if s < 1e-12:
        return np.eye(3) if c > 0 else np.diag([1.0, -1.0, -1.0])
    k = axis / s
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    angle = math.atan2(s, c)
    return np.eye(3) + math.sin(angle) * kx + (1.0 - math.cos(angle)) * (kx @ kx)


def _shape_parts(model: RobotModel) -> list[Part]:
    import meshcat.geometry as mg

    size = reach(model)
    radius = 0.04 * size
    out = []
    ends: list[FloatArray] = [j.placement[:3, 3] for j in model.joints[1:]]
    if model.tool_frame is not None:
        tool = model.frame(model.tool_frame)
        ends.append(tool.placement[:3, 3] if tool.joint == model.n else np.zeros(3))
    else:
        ends.append(np.zeros(3))
    for i, joint in enumerate(model.joints, start=1):
        place = np.eye(4)
        place[:3, :3] = _rotation_y_to(np.asarray(joint.axis, dtype=float))
        out.append(Part(f"{joint.name}_joint", i, place, mg.Cylinder(3.0 * radius, 1.3 * radius), JOINT_COLOUR))
        end = np.asarray(ends[i - 1], dtype=float)
        length = float(np.linalg.norm(end))
        if length < 1e-9:
            continue
        rod = np.eye(4)
        rod[:3, :3] = _rotation_y_to(end)
        rod[:3, 3] = end / 2.0
        out.append(Part(f"{joint.name}_link", i, rod, mg.Cylinder(length, 0.7 * radius), LINK_COLOUR))
    base = np.eye(4)
    base[:3, :3] = _rotation_y_to(np.array([0.0, 0.0, 1.0]))
    base[2, 3] = -radius
    out.append(Part("base", 0, base, mg.Cylinder(2.0 * radius, 2.5 * radius), LINK_COLOUR))
    return out
