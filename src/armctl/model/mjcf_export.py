"""`RobotModel.to_mjcf`: an arm as an MJCF text that MuJoCo compiles to the same rigid-body dynamics.

* One body per joint, at the joint's placement (``pos`` and ``quat`` in the previous joint's frame), the joint at
  the body's origin, so that MuJoCo's ``qpos`` is armctl's q.
* ``<inertial>`` with the link's mass, centre of mass and ``fullinertia`` (MuJoCo's order Ixx Iyy Izz Ixy Ixz Iyz).
  MuJoCo refuses moving bodies whose mass or principal moments are zero (a massless link, a slender rod): the
  ``boundmass`` and ``boundinertia`` of :data:`BOUND` raise them to 10⁻¹² (kg, kg·m²), which changes M by as much.
  A link whose inertia violates the triangle inequality (``Link(physical=False)``) is refused.
* ``armature`` = k_r² I_m, the reflected rotor inertia (MuJoCo has no gyroscopic rotor coupling: like Pinocchio it
  keeps the armature only), ``damping`` = F_v, ``frictionloss`` = F_c (MuJoCo's joint friction has one level: an
  asymmetric Coulomb friction is written as its mean, a breakaway level above it and a Stribeck curve are dropped,
  with a warning).
* ``range`` for joints with both limits finite; a ``motor`` actuator per joint with a finite effort limit (gear 1,
  ``ctrlrange`` and ``forcerange`` ± the limit: ``ctrl`` is the joint torque); the named frames as sites.
* Geometry, for viewing and for contact in a scene: the collision meshes (else the visual ones) of the URDF the model
  was read from, placed on the link frames of the same names, where MuJoCo can read them (STL, OBJ, MSH); a capsule
  from each joint to the next (to the tool frame after the last joint) for the links that get no mesh. With
  ``contacts=True`` the arm's geoms have ``contype="1" conaffinity="0"``: they collide with a scene's geoms
  (default ``conaffinity="1"``) but never with each other, as in armctl's own simulator.
"""

from __future__ import annotations

import math
import os
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from armctl._checks import FloatArray
from armctl.errors import InvalidParameterError, UnknownNameError
from armctl.model.parts import inertia_tensor, rot, transform

if TYPE_CHECKING:
    from armctl.model.robot import RobotModel

#: lower bound MuJoCo is told to put on every moving body's mass [kg] and principal moments [kg·m²]
BOUND = 1e-12
#: mesh files MuJoCo reads
MESH_FORMATS = (".stl", ".obj", ".msh")


def _num(x: Any) -> str:
    return " ".join(repr(float(v)) for v in np.atleast_1d(np.asarray(x, dtype=float)))


