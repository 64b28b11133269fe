"""`RobotModel`: the immutable description of a serial arm (kinematics, inertias, motors, friction, limits).

A model describes; it does not evaluate (that is :class:`armctl.Dynamics`). Variants are new objects:
:meth:`RobotModel.with_payload`, :meth:`RobotModel.perturbed`, :meth:`RobotModel.reduced`,
:meth:`RobotModel.with_friction`.
"""

from __future__ import annotations

import hashlib
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, overload

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import (
    FloatArray,
    boolean,
    instances,
    nonnegative_vector,
    readonly,
    scalar,
    vector,
    whole_number,
)
from armctl.errors import InvalidParameterError, UnknownNameError
from armctl.model.dh import model_from_dh
from armctl.model.named_poses import checked_poses
from armctl.model.parts import (
    Frame,
    Joint,
    JointFriction,
    Link,
    inertia_tensor,
    name_text,
    vec3,
)
from armctl.model.urdf import model_from_urdf

if TYPE_CHECKING:
    import pinocchio

#: Names of the 13 dynamic parameters of one joint, in the order of :meth:`RobotModel.parameters`.
PARAMETER_NAMES: tuple[str, ...] = (
    "m",
    "mcx",
    "mcy",
    "mcz",
    "Ixx",
    "Ixy",
    "Iyy",
    "Ixz",
    "Iyz",
    "Izz",
    "Im_reflected",
    "Fv",
    "Fc",
)
#: The number of dynamic parameters of one joint (13): the length of :data:`PARAMETER_NAMES`.
PARAMS_PER_JOINT = len(PARAMETER_NAMES)


def _check_scale(joints: tuple[Joint, ...], gravity: FloatArray) -> None:
    """Raise if the parameters overflow the dynamics: bounds of the gravity torques (|g| Σ m_j ℓ_j) and of the
    mass matrix's entries (Σ tr I_j + m_j ℓ_j² + k_r² I_m), ℓ_j = 2 (reach of joint j's origin + |c_j|) bounding
    the lever of link j's centre of mass about any joint axis (a prismatic joint adds its range, where finite),
    must be finite. A model with finite parameters may still fail this (a payload of 1e308 kg weighs inf N)."""
    reach = weight = inertia = 0.0
    g = float(np.linalg.norm(gravity))
    with np.errstate(over="ignore", invalid="ignore"):
        for j in joints:
            reach += float(np.linalg.norm(j.placement[:3, 3]))
            if j.kind == "prismatic":
                travel = max(abs(j.limits.lower), abs(j.limits.upper))
                reach += travel if math.isfinite(travel) else 0.0
            lk = j.link
            lever = 2.0 * (reach + float(np.linalg.norm(lk.com)))
            weight += g * lk.mass * lever
            inertia += float(np.trace(lk.inertia)) + lk.mass * lever * lever
            inertia += j.motor.reflected_inertia if j.motor is not None else 0.0
            if not (math.isfinite(weight) and math.isfinite(inertia)):
                raise InvalidParameterError(
                    f"joint {j.name!r}: its link ({lk.mass:g} kg, centre of mass up to {lever:g} m from the joint "
                    f"axes) overflows the dynamics: gravity torques up to {weight:g} N·m, mass-matrix entries up "
                    f"to {inertia:g} kg·m² (|g| = {g:g} m/s²); give parameters whose dynamics stay finite",
                    value=lk.mass,
                )


class _LimitField:
    """A property of :class:`RobotModel`: one field of every joint's limits
    (:class:`~armctl.model.parts.JointLimits`), as a read-only (n,) array.

    Parameters
    ----------
    field : str
        The field of :class:`~armctl.model.parts.JointLimits`.
    doc : str
        The property's docstring.
    """

    def __init__(self, field: str, doc: str) -> None:
        self.field = field
        self.__doc__ = doc

    @overload
    def __get__(self, model: None, owner: type) -> _LimitField: ...
    @overload
    def __get__(self, model: RobotModel, owner: type) -> FloatArray: ...
    def __get__(self, model: RobotModel | None, owner: type) -> _LimitField | FloatArray:
        if model is None:
            return self
        return readonly(np.array([getattr(j.limits, self.field) for j in model.joints]))


