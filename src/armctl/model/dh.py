"""Denavit–Hartenberg tables → :class:`~armctl.RobotModel` (standard and modified conventions)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, scalar
from armctl.errors import InvalidParameterError
from armctl.model.parts import (
    JOINT_KINDS,
    Frame,
    Joint,
    JointFriction,
    JointLimits,
    Link,
    Motor,
    homogeneous,
    instance_of,
    name_text,
    rot,
    transform,
)

if TYPE_CHECKING:
    from armctl.model.robot import RobotModel

_Z = np.array([0.0, 0.0, 1.0])
_X = np.array([1.0, 0.0, 0.0])


@dataclass(frozen=True, eq=False)  # numpy fields: compare by identity
class DHLink:
    """One row of a DH table and the body it moves.

    Parameters
    ----------
    d, a : float, optional
        The DH offsets [m] (for a prismatic joint ``d`` is the offset of the joint variable).
    alpha, offset : float, optional
        The DH twist and joint-angle offset [rad] (for a prismatic joint ``offset`` is θ).
    kind : {"revolute", "prismatic"}, optional
        How the joint moves.
    mass : float, optional
        [kg].
    com : array_like, shape (3,), optional
        The centre of mass [m] in the DH link frame {i}, as in Corke's toolbox.
    inertia : array_like, optional
        The inertia about the centre of mass [kg·m²] in frame {i} (as for :class:`~armctl.model.parts.Link`).
    motor : Motor, optional
        As in :mod:`armctl.model.parts`; a motor's explicit spin ``axis`` is in the DH frame {i−1} of the link the
        rotor rides on (the base frame {0} for the first joint). Joint i's axis there is z in the standard
        convention (``Motor(axis=(0, 0, 1))`` spins about the joint axis, as ``axis=None`` does) and Rx(α)z in the
        modified one (z of {i−1} is joint i − 1's).
    friction : JointFriction, optional
        The joint's friction.
    limits : JointLimits, optional
        The joint's limits.
    name : str, optional
        The joint's name (None: ``joint<i>``, 1-based).
    physical : bool, optional
        As for :class:`~armctl.model.parts.Link`.
    """

    d: float = 0.0
    a: float = 0.0
    alpha: float = 0.0
    offset: float = 0.0
    kind: str = "revolute"
    mass: float = 0.0
    com: ArrayLike = (0.0, 0.0, 0.0)
    inertia: ArrayLike = (0.0, 0.0, 0.0)
    motor: Motor | None = None
    friction: JointFriction = field(default_factory=JointFriction)
    limits: JointLimits = field(default_factory=JointLimits)
    name: str | None = None
    physical: bool = True

    def __post_init__(self) -> None:
        for k in ("d", "a", "alpha", "offset"):
            object.__setattr__(self, k, scalar(getattr(self, k), f"DH parameter {k}"))
        if not isinstance(self.kind, str) or self.kind not in JOINT_KINDS:
            raise InvalidParameterError(
                f"DH joint kind must be one of {JOINT_KINDS}, got {self.kind!r}", value=self.kind
            )
        if self.name is not None:
            name_text(self.name, "DH link name")
        body = Link(self.mass, self.com, self.inertia, self.physical)  # checks the body here, not in from_dh
        for k in ("mass", "com", "inertia", "physical"):
            object.__setattr__(self, k, getattr(body, k))
        instance_of(self.motor, Motor, "DH link motor", optional=True)
        instance_of(self.friction, JointFriction, "DH link friction (JointFriction() for none)")
        instance_of(self.limits, JointLimits, "DH link limits (JointLimits() for none)")


def _std(link: DHLink) -> FloatArray:
    """Rz(θ_off) Tz(d) Tx(a) Rx(α): the link-frame offset from the joint frame (standard DH)."""
    return (
        transform(rot(_Z, link.offset))
        @ transform(None, [0, 0, link.d])
        @ transform(None, [link.a, 0, 0])
        @ transform(rot(_X, link.alpha))
    )


def _mod(link: DHLink) -> FloatArray:
    """Rx(α) Tx(a) Rz(θ_off) Tz(d): the joint frame in the previous link frame (modified DH)."""
    return (
        transform(rot(_X, link.alpha))
        @ transform(None, [link.a, 0, 0])
        @ transform(rot(_Z, link.offset))
        @ transform(None, [0, 0, link.d])
    )


def model_from_dh(
    links: Sequence[Any],
    convention: str = "standard",
    gravity: ArrayLike = (0, 0, -9.81),
    tool: ArrayLike | None = None,
    name: str = "dh_robot",
    base: ArrayLike | None = None,
) -> RobotModel:
    """A model from a Denavit–Hartenberg table.

    Joint i's frame is the DH frame in which its axis is z; link bodies are re-expressed there.

    standard: frame {i−1} · Rz(q_i) is joint i's frame, link frame {i} = joint frame · Rz(θ_off)Tz(d)Tx(a)Rx(α).
    modified (Craig): joint i's frame is link frame {i} = {i−1} · Rx(α)Tx(a)Rz(θ_off)Tz(d), moved by Rz(q_i).
    A tool transform (4×4) is given in the last DH link frame and becomes the frame ``"tool"``.

    Parameters
    ----------
    links : sequence of DHLink
        One row per joint, from the base (see :class:`~armctl.model.dh.DHLink` for the parameters and units).
    convention : {"standard", "modified"}, optional
        Standard (distal) or modified (proximal, Craig's) DH.
    gravity : array_like, shape (3,), optional
        g [m/s²] in world axes.
    tool : array_like, shape (4, 4), optional
        The placement of the frame ``"tool"`` (the model's tool frame) in the last DH link frame (None: the
        identity).
    name : str, optional
        The model's name.
    base : array_like, shape (4, 4), optional
        The DH base frame {0} in the world (None: the identity).

    Returns
    -------
    RobotModel
    """
    from armctl.model.robot import RobotModel

    if convention not in ("standard", "modified"):
        raise InvalidParameterError(
            f"DH convention must be 'standard' or 'modified', got {convention!r}", value=convention
        )
    rows = [_row(lk, i) for i, lk in enumerate(_rows(links))]
    if not rows:
        raise InvalidParameterError("a DH table needs at least one link", value=links)
    joints = []
    prev_offset = homogeneous(base, "base") if base is not None else np.eye(4)
    last_link_frame = np.eye(4)
    for i, row in enumerate(rows):
        motor = row.motor
        if motor is not None and motor.axis is not None:  # from DH frame {i−1} to the frame of joint i − 1
            motor = replace(motor, axis=prev_offset[:3, :3] @ motor.axis)  # (whose offset to {i−1} this is)
        if convention == "standard":
            placement = prev_offset
            link_frame = _std(row)  # a prismatic joint moves along z: d is a constant offset
            prev_offset = link_frame
        else:
            placement = prev_offset @ _mod(row)
            link_frame = np.eye(4)
            prev_offset = np.eye(4)
        last_link_frame = link_frame
        try:  # the body moves from the DH link frame {i} to the joint frame: its moments about a new origin
            body = Link(row.mass, row.com, row.inertia, row.physical).transformed(link_frame[:3, :3], link_frame[:3, 3])
        except InvalidParameterError as e:
            raise InvalidParameterError(
                f"DH row {i} ({row.name or f'joint{i + 1}'}), its body in the joint frame: {e}", value=e.value
            ) from None
        joints.append(
            Joint(row.name or f"joint{i + 1}", row.kind, _Z, placement, body, motor, row.friction, row.limits)
        )
    tool_t = last_link_frame @ homogeneous(tool, "tool")
    frames = (Frame("tool", len(joints), tool_t),)
    return RobotModel(tuple(joints), name=name, gravity=gravity, frames=frames, tool_frame="tool")


def _rows(links: Any) -> list[Any]:
    """The rows of a DH table: a sequence (not a str, not a single row)."""
    try:
        if isinstance(links, str | bytes | DHLink | Mapping):
            raise TypeError(type(links).__name__)
        return list(links)
    except TypeError:
        raise InvalidParameterError(
            f"a DH table must be a sequence of DHLink (or of dicts of DHLink's arguments), got {links!r}", value=links
        ) from None


def _row(row: Any, i: int) -> DHLink:
    """Row ``i`` of a DH table as a DHLink (a dict is DHLink's keyword arguments)."""
    if isinstance(row, DHLink):
        return row
    if isinstance(row, Mapping):
        try:
            return DHLink(**row)
        except TypeError as e:  # an unknown key
            raise InvalidParameterError(f"DH row {i}: {e}; the keys are DHLink's arguments", value=row) from None
    raise InvalidParameterError(f"DH row {i} must be a DHLink or a dict of its arguments, got {row!r}", value=row)
