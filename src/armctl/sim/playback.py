"""`playback`: a run as a standalone HTML page that plays the arm's motion in 3D, with a time slider.

The page embeds everything it shows: the meshcat viewer (three.js; MIT licence, shipped in the ``meshcat``
Python package: ``pip install armctl[view]``), the arm's meshes (:mod:`armctl.sim.visuals`: example-robot-data's
where the model has them, simple shapes otherwise) and the motion, as meshcat commands. It loads nothing from
the network when it is viewed, so it can be mailed, archived or opened offline.

What it draws: the arm at the recorded samples (``fps`` frames a second of run time, the nearest sample each),
the tool's path (blue) and the reference's tool path (orange) where the result holds its reference, each contact
point's force on the arm as a red arrow (length proportional to the force, the scale written on the page), and
the planes of ``environment``.
"""

from __future__ import annotations

import base64
import math
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from armctl._checks import FloatArray, scalar
from armctl.errors import BackendError, InvalidParameterError, ShapeError, UnknownNameError
from armctl.model.robot import RobotModel
from armctl.sim.playback_page import page as _page
from armctl.sim.visuals import MESHES, parts, reach

if TYPE_CHECKING:
    from armctl.sim.contact import Environment
    from armctl.sim.run_record import RunRecord

#: at most this many frames in a page (a longer run is shown at a lower frame rate)
MAX_FRAMES = 3000
#: the longest contact arrow, as a share of the arm's reach
ARROW_SHARE = 0.35
TOOL_COLOUR, REFERENCE_COLOUR, FORCE_COLOUR, PLANE_COLOUR = 0x1F6FD6, 0xF08A24, 0xD62828, 0x6C8EA4


def _meshcat() -> Any:
    try:
        with warnings.catch_warnings():  # meshcat's server module, imported with it, uses a deprecated pyzmq API
            warnings.simplefilter("ignore", DeprecationWarning)
            import meshcat.geometry as mg
            import umsgpack
    except ImportError as exc:
        raise BackendError(
            f"the 3D playback needs the meshcat package ({exc}): pip install 'armctl[view]' (or pip install meshcat)"
        ) from exc
    return mg, umsgpack


def frame_samples(t: FloatArray, fps: float) -> tuple[FloatArray, float]:
    """Indices of the samples shown as frames, ``fps`` a second of run time (fewer if there would be more than
    :data:`MAX_FRAMES`), the nearest sample to each frame time; and the frame rate used."""
    duration = float(t[-1] - t[0]) if len(t) > 1 else 0.0
    rate = min(fps, (MAX_FRAMES - 1) / duration) if duration > 0 else fps
    count = math.floor(duration * rate + 1e-9) + 1
    times = t[0] + np.arange(count) / rate
    idx = np.clip(np.searchsorted(t, times), 0, len(t) - 1)
    left = np.clip(idx - 1, 0, len(t) - 1)
    idx = np.where(np.abs(t[left] - times) <= np.abs(t[idx] - times), left, idx)
    return idx, rate


def _quaternion(rot: FloatArray) -> list[float]:
    """[x, y, z, w] of a rotation matrix (three.js's order)."""
    import pinocchio as pin

    x, y, z, w = pin.Quaternion(np.asarray(rot, dtype=float)).coeffs()
    return [float(x), float(y), float(z), float(w)]


