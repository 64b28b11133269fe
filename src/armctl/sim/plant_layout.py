"""`PlantLayout`: what the generated step of a plant is made of, and where its numbers go.

The generated step (:mod:`armctl.sim.generated_plant`, :mod:`armctl.sim.compiled_plant`) has one library per arm and
*structure*: the friction model (none, stick–slip, smooth; with or without a Stribeck term; joints that can stick or
not), the contact points (the link each rides on, its normal law), a disturbance (the link of the tool frame). Every
number is an input of the code, the parameter vector ``par`` laid out here: the arm's inertial parameters π (13 per
joint, :meth:`armctl.RobotModel.parameters`), the friction model's, 14 per contact point, the tool frame's origin.
:func:`layout_of` also says why a plant has no generated step.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import Any, cast

import numpy as np

from armctl._checks import FloatArray
from armctl.model.robot import PARAMS_PER_JOINT, RobotModel
from armctl.sim.contact import Plane
from armctl.sim.friction import SmoothFriction, StickSlip
from armctl.sim.normal_force import HuntCrossley, KelvinVoigt
from armctl.sim.plant import Plant

#: parameters of a contact point in ``par``: normal (3), plane point (3), point in its joint frame (3),
#: stiffness, damping or dissipation, exponent, μ, slip velocity
POINT_PARAMS = 14
#: friction parameters per joint in ``par``: F_v, F_c⁺, F_c⁻, hump⁺, hump⁻, v_s, F_s⁺, F_s⁻, capable
FRICTION_PARAMS = 9


@dataclass(frozen=True)
class PlantLayout:
    """What the generated code of a plant is made of (its structure: one library each) and where each number
    sits in its parameter vector ``par``.

    Attributes
    ----------
    n : int
        Joints.
    friction : str
        ``"none"``, ``"stick-slip"`` or ``"smooth"``.
    stribeck : bool
        The friction curve has a Stribeck term.
    sticky : bool
        Some joint can stick (a stick–slip model with a breakaway level).
    points : tuple of (int, str)
        Every contact point: the 1-based joint it rides on (0: the world) and its normal law (``"kv"``, ``"hc"``).
    disturbance_joint : int or None
        The tool frame's joint when the plant has a disturbance.
    tool_joint : int or None
        The tool frame's joint when the plant has contact points or a disturbance (the disturbance's point of
        application, and the origin of the recorded wrench's moment); its origin in that joint's frame is in
        ``par`` (:attr:`tool_offset`).
    """

    n: int
    friction: str
    stribeck: bool
    sticky: bool
    points: tuple[tuple[int, str], ...]
    disturbance_joint: int | None
    tool_joint: int | None = None

    @property
    def has_friction(self) -> bool:
        return self.friction != "none"

    @property
    def has_external(self) -> bool:
        return bool(self.points) or self.disturbance_joint is not None

    @property
    def friction_offset(self) -> int:
        return PARAMS_PER_JOINT * self.n  # after π

    @property
    def points_offset(self) -> int:
        return self.friction_offset + (FRICTION_PARAMS * self.n + 1 if self.has_friction else 0)

    @property
    def tool_offset(self) -> int:
        return self.points_offset + POINT_PARAMS * len(self.points)

    @property
    def size(self) -> int:
        """Entries of ``par`` (at least one)."""
        return max(self.tool_offset + (3 if self.tool_joint is not None else 0), 1)

    def tag(self) -> str:
        """The structure as a hash, for the library's cache key."""
        text = f"{self.n}|{self.friction}|{self.stribeck}|{self.sticky}|{self.points}|{self.disturbance_joint}"
        text += f"|{self.tool_joint}"
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def parameters(self, plant: Plant) -> FloatArray:
        """``par`` of ``plant`` (which must have this layout, see :func:`layout_of`): the model's inertial
        parameters π (:meth:`armctl.RobotModel.parameters`), the friction model's, the contact points' and the
        tool's."""
        par = np.zeros(self.size)
        model = plant.dyn.model
        par[: self.friction_offset] = model.parameters()
        f = plant.friction
        n = self.n
        if f is not None:
            capable = f.capable if isinstance(f, StickSlip) else np.zeros(n, bool)
            cols: tuple[Any, ...] = (f.viscous, f.coulomb_pos, f.coulomb_neg, f.hump_pos, f.hump_neg)
            cols += (f.stribeck_velocity, f.breakaway_pos, f.breakaway_neg, capable.astype(float))
            at = self.friction_offset
            for k, col in enumerate(cols):
                par[at + k * n : at + (k + 1) * n] = col
            par[at + FRICTION_PARAMS * n] = f.velocity if isinstance(f, SmoothFriction) else 1.0
        at = self.points_offset
        for environment in plant.environments:
            env = cast(Plane, environment)  # the generated step takes planes only (see layout_of)
            law = env.law
            if isinstance(law, KelvinVoigt):
                coeff = (law.stiffness, law.damping, 1.0)
            else:  # the generated step's other law (see layout_of)
                hc = cast(HuntCrossley, law)
                coeff = (hc.stiffness, hc.dissipation, hc.exponent)
            for point in env.points:
                par[at : at + 3] = env.normal
                par[at + 3 : at + 6] = env.point
                par[at + 6 : at + 9] = _in_joint_frame(model, point.frame, point.offset)
                par[at + 9 : at + 12] = coeff
                par[at + 12] = env.friction
                par[at + 13] = env.slip_velocity
                at += POINT_PARAMS
        if self.tool_joint is not None:
            par[at : at + 3] = _in_joint_frame(model, None, np.zeros(3))
        return par


def _in_joint_frame(model: RobotModel, frame: str | None, offset: FloatArray) -> FloatArray:
    """A point at ``offset`` in ``frame``, in the frame of the joint that frame rides on."""
    placement = model.frame(frame).placement
    return placement[:3, :3] @ offset + placement[:3, 3]


def layout_of(plant: Plant) -> PlantLayout | str:
    """The layout of ``plant``'s generated code, or why it has none (a friction model or an environment that
    is not one of the library's own, the rotors' gyroscopic coupling of a ``"lagrange"`` plant)."""
    dyn = plant.dyn
    model = dyn.model
    if getattr(dyn, "rotor_coupling", False) and any(j.motor is not None and j.motor.gyroscopic for j in model.joints):
        return (
            "the generated step integrates the model the 'pinocchio' backend expresses, without the rotors' "
            "gyroscopic coupling this 'lagrange' plant has (rotor_coupling=False or the 'pinocchio' backend "
            "have a generated step)"
        )
    f = plant.friction
    if f is None:
        kind, stribeck = "none", False
    elif type(f) is StickSlip:
        kind, stribeck = "stick-slip", f.has_stribeck
    elif type(f) is SmoothFriction:
        kind, stribeck = "smooth", f.has_stribeck
    else:
        return f"the friction model {type(f).__name__} has no generated code (StickSlip and SmoothFriction do)"
    points = []
    for env in plant.environments:
        if type(env) is not Plane:
            return f"the environment {type(env).__name__} has no generated code (Plane has)"
        law = env.law
        if type(law) not in (KelvinVoigt, HuntCrossley):
            return (
                f"the normal-force law {type(law).__name__} has no generated code (KelvinVoigt and HuntCrossley have)"
            )
        kind_law = "kv" if type(law) is KelvinVoigt else "hc"
        points += [(model.frame(p.frame).joint, kind_law) for p in env.points]
    tool = model.frame(None).joint if points or plant.disturbance is not None else None
    dist = tool if plant.disturbance is not None else None
    return PlantLayout(model.n, kind, stribeck, plant.sticky is not None, tuple(points), dist, tool)
