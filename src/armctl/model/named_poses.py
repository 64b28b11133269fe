"""Named joint configurations of a model (``RobotModel.named_poses``): checked once, when the model is made.

Poses given to a model are checked strictly (size, finite, within the joint limits). Poses a model carries over
from the one it was made from (a :class:`NamedPoses`: a variant, ``dataclasses.replace`` with other joints) follow
its new joints: clipped into new limits, left out if the number of joints changed.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, readonly, vector
from armctl.errors import InvalidParameterError
from armctl.model.parts import name_text


class NamedPoses(dict[str, FloatArray]):
    """The named poses a model holds: a dict of name → read-only joint vector (n,) [rad or m]."""


def zero_pose(lower: FloatArray, upper: FloatArray) -> FloatArray:
    """Every joint at 0, or at the end of its range nearest to 0 where 0 is outside it (the Panda's joint 4).

    Parameters
    ----------
    lower, upper : ndarray, shape (n,)
        The joints' position limits [rad or m].

    Returns
    -------
    ndarray, shape (n,)
        The pose (read-only).
    """
    return readonly(np.clip(np.zeros(len(lower)), lower, upper))


def checked_poses(
    poses: Mapping[str, ArrayLike] | None, lower: FloatArray, upper: FloatArray, joint_names: tuple[str, ...]
) -> NamedPoses:
    """The named poses of a model: those given, as read-only float vectors, with ``"zero"`` (:func:`zero_pose`)
    added where it is not given; a :class:`NamedPoses` (carried over from another model) is fitted to the joints
    instead of checked (see the module).

    Parameters
    ----------
    poses : mapping of str to array_like, or None
        Name → joint vector (n,) [rad or m].
    lower, upper : ndarray, shape (n,)
        The joints' position limits.
    joint_names : tuple of str
        The joints' names (for the messages).

    Returns
    -------
    dict of str to ndarray

    Raises
    ------
    InvalidParameterError
        ``poses`` is not a mapping, a name is not a non-empty string, or a pose is outside the joint limits (the
        joint and its range are named).
    ShapeError, NonFiniteError
        A pose of the wrong size or not finite.
    """
    if poses is not None and not isinstance(poses, Mapping):
        raise InvalidParameterError(
            f"named_poses must be a mapping of name to joint vector, got {type(poses).__name__}", value=poses
        )
    out = NamedPoses()
    if isinstance(poses, NamedPoses):
        for name, carried in poses.items():
            if carried.shape == lower.shape:
                out[name] = readonly(np.clip(carried, lower, upper))
        out.setdefault("zero", zero_pose(lower, upper))
        return out
    for name, q in (poses or {}).items():
        name_text(name, "pose name")
        v = np.array(vector(q, len(lower), f"named pose {name!r}"), dtype=float)
        outside = np.flatnonzero((v < lower) | (v > upper))
        if outside.size:
            j = int(outside[0])
            raise InvalidParameterError(
                f"named pose {name!r} puts {joint_names[j]} at {v[j]:g}, outside its range [{lower[j]:g}, "
                f"{upper[j]:g}]: give a pose within the joint limits",
                value=q,
            )
        out[name] = readonly(v)
    if "zero" not in out:
        out["zero"] = zero_pose(lower, upper)
    return out