def quaternion(r: FloatArray) -> FloatArray:
    """The unit quaternion (w, x, y, z) of a rotation matrix (Shepperd's method)."""
    t = float(np.trace(r))
    if t > 0:
        s = 2.0 * math.sqrt(1.0 + t)
        q = [0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s]
    else:
        i = int(np.argmax(np.diag(r)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(max(1.0 + r[i, i] - r[j, j] - r[k, k], 0.0))
        q = [0.0] * 4
        q[0] = (r[k, j] - r[j, k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (r[j, i] + r[i, j]) / s
        q[1 + k] = (r[k, i] + r[i, k]) / s
    a = np.array(q)
    return a / np.linalg.norm(a)


def _place(el: ET.Element, pose: FloatArray) -> None:
    if np.any(pose[:3, 3]):
        el.set("pos", _num(pose[:3, 3]))
    if not np.allclose(pose[:3, :3], np.eye(3), rtol=0, atol=0):
        el.set("quat", _num(quaternion(pose[:3, :3])))


def model_to_mjcf(model: RobotModel, meshes: Any = None, contacts: bool = True) -> str:
    """The MJCF text of ``model`` (see the module)."""
    root = ET.Element("mujoco", model=model.name)
    ET.SubElement(
        root,
        "compiler",
        angle="radian",
        inertiafromgeom="false",
        boundmass=repr(BOUND),
        boundinertia=repr(BOUND),
    )
    ET.SubElement(root, "option", gravity=_num(model.gravity))
    contact = {"contype": "1", "conaffinity": "0"} if contacts else {"contype": "0", "conaffinity": "0"}
    world = ET.SubElement(root, "worldbody")
    bodies = [world]
    for j in model.joints:
        if not j.link.physical:
            try:
                inertia_tensor(j.link.inertia, "inertia")
            except InvalidParameterError:
                raise InvalidParameterError(
                    f"the inertia of the link of joint {j.name!r}, {j.link.inertia.tolist()}, is not that of a rigid "
                    "body (its principal moments violate the triangle inequality), which MuJoCo refuses; correct it "
                    "(e.g. armctl.models.puma560(physical=True))",
                    value=j.name,
                ) from None
    _friction_warning(model)
    for j in model.joints:
        body = ET.SubElement(bodies[-1], "body", name=j.name)
        _place(body, j.placement)
        attrs = {"name": j.name, "type": "hinge" if j.kind == "revolute" else "slide", "axis": _num(j.axis)}
        if math.isfinite(j.limits.lower) and math.isfinite(j.limits.upper):
            attrs.update(limited="true", range=_num([j.limits.lower, j.limits.upper]))
        fr = j.friction
        for key, value in (
            ("damping", fr.viscous),
            ("frictionloss", fr.coulomb_mean),
            ("armature", j.motor.reflected_inertia if j.motor is not None else 0.0),
        ):
            if value:
                attrs[key] = repr(float(value))
        ET.SubElement(body, "joint", attrs)
        link = j.link
        t = link.inertia
        ET.SubElement(
            body,
            "inertial",
            pos=_num(link.com),
            mass=repr(float(link.mass)),
            fullinertia=_num([t[0, 0], t[1, 1], t[2, 2], t[0, 1], t[0, 2], t[1, 2]]),
        )
        bodies.append(body)
    for f in model.frames:
        site = ET.SubElement(bodies[f.joint], "site", name=f.name)
        _place(site, f.placement)
    covered = _mesh_geoms(model, meshes, root, bodies, contact)
    _simple_geoms(model, bodies, covered, contact)
    motors = [(j.name, j.limits.effort) for j in model.joints if math.isfinite(j.limits.effort)]
    if motors:
        actuator = ET.SubElement(root, "actuator")
        for name, effort in motors:
            span = _num([-effort, effort])
            ET.SubElement(
                actuator,
                "motor",
                name=name,
                joint=name,
                gear="1",
                ctrllimited="true",
                ctrlrange=span,
                forcelimited="true",
                forcerange=span,
            )
    ET.indent(root)
    return ET.tostring(root, encoding="unicode") + "\n"


def _friction_warning(model: RobotModel) -> None:
    lost = []
    for j in model.joints:
        fr = j.friction
        what = []
        if fr.coulomb != fr.coulomb_neg:
            what.append(f"asymmetric Coulomb levels {fr.coulomb:g}/{fr.coulomb_neg:g} written as their mean")
        if fr.static is not None and fr.static > fr.coulomb_mean:
            what.append(f"breakaway level {fr.static:g} dropped")
        if fr.stribeck_velocity:
            what.append("Stribeck curve dropped")
        if what:
            lost.append(f"{j.name} ({', '.join(what)})")
    if lost:
        warnings.warn(
            "MuJoCo's joint friction (frictionloss) has one Coulomb level: " + "; ".join(lost),
            UserWarning,
            stacklevel=4,
        )


def _simple_geoms(model: RobotModel, bodies: list[ET.Element], covered: set[int], contact: dict[str, str]) -> None:
    """A capsule from each joint to the next one (the last: to the tool frame, if it rides on the last joint), a
    sphere where they coincide, on the links without a mesh."""
    ends = [j.placement[:3, 3] for j in model.joints[1:]]
    tool = model.frame(None)
    ends.append(tool.placement[:3, 3] if tool.joint == model.n else np.zeros(3))
    reach = sum(float(np.linalg.norm(e)) for e in ends)
    radius = min(max(0.04 * reach, 0.01), 0.05)
    for i, end in enumerate(ends, start=1):
        if i in covered:
            continue
        if np.linalg.norm(end) > radius:
            ET.SubElement(bodies[i], "geom", contact, type="capsule", fromto=_num([0, 0, 0, *end]), size=repr(radius))
        else:
            ET.SubElement(bodies[i], "geom", contact, type="sphere", size=repr(radius))


def _mesh_geoms(
    model: RobotModel, meshes: Any, root: ET.Element, bodies: list[ET.Element], contact: dict[str, str]
) -> set[int]:
    """Geoms of the URDF ``meshes`` (see :func:`model_to_mjcf`) on their links; returns the joints that got one."""
    if meshes is False:
        return set()
    if meshes is None or meshes is True:
        source = model.source
        if source is None or not source.lower().endswith(".urdf"):
            return set()
        meshes = source
    if not isinstance(meshes, str | os.PathLike) or not os.path.isfile(meshes):
        raise InvalidParameterError(
            f"meshes must be the path of a URDF file, None (the model's source) or False (simple shapes); got "
            f"{meshes!r}",
            value=meshes,
        )
    path = Path(meshes)
    try:
        links = ET.parse(path).getroot().findall("link")
    except ET.ParseError as exc:
        raise InvalidParameterError(f"cannot read the URDF {str(path)!r}: {exc}", value=str(path)) from exc
    asset = ET.Element("asset")
    covered: set[int] = set()
    missing: list[str] = []
    for link in links:
        try:
            frame = model.frame(link.get("name", ""))
        except UnknownNameError:
            continue
        shapes = _urdf_shapes(link, "collision", path, missing) or _urdf_shapes(link, "visual", path, missing)
        for origin, attrs, mesh in shapes:
            geom = ET.SubElement(bodies[frame.joint], "geom", attrs, **contact)
            _place(geom, frame.placement @ origin)
            if mesh is not None:
                name = f"mesh{len(asset)}"
                ET.SubElement(asset, "mesh", name=name, file=str(mesh[0]), scale=_num(mesh[1]))
                geom.set("mesh", name)
            if frame.joint:
                covered.add(frame.joint)
    if len(asset):
        root.insert(2, asset)
    if missing:
        warnings.warn(
            f"meshes of {str(path)!r} that MuJoCo cannot read or that were not found, left out: "
            + ", ".join(sorted(set(missing))),
            UserWarning,
            stacklevel=4,
        )
    return covered


def _urdf_shapes(
    link: ET.Element, kind: str, urdf: Path, missing: list[str]
) -> list[tuple[FloatArray, dict[str, str], tuple[Path, FloatArray] | None]]:
    """(pose on the link, geom attributes, (mesh file, scale) or None) of a URDF link's ``kind`` elements, or []
    if one of them cannot be read."""
    out: list[tuple[FloatArray, dict[str, str], tuple[Path, FloatArray] | None]] = []
    for el in link.findall(kind):
        origin = el.find("origin")
        pose = np.eye(4)
        if origin is not None:
            r, p, y = (float(v) for v in origin.get("rpy", "0 0 0").split())
            turn = rot((0, 0, 1), y) @ rot((0, 1, 0), p) @ rot((1, 0, 0), r)  # URDF's rpy: fixed axes x, y, z
            pose = transform(turn, [float(v) for v in origin.get("xyz", "0 0 0").split()])
        geometry = el.find("geometry")
        shape = geometry[0] if geometry is not None and len(geometry) else None
        if shape is None:
            continue
        if shape.tag == "mesh":
            file = _resolve(shape.get("filename", ""), urdf)
            if file is None or file.suffix.lower() not in MESH_FORMATS:
                missing.append(shape.get("filename", "?"))
                return []
            scale = np.array([float(v) for v in shape.get("scale", "1 1 1").split()])
            out.append((pose, {"type": "mesh"}, (file, scale)))
        elif shape.tag == "box":
            half = 0.5 * np.array([float(v) for v in shape.get("size", "0 0 0").split()])
            out.append((pose, {"type": "box", "size": _num(half)}, None))
        elif shape.tag == "cylinder":
            size = [float(shape.get("radius", 0)), 0.5 * float(shape.get("length", 0))]
            out.append((pose, {"type": "cylinder", "size": _num(size)}, None))
        elif shape.tag == "sphere":
            out.append((pose, {"type": "sphere", "size": _num(float(shape.get("radius", 0)))}, None))
    return out


def _resolve(filename: str, urdf: Path) -> Path | None:
    """The file a URDF names: ``package://NAME/rest`` looked up in the folders above the URDF (a folder called NAME,
    or holding NAME) and in ``ROS_PACKAGE_PATH``; ``file://`` and relative paths from the URDF's folder."""
    if filename.startswith("package://"):
        package, _, rest = filename[len("package://") :].partition("/")
        roots = list(urdf.resolve().parents) + [Path(p) for p in os.environ.get("ROS_PACKAGE_PATH", "").split(":") if p]
        for d in roots:
            for candidate in (d / rest if d.name == package else None, d / package / rest):
                if candidate is not None and candidate.is_file():
                    return candidate
        return None
    name = filename.removeprefix("file://")
    path = Path(name) if os.path.isabs(name) else urdf.parent / name
    return path if path.is_file() else None
