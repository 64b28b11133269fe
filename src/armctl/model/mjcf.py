"""MJCF (MuJoCo) descriptions → :class:`~armctl.RobotModel`.

MuJoCo compiles the description (defaults, ``<include>``, angle units, orientation forms, inertias inferred from
geoms, ``fullinertia`` diagonalised, ``boundmass``/``boundinertia``); the arm is read from the compiled
``mjModel``, so what armctl gets is exactly what MuJoCo simulates:

* the chain: from ``base`` (default: the one subtree of the world that has joints) down to the last joint, one
  body after another; bodies without joints are welded to the link that carries them (their mass added to it),
  subtrees without joints are welded too; two moving branches, ball and free joints are refused by name;
* a body's joints, in order, each a :class:`~armctl.model.parts.Joint` whose frame is the body's frame moved to the
  joint's ``pos`` (a hinge turns about that point, as in MuJoCo), its axis MuJoCo's ``axis``; armctl's q is MuJoCo's
  ``qpos`` (a joint's ``ref`` is folded into its placement);
* link inertias from ``body_mass``, ``body_ipos``, ``body_iquat`` and the principal moments ``body_inertia``;
* ``damping`` → viscous friction F_v, ``frictionloss`` → Coulomb friction F_c, ``armature`` → a
  :class:`~armctl.model.parts.Motor` of that inertia and gear ratio 1 without gyroscopic coupling (MuJoCo's
  armature is reflected inertia only);
* ``range`` of limited joints → position limits; actuator force ranges (``forcerange`` times ``gear`` of the
  actuators that drive a joint, or ``gear`` × gain × ``ctrlrange`` of a plain ``motor``) and a joint's
  ``actuatorfrcrange`` → effort limits (the smaller magnitude of an asymmetric range);
* every named body and site on the chain → a :class:`~armctl.model.parts.Frame`; ``option/gravity`` → gravity;
* joints given in ``lock`` are held at their positions: their bodies are welded to the body that carries them,
  so that a gripper's fingers (a branch whose joints are all locked) ride on the hand.

Joint springs (``stiffness``) and polynomial damping have no counterpart in a RobotModel and raise
:class:`~armctl.errors.ModelLoadError`; gravity compensation (``gravcomp``) is reported by a warning (the model
keeps full gravity).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import Any

from armctl._mujoco import require_mujoco
from armctl.errors import InvalidParameterError, ModelLoadError
from armctl.model.mjcf_chain import MjcfChain, joint_name, read_chain
from armctl.model.pinocchio_io import lock_positions
from armctl.model.robot import RobotModel

__all__ = ["MjcfChain", "compile_mjcf", "model_from_mjcf", "read_chain"]


def compile_mjcf(source: Any, what: str = "RobotModel.from_mjcf") -> tuple[Any, str | None]:
    """Compile an MJCF description with MuJoCo.

    Parameters
    ----------
    source : str, path-like, mujoco.MjSpec or mujoco.MjModel
        A file path, an MJCF text (starting with ``<``), a spec or a compiled model.
    what : str, optional
        The caller's name, for the error messages.

    Returns
    -------
    tuple of (mujoco.MjModel, str or None)
        The compiled model and the file path (None for a text, a spec or a model).

    Raises
    ------
    ModelLoadError
        The description does not compile (MuJoCo's words), or mujoco is not installed.
    """
    mj = require_mujoco(what)
    if isinstance(source, mj.MjModel):
        return source, None
    spec_type = getattr(mj, "MjSpec", None)  # (MuJoCo >= 3.2)
    if spec_type is not None and isinstance(source, spec_type):
        try:
            return source.compile(), None
        except Exception as exc:  # MuJoCo raises ValueError with the compiler's message
            raise ModelLoadError(f"cannot compile the MjSpec: {exc}", value=source) from exc
    if not isinstance(source, str | os.PathLike):
        raise InvalidParameterError(
            f"an MJCF model must be a file path, an XML text, a mujoco.MjSpec or a mujoco.MjModel; got "
            f"{type(source).__name__}",
            value=source,
        )
    if isinstance(source, str) and source.lstrip().startswith("<"):
        try:
            return mj.MjModel.from_xml_string(source), None
        except Exception as exc:
            raise ModelLoadError(f"cannot read the MJCF text: {exc}", value=source[:200]) from exc
    path = os.fspath(source)
    if not os.path.isfile(path):
        raise ModelLoadError(f"MJCF file not found: {path!r}", value=path)
    try:
        return mj.MjModel.from_xml_path(path), path
    except Exception as exc:
        raise ModelLoadError(f"cannot read MJCF {path!r}: {exc}", value=path) from exc


def model_from_mjcf(
    source: Any,
    tool_frame: str | None = None,
    base: str | None = None,
    name: str | None = None,
    lock: Sequence[str] | Mapping[str, float] | None = None,
) -> RobotModel:
    """The arm of an MJCF description (see the module for what is read and how); the function behind
    :meth:`RobotModel.from_mjcf <armctl.model.RobotModel.from_mjcf>`.

    Parameters
    ----------
    source, tool_frame, base, name, lock
        As for :meth:`RobotModel.from_mjcf <armctl.model.RobotModel.from_mjcf>` (``source`` is its
        ``path_or_xml``).

    Returns
    -------
    RobotModel

    Raises
    ------
    ModelLoadError, UnknownNameError
        As for :meth:`RobotModel.from_mjcf <armctl.model.RobotModel.from_mjcf>`.
    """
    m, path = compile_mjcf(source)
    mj = require_mujoco("RobotModel.from_mjcf")
    kinds = (int(mj.mjtJoint.mjJNT_HINGE), int(mj.mjtJoint.mjJNT_SLIDE))
    names = [n for j in range(m.njnt) if int(m.jnt_type[j]) in kinds and (n := joint_name(m, j))]
    positions = lock_positions(lock, names)
    chain = read_chain(m, base, path or "the MJCF model", positions)
    return RobotModel(
        chain.joints,
        name=name or chain.name or (os.path.splitext(os.path.basename(path))[0] if path else "mjcf_robot"),
        gravity=chain.gravity,
        frames=chain.frames,
        tool_frame=tool_frame,
        source=path,
    )