class _Scene:
    """meshcat commands (lowered dicts) and animation tracks, under ``/meshcat/<root>``."""

    def __init__(self, root: str, fps: float) -> None:
        self.root = f"/meshcat/{root}"
        self.fps = fps
        self.commands: list[dict[str, Any]] = []
        self.clips: dict[str, list[dict[str, Any]]] = {}

    def path(self, name: str) -> str:
        return f"{self.root}/{name}"

    def add(self, name: str, geometry: Any, colour: int | None, opacity: float = 1.0, matrix: Any = None) -> str:
        mg, _ = _meshcat()
        from meshcat.commands import SetObject, SetTransform
        from meshcat.path import Path as MeshcatPath

        path = self.path(name)
        mpath = MeshcatPath(tuple(p for p in path.split("/") if p))
        material = None
        if colour is not None:
            material = mg.MeshPhongMaterial(color=colour, opacity=opacity, transparent=opacity < 1.0)
        if hasattr(geometry, "dae_raw"):  # a Collada mesh: it lowers itself, textures included
            geometry.path = mpath
            if material is not None:
                geometry.material = material
            self.commands.append(geometry.lower())
        elif isinstance(geometry, mg.Object):
            self.commands.append(SetObject(geometry, path=mpath).lower())
        else:
            self.commands.append(_current_types(SetObject(geometry, material, path=mpath).lower()))
        if matrix is not None:
            self.commands.append(SetTransform(np.asarray(matrix, dtype=float), mpath).lower())
        return path

    def track(self, path: str, name: str, kind: str, values: list[Any]) -> None:
        keys = [{"time": i, "value": v} for i, v in enumerate(values)]
        self.clips.setdefault(path, []).append({"name": f".{name}", "type": kind, "keys": keys})

    def pose_tracks(self, path: str, poses: list[FloatArray]) -> None:
        self.track(path, "position", "vector3", [[float(x) for x in p[:3, 3]] for p in poses])
        self.track(path, "quaternion", "quaternion", [_quaternion(p[:3, :3]) for p in poses])

    def property(self, path: str, key: str, value: Any) -> None:
        self.commands.append({"type": "set_property", "path": path, "property": key, "value": value})

    def encoded(self) -> list[str]:
        """Every command, the animation last, msgpack-encoded in base64."""
        _, umsgpack = _meshcat()
        animation = {
            "type": "set_animation",
            "path": "",
            "animations": [
                {"path": path, "clip": {"fps": self.fps, "name": "default", "tracks": tracks}}
                for path, tracks in self.clips.items()
            ],
            "options": {"play": True, "repetitions": 1},
        }
        return [base64.b64encode(umsgpack.packb(c)).decode("ascii") for c in (*self.commands, animation)]


def _current_types(command: dict[str, Any]) -> dict[str, Any]:
    """A lowered set_object command with its mesh files under the type the viewer reads without a console
    warning: meshcat's Python package lowers a mesh file as "_meshfile", which its viewer reads as the deprecated
    spelling of "_meshfile_geometry"."""
    for geometry in command.get("object", {}).get("geometries", []):
        if geometry.get("type") == "_meshfile":
            geometry["type"] = "_meshfile_geometry"
    return command


def _line(points: FloatArray, colour: int) -> Any:
    mg, _ = _meshcat()
    geometry = mg.PointsGeometry(np.asarray(points, dtype=float).T)
    return mg.Line(geometry, mg.LineBasicMaterial(color=colour, linewidth=2))


def _arrows(scene: _Scene, res: RunRecord, idx: FloatArray, size: float) -> str:
    """A red arrow per contact point, animated: at the point, along the force on the arm (contact_force_on_robot),
    of length |F| × scale. Returns the scale's text for the page ("" without contact forces)."""
    mg, _ = _meshcat()
    from armctl.sim.visuals import _rotation_y_to

    forces = np.asarray(res.contact_force_on_robot)[idx]  # the environment's force on the arm
    positions = res.contact_position
    if forces.size == 0 or positions is None or not np.abs(forces).max() > 0.0:
        return ""
    positions = np.asarray(positions)[idx]
    peak = float(np.linalg.norm(forces, axis=2).max())
    scale = ARROW_SHARE * size / peak  # m per N
    shaft_r, head_r, head_h = 0.008 * size, 0.02 * size, 0.05 * size
    for p in range(forces.shape[1]):
        arrow = f"contact_force_{p}"
        shaft_len, head_pos, visible, poses = [], [], [], []
        for k in range(len(idx)):
            f = forces[k, p]
            magnitude = float(np.linalg.norm(f))
            pose = np.eye(4)
            pose[:3, 3] = positions[k, p]
            if magnitude > 1e-9 * peak:
                pose[:3, :3] = _rotation_y_to(f)
            length = max(magnitude * scale - head_h, 1e-6)
            poses.append(pose)
            shaft_len.append([1.0, length, 1.0])
            head_pos.append([0.0, length + head_h / 2.0, 0.0])
            visible.append(bool(magnitude > 1e-9 * peak))
        # the arrow's node turns and moves with the force; its shaft (a unit cylinder from the node's origin along
        # y) is stretched to the length, its head (a cone) moved to the shaft's end
        root, shaft, head = scene.path(arrow), scene.path(f"{arrow}/shaft"), scene.path(f"{arrow}/head")
        centre = np.eye(4)
        centre[1, 3] = 0.5
        scene.add(f"{arrow}/shaft/body", mg.Cylinder(1.0, shaft_r), FORCE_COLOUR, matrix=centre)
        scene.add(f"{arrow}/head", mg.Cylinder(head_h, radiusTop=0.0, radiusBottom=head_r), FORCE_COLOUR)
        scene.pose_tracks(root, poses)
        scene.track(root, "visible", "boolean", visible)
        scene.track(shaft, "scale", "vector3", shaft_len)
        scene.track(head, "position", "vector3", head_pos)
    return f"red arrows: contact force on the arm, {1000.0 * scale:.3g} mm per N (largest {peak:.3g} N)"


