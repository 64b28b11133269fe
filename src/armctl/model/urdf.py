"""URDF files → :class:`~armctl.RobotModel`, through Pinocchio's parser."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

from numpy.typing import ArrayLike

from armctl._checks import boolean
from armctl.errors import InvalidParameterError, ModelLoadError, UnknownNameError

if TYPE_CHECKING:
    from armctl.model.robot import RobotModel


def model_from_urdf(
    path: str | os.PathLike[str],
    tool_frame: str | None = None,
    lock: Sequence[str] | Mapping[str, float] = (),
    gravity: ArrayLike = (0, 0, -9.81),
    name: str | None = None,
    physical: bool = True,
) -> RobotModel:
    """A model from a URDF file through Pinocchio's parser.

    URDF ``<dynamics damping friction>`` become viscous and Coulomb friction. Every link and fixed joint becomes a
    named frame, those fixed to the world included (the base link, and with the first joint locked its link and the
    locked joint's frame); a root link called ``"world"`` is the model's own ``"world"`` frame. The file is checked
    before Pinocchio reads it (:mod:`armctl.model.urdf_checks`).

    Parameters
    ----------
    path : str or path-like
        The URDF file.
    tool_frame : str, optional
        The frame a method given ``frame=None`` uses (None: the last joint's).
    lock : str, sequence of str or mapping str → float, optional
        Joints held fixed: names (locked at 0) or name → position [rad or m], checked as in
        :meth:`~armctl.model.RobotModel.reduced`.
    gravity : array_like, shape (3,), optional
        g [m/s²] in world axes.
    name : str, optional
        The model's name (None: the URDF's robot name).
    physical : bool, optional
        False accepts link inertias that violate the triangle inequality, as published data sets have some (see
        :class:`~armctl.model.parts.Link`).

    Returns
    -------
    RobotModel

    Raises
    ------
    ModelLoadError
        A number Pinocchio cannot read (an ``<inertial>`` that would leave its link massless), duplicate or missing
        names, a link called ``universe``, a ``<mimic>`` joint not given in ``lock`` (a model's joints are
        independent), or a ``"world"`` frame other than the root link; each naming the link or joint.
    """
    import pinocchio as pin

    from armctl.model.pinocchio_io import joints_from_pinocchio, lock_positions
    from armctl.model.robot import RobotModel
    from armctl.model.urdf_checks import check_urdf

    if not isinstance(path, str | os.PathLike):
        raise InvalidParameterError(f"URDF path must be a str or a path, got {path!r}", value=path)
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise ModelLoadError(f"URDF file not found: {path!r}", value=path)
    physical = boolean(physical, "physical")
    mimic = check_urdf(path)
    try:
        pm = pin.buildModelFromUrdf(path)
    except Exception as exc:  # pinocchio raises plain ValueError/RuntimeError with the parser's words
        raise ModelLoadError(f"cannot read URDF {path!r}: {exc}", value=path) from exc
    positions = lock_positions(lock, list(pm.names)[1:])
    if positions:
        q = pin.neutral(pm)
        ids = []
        for jname, value in positions.items():
            jid = pm.getJointId(jname)
            q[pm.idx_qs[jid]] = value
            ids.append(jid)
        pm = pin.buildReducedModel(pm, ids, q)
    joints, frames = joints_from_pinocchio(pm, path, physical)
    free = [j for j in mimic if j not in positions]
    if free:
        pairs = ", ".join(f"{j!r} follows {mimic[j]!r}" for j in free)
        raise ModelLoadError(
            f"{path}: <mimic> joints are not supported ({pairs}): a model's joints move independently, so each "
            f"would move on its own. Lock them (lock={free!r}) to hold them fixed, or remove their <mimic> element "
            "to make them independent joints",
            value=path,
        )
    model = RobotModel(
        tuple(joints),
        name=name or pm.name or os.path.basename(path),
        gravity=gravity,
        frames=tuple(frames),
        source=path,
    )
    if tool_frame is not None:
        if tool_frame not in model.frame_names:
            raise UnknownNameError("frame", tool_frame, model.frame_names)
        model = replace(model, tool_frame=tool_frame)
    return model
