"""Contact environments: they turn the pose and velocity of points on the arm into forces.

A contact point is a point rigidly attached to a frame of the plant model. An environment computes, for every
point, the force F the environment exerts on the arm; the force the arm exerts on the environment is h = −F,
and the joint torque of the contact enters the dynamics as

    M q̈ + C q̇ + g = τ − τ_f − Σ_p J_p(q)ᵀ h_p,        J_p = J_lin − [r_p]× J_ang

with J_p the Jacobian of the point's velocity (r_p: the point's offset from its frame origin, world axes). For
the implicit integrator an environment also gives the joint-space stiffness and damping
K = Σ J_pᵀ (∂F/∂p) J_p and D = Σ J_pᵀ (∂F/∂ṗ) J_p (geometric stiffness J̇-terms neglected: they only slow
Newton's convergence, not what it converges to).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal, overload

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, boolean, readonly, real_array, scalar
from armctl.dynamics.base import Dynamics
from armctl.dynamics.pinocchio_backend import PinocchioKernel
from armctl.errors import InvalidParameterError
from armctl.model.robot import RobotModel
from armctl.sim.normal_force import NormalForce


@dataclass(frozen=True, eq=False)
class ContactPoint:
    """A point at ``offset`` [m] (in the axes of ``frame``) from the origin of ``frame`` (None: the tool
    frame)."""

    frame: str | None = None
    offset: FloatArray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        o = np.array(real_array(self.offset, "contact point offset"))  # a copy; text, None, booleans refused
        if o.shape != (3,) or not np.isfinite(o).all():
            raise InvalidParameterError(
                f"contact point offset must be a finite 3-vector, got {self.offset!r}", value=self.offset
            )
        object.__setattr__(self, "offset", readonly(o))


def _skew(r: FloatArray) -> FloatArray:
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


class PointKinematics:
    """Positions p [m] and velocity Jacobians J_p = J_lin − [r]× J_ang (3×n) of a fixed set of points for one
    Dynamics, one frame evaluation per frame (straight through Pinocchio for the ``"pinocchio"`` backend)."""

    def __init__(self, dyn: Dynamics, points: Sequence[ContactPoint]) -> None:
        self.dyn = dyn
        self.points = tuple(points)
        self.frames = list(dict.fromkeys(p.frame for p in self.points))
        self._slot = [self.frames.index(p.frame) for p in self.points]
        #: 1-based joint each point rides on (0: the world)
        self.joints = np.array([dyn.model.frame(p.frame).joint for p in self.points])
        self._pin = None
        self._kernel = kernel = dyn.kernel
        if isinstance(kernel, PinocchioKernel):  # Pinocchio's frame Jacobian leaves the frame's pose in its data
            ids = [kernel.frame_id(f) for f in self.frames]
            if all(i != 0 for i in ids):
                self._pin = (pin.computeFrameJacobian, kernel.pin_model, kernel.pin_data, ids, pin.LOCAL_WORLD_ALIGNED)

    def __call__(self, q: FloatArray) -> list[tuple[FloatArray, FloatArray]]:
        """[(p, J_p)] for every point at configuration q."""
        frames = []
        if self._pin is not None:
            jac_fn, pm, pd, ids, rf = self._pin
            for fid in ids:
                jac = jac_fn(pm, pd, q, fid, rf).reshape(6, -1)
                oMf = pd.oMf[fid]
                frames.append((oMf.translation, oMf.rotation, jac))
        else:
            k = self._kernel
            for f in self.frames:
                pose = k.frame_pose(q, f)
                frames.append((pose[:3, 3], pose[:3, :3], k.jacobian(q, f)))
        out = []
        for point, slot in zip(self.points, self._slot, strict=True):
            origin, rot, jac = frames[slot]
            if not point.offset.any():
                out.append((origin, jac[:3]))
                continue
            r = rot @ point.offset
            out.append((origin + r, jac[:3] - _skew(r) @ jac[3:]))
        return out


class Environment(ABC):
    """Something the arm touches. ``points``: the contact points it acts on."""

    points: tuple[ContactPoint, ...] = ()

    def check(self, model: RobotModel) -> None:
        """Raise :class:`~armctl.errors.UnknownNameError` if a point names a frame the model does not have."""
        for p in self.points:
            model.frame(p.frame)

    def kinematics(self, dyn: Dynamics) -> PointKinematics:
        """The evaluator of this environment's points for ``dyn`` (build once, call at every step)."""
        return PointKinematics(dyn, self.points)

    @overload
    def joint_torque(
        self, kin: PointKinematics, q: FloatArray, qd: FloatArray, stiffness: Literal[False] = False
    ) -> tuple[FloatArray, None, None]: ...
    @overload
    def joint_torque(
        self, kin: PointKinematics, q: FloatArray, qd: FloatArray, stiffness: Literal[True]
    ) -> tuple[FloatArray, FloatArray, FloatArray]: ...
    def joint_torque(
        self, kin: PointKinematics, q: FloatArray, qd: FloatArray, stiffness: bool = False
    ) -> tuple[FloatArray, FloatArray | None, FloatArray | None]:
        """(τ_c, K, D): τ_c = Σ J_pᵀ F_p, the joint torque of the forces on the arm (it is *added* to τ), and,
        if ``stiffness``, K = Σ J_pᵀ (∂F/∂p) J_p (∂τ_c/∂q without the J-derivative terms, see the module) and
        D = ∂τ_c/∂q̇ (n×n). ``kin``: :meth:`kinematics` of the plant."""
        n = kin.dyn.n
        tau = np.zeros(n)
        kj = np.zeros((n, n)) if stiffness else None
        dj = np.zeros((n, n)) if stiffness else None
        for p, jp in kin(q):
            force, dfdp, dfdv = self.force(p, jp @ qd, stiffness)
            if force is None:
                continue
            tau += jp.T @ force
            if stiffness:
                kj += jp.T @ dfdp @ jp
                dj += jp.T @ dfdv @ jp
        return tau, kj, dj

    def forces(self, kin: PointKinematics, q: FloatArray, qd: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(h, p): the force each point exerts *on the environment* h_p = −F_p [N] and its position [m], (P, 3)."""
        hs, ps = np.zeros((len(self.points), 3)), np.zeros((len(self.points), 3))
        for i, (p, jp) in enumerate(kin(q)):
            force, _, _ = self.force(p, jp @ qd, False)
            ps[i] = p
            if force is not None:
                hs[i] = -force
        return hs, ps

    @abstractmethod
    def force(
        self, p: FloatArray, v: FloatArray, derivatives: bool
    ) -> tuple[FloatArray | None, FloatArray | None, FloatArray | None]:
        """(F, ∂F/∂p, ∂F/∂v): the force on the arm [N] at a point at p [m] moving at v [m/s], or
        (None, None, None) without contact."""


class Plane(Environment):
    """A compliant half-space (a floor, a wall): everything on the side opposite ``normal`` is inside.

    normal: unit outward normal (pointing into free space, towards the arm). point: a point of the surface
    [m]. law: the normal-force law (:class:`~armctl.sim.normal_force.KelvinVoigt` or
    :class:`~armctl.sim.normal_force.HuntCrossley`). friction: Coulomb coefficient μ of the tangential force
    F_t = −μ f_n v_t / max(|v_t|, v_slip), i.e. Coulomb friction above the slip velocity ``slip_velocity``
    [m/s] and a stiff viscous law below it (it does not hold a point exactly still: that is the joints' job).
    points: the contact points of the arm it acts on (default: the tool frame origin).

    Penetration δ = nᵀ(point − p) > 0 and its rate δ̇ = −nᵀṗ give f_n(δ, δ̇); the force on the arm is
    F = f_n n + F_t.
    """

    def __init__(
        self,
        law: NormalForce,
        normal: ArrayLike = (0.0, 0.0, 1.0),
        point: ArrayLike = (0.0, 0.0, 0.0),
        friction: float = 0.0,
        slip_velocity: float = 1e-3,
        points: Sequence[ContactPoint] | None = None,
    ) -> None:
        if not isinstance(law, NormalForce):
            raise InvalidParameterError(
                f"law must be a NormalForce (KelvinVoigt, HuntCrossley), got {law!r}", value=law
            )
        nrm = np.array(real_array(normal, "plane normal"), dtype=float)
        if nrm.shape == (3,) and np.isfinite(nrm).all() and np.abs(nrm).max() > 0.0:
            nrm = nrm / np.abs(nrm).max()  # first: the norm of (1e300, 0, 0) would overflow
        length = float(np.linalg.norm(nrm)) if nrm.shape == (3,) and np.isfinite(nrm).all() else 0.0
        if length < 1e-12:
            raise InvalidParameterError(
                f"plane normal must be a finite non-zero 3-vector, got {normal!r}", value=normal
            )
        pt = real_array(point, "plane point")
        if pt.shape != (3,) or not np.isfinite(pt).all():
            raise InvalidParameterError(f"plane point must be a finite 3-vector, got {point!r}", value=point)
        self.law = law
        self.normal = readonly(nrm / length)
        self.point = readonly(pt)
        self.friction = scalar(friction, "plane friction coefficient", nonnegative=True)
        self.slip_velocity = scalar(slip_velocity, "slip velocity", positive=True)
        pts = (ContactPoint(),) if points is None else (points,) if isinstance(points, ContactPoint) else points
        try:
            pts = tuple(pts)
        except TypeError:
            pts = ()
        if not pts or not all(isinstance(p, ContactPoint) for p in pts):
            raise InvalidParameterError(
                f"points must be a non-empty sequence of ContactPoint, got {points!r}", value=points
            )
        self.points = pts
        self._nn = np.outer(self.normal, self.normal)
        self._tangent_projector = np.eye(3) - self._nn

    def depth(self, p: ArrayLike) -> float:
        """Penetration δ [m] of a point at p (negative: outside)."""
        return float(self.normal @ (self.point - np.asarray(p, dtype=float)))

    def force(
        self, p: FloatArray, v: FloatArray, derivatives: bool
    ) -> tuple[FloatArray | None, FloatArray | None, FloatArray | None]:
        n = self.normal
        depth = float(n @ (self.point - p))
        if depth <= 0.0:
            return None, None, None
        vn = float(n @ v)
        fn, dfn_ddepth, dfn_drate = self.law.force(depth, -vn)
        if fn == 0.0:
            return None, None, None
        dirn = n.copy()  # ∂F/∂f_n: n plus the friction direction factor
        mu = self.friction
        vt = speed = None
        if mu > 0.0:
            vt = v - vn * n
            speed = float(np.sqrt(vt @ vt))
            dirn -= (mu / max(speed, self.slip_velocity)) * vt
        force = fn * dirn
        if not derivatives:
            return force, None, None
        # ∂f_n/∂p = −(∂f_n/∂δ) nᵀ, ∂f_n/∂v = −(∂f_n/∂δ̇) nᵀ
        dfdp = -dfn_ddepth * np.outer(dirn, n)
        dfdv = -dfn_drate * np.outer(dirn, n)
        if mu > 0.0 and vt is not None and speed is not None:
            if speed <= self.slip_velocity:
                dfdv -= (mu * fn / self.slip_velocity) * self._tangent_projector
            else:
                t = vt / speed
                dfdv -= (mu * fn / speed) * (self._tangent_projector - np.outer(t, t))
        return force, dfdp, dfdv

    def __repr__(self) -> str:
        return (
            f"Plane({self.law!r}, normal={self.normal.tolist()}, point={self.point.tolist()}, "
            f"friction={self.friction:g}, {len(self.points)} point(s))"
        )


@dataclass(frozen=True, eq=False)
class ForceSensor:
    """A six-axis force/torque sensor at ``frame`` (None: the tool frame). It reads the wrench the contact
    points attached at or beyond its joint exert on the environment, [f; μ] with the moment about the
    sensor's origin, in the sensor's own axes (``world_axes=False``) or world axes. External disturbances
    are not contacts and are not read."""

    frame: str | None = None
    world_axes: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "world_axes", boolean(self.world_axes, "world_axes"))

    def reading(
        self, dyn: Dynamics, q: FloatArray, forces: FloatArray, positions: FloatArray, joints: FloatArray
    ) -> FloatArray:
        """The (6,) reading from the contact forces on the environment (P, 3), their positions (P, 3) and the
        1-based joint index each point rides on (P,)."""
        mount = dyn.model.frame(self.frame).joint
        pose = dyn.frame_pose(q, self.frame)
        sel = joints >= mount
        f = forces[sel].sum(axis=0) if sel.any() else np.zeros(3)
        m = np.cross(positions[sel] - pose[:3, 3], forces[sel]).sum(axis=0) if sel.any() else np.zeros(3)
        if self.world_axes:
            return np.concatenate([f, m])
        rt = pose[:3, :3].T
        return np.concatenate([rt @ f, rt @ m])