@dataclass(frozen=True, eq=False, init=False)  # numpy fields: compare by identity
class RobotModel:
    """A serial manipulator: joints (each with its link, motor, friction, limits), named frames, gravity.

    Build one with :meth:`from_dh`, :meth:`from_urdf`, :meth:`from_mjcf`, one of :mod:`armctl.models`, or directly
    from :class:`~armctl.model.parts.Joint` objects. Immutable: the variants (:meth:`with_payload`,
    :meth:`with_friction`, :meth:`perturbed`, :meth:`reduced`, ...) are new models. Every joint frame is also a
    named frame (the joint's name).

    Parameters
    ----------
    joints : sequence of Joint
        The chain from the base (at least one; unique names).
    name : str, optional
        The model's name.
    gravity : array_like, shape (3,), optional
        g [m/s²] in world axes (default (0, 0, −9.81)).
    frames : sequence of Frame, optional
        Named frames besides the joints' (unique names; ``"world"`` and ``"universe"`` are reserved).
    tool_frame : str, optional
        The frame a method given ``frame=None`` uses (None: the last joint's).
    source : str or path-like, optional
        The description file the model was read from (URDF or MJCF; None for a model built in code), where
        :meth:`to_mjcf` finds its meshes.
    named_poses : mapping of str to array_like, optional
        Named joint configurations (n,) [rad or m], each within the joint limits, e.g. ``{"ready": q}``;
        ``"zero"`` is added where it is not given (every joint at 0, or at the end of its range nearest to 0).
        Kept by the variants (:meth:`with_payload`, :meth:`reduced`, ...).

    Attributes
    ----------
    named_poses : dict of str to ndarray
        The named poses (read-only arrays). Every built-in arm of :mod:`armctl.models` has at least ``"ready"``
        (a posture to start from, away from singularities) and ``"zero"``.

    Raises
    ------
    InvalidParameterError
        No joints, names repeated or reserved, a frame on a joint that does not exist, parameters whose dynamics
        overflow, a named pose outside the joint limits.
    UnknownNameError
        ``tool_frame`` names no frame.
    """

    joints: tuple[Joint, ...]
    name: str
    gravity: FloatArray
    frames: tuple[Frame, ...]
    tool_frame: str | None
    source: str | None
    named_poses: dict[str, FloatArray]

    def __init__(
        self,
        joints: Sequence[Joint],
        name: str = "robot",
        gravity: ArrayLike = (0.0, 0.0, -9.81),
        frames: Sequence[Frame] = (),
        tool_frame: str | None = None,
        source: str | os.PathLike[str] | None = None,
        named_poses: Mapping[str, ArrayLike] | None = None,
    ) -> None:
        """See the class."""
        values = (("joints", joints), ("name", name), ("gravity", gravity), ("frames", frames))
        for key, value in (*values, ("tool_frame", tool_frame), ("source", source), ("named_poses", named_poses)):
            object.__setattr__(self, key, value)
        self._check()

    def _check(self) -> None:
        joints = instances(self.joints, Joint, "joints", "armctl.model.Joint")
        frames = instances(self.frames, Frame, "frames", "armctl.model.Frame")
        if not joints:
            raise InvalidParameterError("a RobotModel needs at least one joint", value=self.joints)
        name_text(self.name, "model name")
        names = [j.name for j in joints]
        if len(set(names)) != len(names):
            raise InvalidParameterError(f"joint names must be unique: {names}", value=names)
        g = np.array(vector(self.gravity, 3, "gravity"))  # a copy, made read-only below
        for f in frames:
            if not 0 <= f.joint <= len(joints):
                raise InvalidParameterError(
                    f"frame {f.name!r} is attached to joint {f.joint}, but the model "
                    f"has joints 1..{len(joints)} (0 is the world)",
                    value=f.joint,
                )
        all_names = ["world", *names, *(f.name for f in frames)]
        if "universe" in all_names:  # Pinocchio's own name for its world frame: a second one is ambiguous there
            raise InvalidParameterError(
                "the name 'universe' is reserved (Pinocchio's world frame, which armctl "
                "calls 'world'): rename that joint or frame",
                value="universe",
            )
        if len(set(all_names)) != len(all_names):
            raise InvalidParameterError(
                f"frame names must be unique (joint names count as frames): {all_names}", value=all_names
            )
        _check_scale(joints, g)
        object.__setattr__(self, "joints", joints)
        object.__setattr__(self, "frames", frames)
        object.__setattr__(self, "gravity", readonly(g))
        if isinstance(self.source, os.PathLike):
            object.__setattr__(self, "source", os.fspath(self.source))
        if self.source is not None:
            name_text(self.source, "model source (a file path)")
        if self.tool_frame is not None and self.tool_frame not in all_names:
            raise UnknownNameError("frame", self.tool_frame, all_names)
        poses = checked_poses(self.named_poses, self.lower, self.upper, tuple(names))
        object.__setattr__(self, "named_poses", poses)

    # ----------------------------------------------------------------------------------------- builders
    # RobotModel.from_dh(...) and .from_urdf(...) are the builders' functions themselves
    from_dh = staticmethod(model_from_dh)
    from_urdf = staticmethod(model_from_urdf)

    @classmethod
    def from_mjcf(
        cls,
        path_or_xml: Any,
        tool_frame: str | None = None,
        base: str | None = None,
        name: str | None = None,
        lock: Sequence[str] | Mapping[str, float] | None = None,
    ) -> RobotModel:
        """A model from an MJCF (MuJoCo) description (needs ``pip install "armctl[mujoco]"``).

        The serial chain of hinge and slide joints from the body ``base``; inertias as MuJoCo compiles them,
        ``damping`` / ``frictionloss`` / ``armature`` as viscous friction / Coulomb friction / reflected rotor inertia,
        ranges, actuator force ranges as effort limits, named bodies and sites as frames, gravity (see
        :mod:`armctl.model.mjcf`).

        Parameters
        ----------
        path_or_xml : str, path-like, mujoco.MjSpec or mujoco.MjModel
            A file path, an XML text, a spec or a compiled model.
        tool_frame : str, optional
            The frame a method given ``frame=None`` uses (None: the last joint's).
        base : str, optional
            The body the chain starts from (None: the one subtree of the world with joints).
        name : str, optional
            The model's name (None: the MJCF's).
        lock : str, sequence of str or mapping str → float, optional
            Joints held fixed: names (held at 0) or name → position (MuJoCo's ``qpos``) [rad or m], as in
            :meth:`from_urdf`; a branch whose joints are all locked (a gripper's fingers) is welded to the chain.

        Returns
        -------
        RobotModel

        Raises
        ------
        ModelLoadError
            What a RobotModel cannot hold (free or ball joints, branches with joints, joint springs), named.
        UnknownNameError
            A name in ``lock`` that is not a hinge or slide joint of the description.
        """
        from armctl.model.mjcf import model_from_mjcf

        return model_from_mjcf(path_or_xml, tool_frame=tool_frame, base=base, name=name, lock=lock)

    def to_mjcf(self, meshes: Any = None, contacts: bool = True) -> str:
        """This arm as an MJCF text that MuJoCo compiles to the same dynamics (see :mod:`armctl.model.mjcf_export`).

        One body per joint, explicit inertias, armature k_r²I_m, damping F_v, frictionloss F_c, ranges, a torque motor
        per joint with a finite effort limit, the frames as sites.

        Parameters
        ----------
        meshes : path-like, None or False, optional
            The URDF whose collision meshes to attach (None: :attr:`source` if it is a URDF; False: simple shapes, a
            capsule per link).
        contacts : bool, optional
            The arm's geoms collide with the rest of a scene (never with each other).

        Returns
        -------
        str
            The MJCF XML.
        """
        from armctl.model.mjcf_export import model_to_mjcf

        return model_to_mjcf(self, meshes=meshes, contacts=contacts)

    # ------------------------------------------------------------------------------------------ queries
    @property
    def n(self) -> int:
        """Number of joints (degrees of freedom)."""
        return len(self.joints)

    def __repr__(self) -> str:  # a summary: the dataclass's own repr prints every array of every joint
        kinds = "".join("P" if j.kind == "prismatic" else "R" for j in self.joints)
        mass = sum(j.link.mass for j in self.joints)
        return (
            f"RobotModel({self.name!r}: {self.n} joints {kinds}, {mass:.4g} kg of links, "
            f"motors={self.has_motors}, friction={self.has_friction}, tool_frame={self.tool_frame!r}, "
            f"gravity={self.gravity.tolist()}, {len(self.frames)} named frames besides the joints)"
        )

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(j.name for j in self.joints)

    @property
    def frame_names(self) -> tuple[str, ...]:
        """Every frame a method can be asked about: 'world', the joint frames, the extra frames."""
        return ("world", *self.joint_names, *(f.name for f in self.frames))

    def frame(self, name: str | None = None) -> Frame:
        """The frame called ``name``.

        Parameters
        ----------
        name : str, optional
            A name of :attr:`frame_names` (None: the tool frame, or the last joint frame if there is none).

        Returns
        -------
        Frame

        Raises
        ------
        UnknownNameError
            No frame has that name (the error lists them).
        """
        if name is None:
            name = self.tool_frame or self.joints[-1].name
        if name == "world":
            return Frame("world", 0, np.eye(4))
        for i, j in enumerate(self.joints, start=1):
            if j.name == name:
                return Frame(name, i, np.eye(4))
        for f in self.frames:
            if f.name == name:
                return f
        raise UnknownNameError("frame", name, self.frame_names)

    def joint_index(self, name: str) -> int:
        """0-based index of the joint called ``name``.

        Parameters
        ----------
        name : str
            A joint name.

        Returns
        -------
        int

        Raises
        ------
        UnknownNameError
            No joint has that name.
        """
        try:
            return self.joint_names.index(name)
        except ValueError:
            raise UnknownNameError("joint", name, self.joint_names) from None

    lower = _LimitField("lower", "Lower position limits (n,) [rad or m].")
    upper = _LimitField("upper", "Upper position limits (n,) [rad or m].")
    velocity_limit = _LimitField("velocity", "Velocity limits (n,) [rad/s or m/s].")
    effort_limit = _LimitField("effort", "Effort limits (n,) [N·m or N].")

    @property
    def has_motors(self) -> bool:
        return any(j.motor is not None and j.motor.inertia > 0 for j in self.joints)

    @property
    def has_friction(self) -> bool:
        return any(not j.friction.is_zero for j in self.joints)

    def parameters(self) -> FloatArray:
        """The dynamic parameter vector π, 13 per joint (13·n,), joint by joint, each in the order of
        :data:`PARAMETER_NAMES`:

        ``m, m·cx, m·cy, m·cz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz, k_r²·I_m, F_v, F_c``

        with the first moment m·c and the inertia tensor *about the joint-frame origin* in joint-frame axes
        (the augmented link; the ten inertial parameters in Pinocchio's order, so its regressor columns map
        one to one), k_r²·I_m the reflected rotor inertia, F_v the viscous and F_c the Coulomb
        friction. For an asymmetric Coulomb friction F_c is the mean (F_c⁺ + F_c⁻)/2, and the regressor's
        Coulomb column carries the ratio of the two levels, so Y π = τ still holds (see
        ``Dynamics.regressor`` and ``Dynamics.coulomb_column``).

        Returns
        -------
        ndarray, shape (13 n,)
            π.
        """
        out = np.empty(PARAMS_PER_JOINT * self.n)
        for i, j in enumerate(self.joints):
            lk = j.link
            io = lk.inertia_about_origin()
            rotor = j.motor.reflected_inertia if j.motor is not None else 0.0
            out[PARAMS_PER_JOINT * i : PARAMS_PER_JOINT * (i + 1)] = [
                lk.mass,
                *(lk.mass * lk.com),
                io[0, 0],
                io[0, 1],
                io[1, 1],
                io[0, 2],
                io[1, 2],
                io[2, 2],
                rotor,
                j.friction.viscous,
                j.friction.coulomb_mean,
            ]
        return readonly(out)

    def parameter_names(self) -> tuple[str, ...]:
        """Names of the entries of :meth:`parameters`, e.g. ``'m[2]'`` for the mass of the third joint's link.

        Returns
        -------
        tuple of str
            13 n names.
        """
        return tuple(f"{p}[{i}]" for i in range(self.n) for p in PARAMETER_NAMES)

    def fingerprint(self, inertial: bool = True, tool: bool = True) -> str:
        """A short hash keying caches of code generated from this model (the ``"lagrange"`` backend's
        compiled CasADi library uses ``fingerprint(inertial=False)``).

        Covered: gravity; every joint's kind, axis and placement; for joints with a gyroscopic motor, its gear ratio and
        spin axis (an armature changes no code: it is in π); the tool frame (name, joint, placement). Not covered:
        friction, joint limits, joint names and the frames other than the tool frame. So equal fingerprints do *not*
        mean equal dynamics (models that differ only in friction share one); they mean the same generated code, whose
        π input carries the inertial and friction parameters at run time: every payload, perturbed or friction variant
        of an arm shares ``fingerprint(inertial=False)``.

        Parameters
        ----------
        inertial : bool, optional
            Also cover the link masses, centres of mass, inertia tensors and rotor inertias.
        tool : bool, optional
            Cover the tool frame (False: for code of joint-space terms only, the compiled dynamics and simulator step).

        Returns
        -------
        str
            Hexadecimal digits.
        """
        h = hashlib.sha256()
        h.update(self.gravity.tobytes())
        for j in self.joints:
            h.update(j.kind.encode())
            h.update(j.axis.tobytes())
            h.update(j.placement.tobytes())
            if inertial:
                h.update(np.array([j.link.mass, *j.link.com]).tobytes())
                h.update(j.link.inertia.tobytes())
            if j.motor is not None and j.motor.gyroscopic:
                h.update(np.array([j.motor.gear_ratio]).tobytes())
                h.update(j.motor_axis.tobytes())
                if inertial:
                    h.update(np.array([j.motor.inertia]).tobytes())
            elif j.motor is not None and inertial:  # an armature: generated code as without a motor
                h.update(b"armature" + np.array([j.motor.inertia * j.motor.gear_ratio**2]).tobytes())
        if tool:
            frame = self.frame(None)
            h.update(f"{frame.name}:{frame.joint}".encode())
            h.update(frame.placement.tobytes())
        return h.hexdigest()[:16]

    def to_pinocchio(self) -> pinocchio.Model:
        """A new ``pinocchio.Model`` of this arm (rotors as armature k_r²I_m; friction is not copied).

        Returns
        -------
        pinocchio.Model
        """
        from armctl.model.pinocchio_io import build_pinocchio

        return build_pinocchio(self)

    # ----------------------------------------------------------------------------------------- variants
    def with_payload(
        self,
        mass: float,
        com: ArrayLike = (0.0, 0.0, 0.0),
        inertia: ArrayLike = (0.0, 0.0, 0.0),
        frame: str | None = None,
    ) -> RobotModel:
        """This arm carrying a rigid payload.

        Parameters
        ----------
        mass : float
            [kg], ≥ 0.
        com : array_like, shape (3,), optional
            The payload's centre of mass [m] in the axes and from the origin of ``frame``.
        inertia : array_like, optional
            Its inertia about its centre of mass [kg·m²] in the axes of ``frame``: a 3×3 tensor, 3 principal moments
            or 6 values in URDF order (Ixx, Ixy, Ixz, Iyy, Iyz, Izz) — not π's order (Ixx, Ixy, Iyy, Ixz, Iyz, Izz,
            Pinocchio's, and about the joint frame, not the centre of mass).
        frame : str, optional
            The frame it is attached to (None: the tool frame); not a frame fixed to the world.

        Returns
        -------
        RobotModel
            A new model named ``"<name>+payload"``.

        Raises
        ------
        InvalidParameterError, ShapeError, NonFiniteError
            A value out of range, of the wrong shape, or not finite; a frame fixed to the world.
        """
        f = self.frame(frame)
        if f.joint == 0:
            raise InvalidParameterError(
                f"a payload cannot be attached to frame {f.name!r}: it is fixed to the world", value=frame
            )
        mass = scalar(mass, "payload mass [kg]", nonnegative=True)
        payload = Link(mass, vec3(com, "payload com"), inertia_tensor(inertia, "payload inertia")).transformed(
            f.placement[:3, :3], f.placement[:3, 3]
        )
        idx = f.joint - 1
        joints = list(self.joints)
        joints[idx] = replace(joints[idx], link=joints[idx].link.combined(payload))
        return replace(self, joints=tuple(joints), name=f"{self.name}+payload")

    def with_parameters(
        self, pi: ArrayLike, coulomb_offset: ArrayLike | None = None, physical: bool = True
    ) -> RobotModel:
        """This arm's kinematics with the dynamic parameters π.

        Parameters
        ----------
        pi : array_like, shape (13 n,)
            The layout of :meth:`parameters` (per joint: m, m·c [kg·m], the inertia about the joint frame [kg·m²], the
            reflected rotor inertia, F_v, F_c).
        coulomb_offset : array_like, shape (n,), optional
            ½(F_c⁺ − F_c⁻) per joint [N·m] (default: this model's).
        physical : bool, optional
            As for :class:`~armctl.model.parts.Link`.

        Returns
        -------
        RobotModel

        Raises
        ------
        InvalidParameterError
            π is not that of physical bodies.
        """
        from armctl.model.from_parameters import model_from_parameters

        return model_from_parameters(self, pi, coulomb_offset=coulomb_offset, physical=physical)

    def with_friction(
        self,
        viscous: ArrayLike = 0.0,
        coulomb: ArrayLike = 0.0,
        coulomb_negative: ArrayLike | None = None,
        static: ArrayLike | None = None,
        stribeck_velocity: ArrayLike = 0.0,
    ) -> RobotModel:
        """This arm with the given joint friction (see :class:`~armctl.model.parts.JointFriction`).

        Each argument is a scalar for all joints or an (n,) vector, finite and ≥ 0.

        Parameters
        ----------
        viscous : array_like, optional
            F_v [N·m·s/rad].
        coulomb : array_like, optional
            F_c⁺, the Coulomb level for q̇ > 0 [N·m].
        coulomb_negative : array_like, optional
            F_c⁻ for q̇ < 0 (None: the Coulomb level).
        static : array_like, optional
            The breakaway (stiction) level [N·m] (None: the Coulomb level).
        stribeck_velocity : array_like, optional
            v_s [rad/s] of the Stribeck curve (0: none).

        Returns
        -------
        RobotModel

        Raises
        ------
        InvalidParameterError, ShapeError, NonFiniteError
            A negative, non-finite or wrongly shaped value; a static level below the Coulomb levels.
        """

        def per_joint(x: ArrayLike | None, what: str) -> list[float]:
            return nonnegative_vector(x, self.n, f"with_friction(): {what}").tolist()

        def optional(x: ArrayLike | None, what: str) -> list[float | None]:
            return [None] * self.n if x is None else list(per_joint(x, what))

        cols = zip(
            per_joint(viscous, "viscous"),
            per_joint(coulomb, "coulomb"),
            optional(coulomb_negative, "coulomb_negative"),
            optional(static, "static"),
            per_joint(stribeck_velocity, "stribeck_velocity"),
            strict=True,
        )
        joints = tuple(replace(j, friction=JointFriction(*c)) for j, c in zip(self.joints, cols, strict=True))
        return replace(self, joints=joints)

    def perturbed(
        self,
        mass: float = 1.0,
        inertia: float = 1.0,
        com_offset: float = 0.0,
        friction: float = 1.0,
        rotor: float = 1.0,
        noise: float = 0.0,
        seed: int | None = None,
    ) -> RobotModel:
        """A deliberately wrong copy of this arm, for model-error studies.

        Parameters
        ----------
        mass, inertia, friction, rotor : float, optional
            Factors on every link mass, every inertia tensor about the centre of mass, every friction coefficient and
            every rotor inertia.
        com_offset : float, optional
            A shift [m] of every centre of mass along a random direction.
        noise : float, optional
            Relative standard deviation of an extra random factor per link, clipped to stay physical.
        seed : int, optional
            Seeds the random direction and factors.

        Returns
        -------
        RobotModel
            A new model named ``"<name>~perturbed"``.
        """
        factor = "a factor, 1 leaves it unchanged"
        for nm, v, hint in (
            ("mass", mass, factor),
            ("inertia", inertia, factor),
            ("friction", friction, factor),
            ("rotor", rotor, factor),
            ("com_offset", com_offset, "a distance in m, 0 for none"),
            ("noise", noise, "a relative standard deviation, 0 for none"),
        ):
            try:
                ok = not isinstance(v, bool | np.bool_) and math.isfinite(v) and v >= 0
            except TypeError:
                ok = False
            if not ok:
                raise InvalidParameterError(f"perturbed(): {nm} must be finite and >= 0 ({hint}), got {v!r}", value=v)
        rng = np.random.default_rng(None if seed is None else whole_number(seed, "perturbed(): seed"))
        joints = []
        for j in self.joints:
            f_noise = max(0.05, 1.0 + noise * rng.standard_normal()) if noise else 1.0
            d = rng.standard_normal(3)
            d *= com_offset / max(float(np.linalg.norm(d)), 1e-12)
            link = Link(
                j.link.mass * mass * f_noise, j.link.com + d, j.link.inertia * inertia * f_noise, j.link.physical
            )
            motor = replace(j.motor, inertia=j.motor.inertia * rotor) if j.motor is not None else None
            fr = j.friction
            fr = JointFriction(
                fr.viscous * friction,
                fr.coulomb * friction,
                None if fr.coulomb_negative is None else fr.coulomb_negative * friction,
                None if fr.static is None else fr.static * friction,
                fr.stribeck_velocity,
            )
            joints.append(replace(j, link=link, motor=motor, friction=fr))
        return replace(self, joints=tuple(joints), name=f"{self.name}~perturbed")

    def reduced(
        self, rotors: bool = True, friction: bool = True, lock: Sequence[str] | Mapping[str, float] = ()
    ) -> RobotModel:
        """A simpler model of this arm.

        With ``lock``, the locked joints' frames and every other frame stay (attached to the joint that now carries
        them, the world for links merged into it), a motor's explicit spin axis is re-expressed in the link its rotor
        now rides on, the locked joints' motors and friction are dropped (they no longer move), and a default tool frame
        (``tool_frame=None``: the last joint's) is kept by name if that joint is locked; the named poses keep the
        entries of the free joints. Links merged into the world
        (locking the first joints) no longer move and are no longer in the model: the dynamics are the full arm's held
        at the lock, but ``potential_energy`` differs from the full arm's by their constant potential energy.

        Parameters
        ----------
        rotors : bool, optional
            False drops the motors.
        friction : bool, optional
            False drops the friction.
        lock : sequence of str or mapping str → float, optional
            Joints held fixed (names locked at 0, or name → position [rad or m]), their links merged into the previous
            one.

        Returns
        -------
        RobotModel

        Raises
        ------
        UnknownNameError
            An unknown joint.
        NonFiniteError
            A non-finite lock position.
        InvalidParameterError
            A lock position that is not a number, or locking every joint.
        """
        from armctl.model.pinocchio_io import lock_joints, lock_positions

        rotors, friction = boolean(rotors, "reduced(): rotors"), boolean(friction, "reduced(): friction")
        positions = lock_positions(lock, self.joint_names)
        joints = tuple(
            replace(j, motor=j.motor if rotors else None, friction=j.friction if friction else JointFriction())
            for j in self.joints
        )
        model = replace(self, joints=joints)
        if positions:
            model = lock_joints(model, positions)
        return model
