"""Contact environments: they turn the pose and velocity of points on the arm into forces.

:class:`ContactPoint` (a point rigidly attached to a frame of the arm), :class:`Environment` (what the arm touches;
the equations of the contact torque are given with it), :class:`Plane` (a compliant half-space, the built-in
environment) and :class:`ForceSensor` (what a six-axis sensor on the arm reads).
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
    """A point rigidly attached to a frame of the plant model, where an :class:`Environment` can push on the arm.

    Parameters
    ----------
    frame : str, optional
        The frame the point rides on (a name of the model's ``frame_names``); None (the default): the tool frame,
        or the last joint's frame if the model has none. Checked against the model when the environment is
        given to ``simulate``.
    offset : array_like, shape (3,), optional
        The point's position [m] from the frame's origin, in the frame's own axes; zero by default. Stored as a
        read-only copy.

    Raises
    ------
    InvalidParameterError
        ``offset`` is not a finite 3-vector of real numbers.
    ShapeError
        ``offset`` is a ragged sequence.
    """

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
    """Something the arm touches: it turns the position and velocity of contact points on the arm into forces.

    A subclass sets :attr:`points` and implements :meth:`force`; the joint torques, the forces on the
    environment and the derivatives of the implicit integrators follow from it. :class:`Plane` is the built-in
    environment; the generated simulation step (``simulate(compile=...)``) covers it with the built-in normal
    laws, and a plant with an environment of another class (a subclass included) runs on the Python step.

    Attributes
    ----------
    points : tuple of ContactPoint
        The contact points on the arm it acts on.

    Notes
    -----
    For every point p the environment gives the force F_p [N] it exerts on the arm; the force the arm exerts on
    the environment is h_p = −F_p, and the joint torque of the contacts enters the dynamics as::

        M q̈ + C q̇ + g = τ − τ_f − Σ_p J_p(q)ᵀ h_p,        J_p = J_lin − [r_p]× J_ang

    with J_p (3×n) the Jacobian of the point's velocity, J_lin and J_ang the rows of its frame's Jacobian in
    world axes, and r_p the point's offset from its frame's origin, in world axes. For the implicit integrators
    an environment also gives the joint-space stiffness and damping::

        K = Σ_p J_pᵀ (∂F_p/∂p) J_p,        D = Σ_p J_pᵀ (∂F_p/∂ṗ) J_p

    without the terms in the derivatives of J_p (geometric stiffness): Newton's method then converges more
    slowly, to the same step.
    """

    points: tuple[ContactPoint, ...] = ()

    def check(self, model: RobotModel) -> None:
        """Check the contact points against the plant's model (``simulate`` calls it once, before the run).

        Parameters
        ----------
        model : RobotModel
            The plant's model.

        Raises
        ------
        UnknownNameError
            A point names a frame the model does not have (the error lists the model's frames).
        """
        for p in self.points:
            model.frame(p.frame)

    def kinematics(self, dyn: Dynamics) -> PointKinematics:
        """The evaluator of this environment's points on the plant: built once, called at every step.

        Parameters
        ----------
        dyn : Dynamics
            The plant's dynamics (its frames' poses and Jacobians).

        Returns
        -------
        PointKinematics
            A callable ``q -> [(p, J_p)]``: every point's position p (3,) [m] and velocity Jacobian
            J_p (3, n), in world axes.
        """
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
        """The joint torque of the contact forces, and its derivatives for the implicit integrators.

        Parameters
        ----------
        kin : PointKinematics
            :meth:`kinematics` of the plant.
        q : ndarray, shape (n,)
            Joint positions [rad] (m for a prismatic joint).
        qd : ndarray, shape (n,)
            Joint velocities [rad/s].
        stiffness : bool, optional
            Whether to compute K and D as well.

        Returns
        -------
        tau : ndarray, shape (n,)
            τ_c = Σ_p J_pᵀ F_p [N·m], the joint torque of the forces on the arm; it is *added* to τ.
        K : ndarray, shape (n, n), or None
            With ``stiffness``: Σ_p J_pᵀ (∂F_p/∂p) J_p [N·m/rad], ∂τ_c/∂q without the terms in the derivatives of
            J_p (see Notes of :class:`Environment`); else None.
        D : ndarray, shape (n, n), or None
            With ``stiffness``: ∂τ_c/∂q̇ = Σ_p J_pᵀ (∂F_p/∂ṗ) J_p [N·m·s/rad]; else None.
        """
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
        """The force each contact point exerts on the environment, and where it is (what force sensors read).

        Parameters
        ----------
        kin, q, qd
            As for :meth:`joint_torque`.

        Returns
        -------
        h : ndarray, shape (P, 3)
            h_p = −F_p [N], world axes, for each of the P points (zero for a point out of contact).
        p : ndarray, shape (P, 3)
            The points' positions [m], world axes.
        """
        _, hs, ps = self.contact(kin, q, qd)
        return hs, ps

    def contact(self, kin: PointKinematics, q: FloatArray, qd: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """:meth:`joint_torque`'s τ_c and :meth:`forces`' h and p, from one evaluation of the points' kinematics.

        Parameters
        ----------
        kin, q, qd
            As for :meth:`joint_torque`.

        Returns
        -------
        tau : ndarray, shape (n,)
            τ_c [N·m], as for :meth:`joint_torque`.
        h, p : ndarray, shape (P, 3)
            As for :meth:`forces`.
        """
        tau = np.zeros(kin.dyn.n)
        hs, ps = np.zeros((len(self.points), 3)), np.zeros((len(self.points), 3))
        for i, (p, jp) in enumerate(kin(q)):
            force, _, _ = self.force(p, jp @ qd, False)
            ps[i] = p
            if force is not None:
                tau += jp.T @ force
                hs[i] = -force
        return tau, hs, ps

    @abstractmethod
    def force(
        self, p: FloatArray, v: FloatArray, derivatives: bool
    ) -> tuple[FloatArray | None, FloatArray | None, FloatArray | None]:
        """The force the environment exerts on the arm at one point.

        Parameters
        ----------
        p : ndarray, shape (3,)
            The point's position [m], world axes.
        v : ndarray, shape (3,)
            Its velocity ṗ [m/s], world axes.
        derivatives : bool
            Whether to compute ∂F/∂p and ∂F/∂v as well.

        Returns
        -------
        F : ndarray, shape (3,), or None
            The force on the arm [N], world axes; None without contact.
        dF_dp : ndarray, shape (3, 3), or None
            ∂F/∂p [N/m] with ``derivatives`` (and contact), else None.
        dF_dv : ndarray, shape (3, 3), or None
            ∂F/∂v [N·s/m] with ``derivatives`` (and contact), else None.
        """


class Plane(Environment):
    """A compliant half-space (a floor, a wall): everything on the side of the surface opposite ``normal`` is
    inside, and a contact point inside is pushed out along the normal, with Coulomb friction along the surface.

    Parameters
    ----------
    law : NormalForce
        The normal-force law f_n(δ, δ̇): :class:`KelvinVoigt` or :class:`HuntCrossley`.
    normal : array_like, shape (3,), optional
        The outward normal n (world axes), pointing into free space, towards the arm; normalised here. Default:
        +z, a floor.
    point : array_like, shape (3,), optional
        A point of the surface [m], world axes. Default: the origin.
    friction : float, optional
        The Coulomb coefficient μ ≥ 0 of the tangential force; 0 (the default): a frictionless surface.
    slip_velocity : float, optional
        v_slip > 0 [m/s]: the tangential speed below which the friction becomes viscous (see Notes).
    points : ContactPoint or sequence of ContactPoint, optional
        The contact points of the arm the plane acts on; None (the default): the tool frame's origin.

    Attributes
    ----------
    law : NormalForce
        As given.
    normal : ndarray, shape (3,)
        The unit outward normal n (read-only).
    point : ndarray, shape (3,)
        As given (read-only) [m].
    friction : float
        The Coulomb coefficient μ.
    slip_velocity : float
        The slip velocity v_slip [m/s].
    points : tuple of ContactPoint
        The points it acts on.

    Raises
    ------
    InvalidParameterError
        ``law`` is not a :class:`NormalForce`; ``normal`` is not a finite non-zero 3-vector; ``point`` is not a
        finite 3-vector; ``friction`` < 0 or ``slip_velocity`` ≤ 0; ``points`` is empty or holds anything but
        ContactPoint objects.
    NonFiniteError
        ``friction`` or ``slip_velocity`` is NaN or infinite.
    ShapeError
        ``normal`` or ``point`` is a ragged sequence.

    Notes
    -----
    A point at p moving at ṗ has the penetration δ = nᵀ(point − p) and its rate δ̇ = −nᵀṗ; it touches while
    δ > 0 and f_n(δ, δ̇) > 0. The force on the arm is then::

        F = f_n n + F_t,        F_t = −μ f_n v_t / max(‖v_t‖, v_slip),        v_t = ṗ − (nᵀṗ) n

    that is Coulomb friction μ f_n against the sliding direction above the slip velocity, and a stiff viscous
    law (μ f_n / v_slip) v_t below it: it slows a point down but does not hold it exactly still (sticking is the
    joints' friction's job, see :class:`StickSlip`).
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
        """The penetration of a point: how far it is inside the half-space.

        Parameters
        ----------
        p : array_like, shape (3,)
            The point's position [m], world axes.

        Returns
        -------
        float
            δ = nᵀ(point − p) [m]; negative outside.
        """
        return float(self.normal @ (self.point - np.asarray(p, dtype=float)))

    def force(
        self, p: FloatArray, v: FloatArray, derivatives: bool
    ) -> tuple[FloatArray | None, FloatArray | None, FloatArray | None]:
        # (a second source: armctl.sim.generated_plant.PlantExpressions.contact, the generated step's;
        # a change here is a change there: tests/sim/test_compiled_plant.py fails when they disagree)
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
    """A six-axis force/torque sensor on the arm: it reads the wrench that the contact points at or beyond its
    joint exert on the environment (``simulate(sensors=...)`` records it in ``SimResult.sensor``).

    Parameters
    ----------
    frame : str, optional
        The frame the sensor is mounted at (a name of the model's ``frame_names``); None (the default): the tool
        frame. Checked against the model by ``simulate``.
    world_axes : bool, optional
        False (the default): the reading in the sensor's own axes (those of ``frame``); True: in world axes.

    Raises
    ------
    InvalidParameterError
        ``world_axes`` is not True or False.

    Notes
    -----
    The reading is [f; m] (6,): the sum f [N] of the forces h_p = −F_p of the contact points riding on the
    sensor's joint or on a joint after it (what the arm exerts: the sense of ``SimResult.wrench`` and
    ``SimResult.contact_force_on_environment``, opposite to ``SimResult.contact_force_on_robot``), and their
    moment m = Σ_p (p − o) × h_p [N·m] about the sensor's origin o. External disturbances
    (``simulate(disturbance=...)``) are not contacts and are not read.
    """

    frame: str | None = None
    world_axes: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "world_axes", boolean(self.world_axes, "world_axes"))

    def reading(
        self, dyn: Dynamics, q: FloatArray, forces: FloatArray, positions: FloatArray, joints: FloatArray
    ) -> FloatArray:
        """The sensor's reading at one state (the simulator calls it at every sample).

        Parameters
        ----------
        dyn : Dynamics
            The plant's dynamics (the sensor frame's pose).
        q : ndarray, shape (n,)
            Joint positions [rad] (m for a prismatic joint).
        forces : ndarray, shape (P, 3)
            The force h_p [N] each contact point exerts on the environment, world axes
            (:meth:`Environment.forces`).
        positions : ndarray, shape (P, 3)
            The points' positions [m], world axes.
        joints : ndarray, shape (P,)
            The 1-based index of the joint each point rides on (0: the world).

        Returns
        -------
        ndarray, shape (6,)
            [f; m]: force [N] and moment about the sensor's origin [N·m], in the sensor's axes or world axes
            (``world_axes``).

        Raises
        ------
        UnknownNameError
            The model has no frame ``frame``.
        """
        mount = dyn.model.frame(self.frame).joint
        pose = dyn.frame_pose(q, self.frame)
        sel = joints >= mount
        f = forces[sel].sum(axis=0) if sel.any() else np.zeros(3)
        m = np.cross(positions[sel] - pose[:3, 3], forces[sel]).sum(axis=0) if sel.any() else np.zeros(3)
        if self.world_axes:
            return np.concatenate([f, m])
        rt = pose[:3, :3].T
        return np.concatenate([rt @ f, rt @ m])