def _planes(scene: _Scene, environment: Any, centre: FloatArray, size: float) -> None:
    mg, _ = _meshcat()
    from armctl.sim.contact import Plane
    from armctl.sim.visuals import _rotation_y_to

    envs = () if environment is None else (environment,) if not isinstance(environment, list | tuple) else environment
    for e, env in enumerate(envs):
        if not isinstance(env, Plane):
            continue
        normal = np.asarray(env.normal, dtype=float)
        pose = np.eye(4)
        pose[:3, :3] = _rotation_y_to(normal)
        # the plane's point nearest the arm's workspace centre, the slab just under the surface
        pose[:3, 3] = centre - float(normal @ (centre - env.point)) * normal - normal * 0.0025
        side = 1.2 * size
        scene.add(f"environment_{e}", mg.Box([side, 0.005, side]), PLANE_COLOUR, opacity=0.45, matrix=pose)


def _ground_and_camera(scene: _Scene, low: FloatArray, high: FloatArray, size: float) -> None:
    """The ground grid under everything the arm sweeps (``low``, ``high``: the corners of its box [m]), sized to
    the arm (cells of a tenth of its reach), and the camera on the box's centre, from ahead, to the side and
    above, far enough to see the whole box."""
    centre = (low + high) / 2.0
    ground = np.diag([0.2 * size, 0.2 * size, 0.2 * size, 1.0])  # meshcat's grid: 20 m, in 0.5 m cells
    ground[:3, 3] = [centre[0], centre[1], min(0.0, float(low[2])) - 0.01 * size]
    scene.commands.append({"type": "set_transform", "path": "/Grid", "matrix": ground.T.flatten().tolist()})
    cam = np.eye(4)
    cam[:3, 3] = centre
    scene.commands.append({"type": "set_transform", "path": "/Cameras/default", "matrix": cam.T.flatten().tolist()})
    # the camera's offset from its target, in three.js axes (y up): 30° above the horizon
    reach = max(float(np.linalg.norm(high - low)) / 2.0, 0.3 * size)
    scene.property("/Cameras/default/rotated/<object>", "position", [1.6 * reach, 1.3 * reach, 1.6 * reach])


def playback(
    res: RunRecord,
    path: str | Path,
    model: RobotModel | None = None,
    *,
    fps: float = 30.0,
    meshes: str = "collision",
    environment: Environment | list[Environment] | tuple[Environment, ...] | None = None,
    title: str | None = None,
) -> Path:
    """Write a run as a standalone HTML page that plays the arm's motion in 3D, with play/pause and a time slider.

    Parameters
    ----------
    res : SimResult or RunRecord
        The run (what it reads of it: :class:`~armctl.sim.run_record.RunRecord`).
    path : str or path-like
        The page (``.html`` added if missing).
    model : RobotModel, optional
        The arm (default: ``res.plant``, the model the run simulated; needed for a result read from a file).
    fps : float, optional
        Frames a second of run time (at most :data:`MAX_FRAMES` in all).
    meshes : {"collision", "visual", "shapes"}, optional
        ``"collision"`` (the default): the example-robot-data collision meshes of a model that has them (a page
        about ten times smaller than with the visual meshes), else simple shapes; ``"visual"``: that
        description's visual meshes (textured, larger); ``"shapes"``: simple shapes.
    environment : Environment or sequence of Environment, optional
        Contact environments to draw (their planes), e.g. the run's own.
    title : str, optional
        The page's heading (default: the plant's name, the status and the duration).

    Returns
    -------
    pathlib.Path
        The page written.

    Raises
    ------
    BackendError
        meshcat is not installed.
    InvalidParameterError
        A result without samples or without a model to draw.
    ShapeError
        ``model`` has another number of joints.
    """
    _meshcat()
    model = res.plant if model is None else model
    if not isinstance(model, RobotModel):
        raise InvalidParameterError(
            "the result does not know its arm (it was read from a file): pass model=, the RobotModel it simulated",
            value=model,
        )
    if model.n != res.n:
        raise ShapeError(f"model has {model.n} joints, the result {res.n}", value=model)
    if not len(res.t):
        raise InvalidParameterError("the result has no samples: there is no motion to play", value=res)
    if not isinstance(meshes, str) or meshes not in MESHES:
        raise UnknownNameError("meshes", meshes, MESHES)
    fps = scalar(fps, "fps [frames/s]", positive=True)
    path = Path(path)
    if path.suffix != ".html":
        path = path.with_name(path.name + ".html")

    import pinocchio as pin

    idx, rate = frame_samples(np.asarray(res.t), fps)
    pm = model.to_pinocchio()
    pd = pm.createData()
    tool_id = pm.getFrameId(model.tool_frame) if model.tool_frame is not None else None
    joint_poses, tool, points = [], [], []
    for k in idx:
        pin.forwardKinematics(pm, pd, np.asarray(res.q[k], dtype=float))
        joint_poses.append([np.array(pd.oMi[j].homogeneous) for j in range(pm.njoints)])
        points += [pose[:3, 3] for pose in joint_poses[-1]]
        if tool_id is not None:
            pin.updateFramePlacement(pm, pd, tool_id)
            tool.append(np.array(pd.oMf[tool_id].translation))
        else:
            tool.append(np.array(pd.oMi[pm.njoints - 1].translation))
    size = reach(model)
    scene = _Scene(model.name, rate)
    drawn, source = parts(model, meshes)
    for part in drawn:
        node = scene.add(part.name, part.geometry, part.colour, part.opacity)
        poses = [frame[part.joint] @ part.placement for frame in joint_poses]
        scene.pose_tracks(node, poses)
        if part.scale != (1.0, 1.0, 1.0):
            scene.track(node, "scale", "vector3", [list(part.scale)] * len(poses))
    tool_path = np.array(tool)
    legend = [f"drawn with {source}"]
    if len(tool_path) > 1:
        scene.add("tool_path", _line(tool_path, TOOL_COLOUR), None)
        legend.append("blue line: tool path")
    if res.reference is not None and len(res.reference.q):
        ref_path = []
        for k in idx:
            pin.forwardKinematics(pm, pd, np.asarray(res.reference.q[k], dtype=float))
            if tool_id is not None:
                pin.updateFramePlacement(pm, pd, tool_id)
                ref_path.append(np.array(pd.oMf[tool_id].translation))
            else:
                ref_path.append(np.array(pd.oMi[pm.njoints - 1].translation))
        if len(ref_path) > 1:
            scene.add("reference_path", _line(np.array(ref_path), REFERENCE_COLOUR), None)
            legend.append("orange line: the reference's tool path")
    arrows = _arrows(scene, res, idx, size)
    if arrows:
        legend.append(arrows)
    _planes(scene, environment, tool_path.mean(axis=0), size)
    if environment is not None:
        legend.append("grey slab: contact plane")
    swept = np.vstack([np.array(points), tool_path])
    _ground_and_camera(scene, swept.min(axis=0), swept.max(axis=0), size)
    if title is None:
        title = f"{res.info.get('plant', model.name)}: {res.status}, {res.duration:g} s"
    page = _page(scene.encoded(), title, legend, float(res.t[idx[0]]), (len(idx) - 1) / rate, rate)
    try:
        path.write_text(page, encoding="utf-8")
    except OSError as e:
        raise InvalidParameterError(
            f"cannot write the playback to {str(path)!r}: {e.strerror or e}; pass a path in an existing, writable "
            "folder",
            value=str(path),
        ) from e
    return path
