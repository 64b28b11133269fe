"""`ModelState`: the model terms one control step needs, evaluated once at the measured (q, q̇).

    M(q),  h(q, q̇) = C(q, q̇) q̇ + g(q),  τ_f(q̇),  and per frame: pose, J (6×n), v = J q̇, J̇ q̇

Frames follow :meth:`armctl.Dynamics.jacobian`: world-aligned axes at the frame origin, rows [linear; angular].
J̇ q̇ is the classical acceleration of the frame origin at q̈ = 0 (the drift of the task acceleration,
ẍ = J q̈ + J̇ q̇).

Two evaluators:

* Pinocchio dynamics: one ``computeAllTerms`` pass (M, h, joint Jacobians, placements, velocities, the
  accelerations at q̈ = 0), then frame placement, ``getFrameJacobian`` and ``getFrameClassicalAcceleration``
  (LOCAL_WORLD_ALIGNED) per frame asked for.
* Any other backend (e.g. ``"lagrange"``): the public :class:`~armctl.Dynamics` API, with J̇ q̇ by a central
  difference of J along q̇:  J̇ q̇ ≈ [J(q + s q̇) − J(q − s q̇)] / (2 s) · q̇,  s = 1e-6 rad / ‖q̇‖_∞ (truncation
  error O(s²‖q̇‖³), i.e. ~1e-12 relative; zero drift at rest).
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np

from armctl._checks import FloatArray
from armctl.dynamics.base import Dynamics

_FD_STEP = 1e-6  # [rad] largest joint displacement of the finite difference of J


class FrameKinematics:
    """Kinematics of one frame at the current state: ``position`` (3,) [m], ``rotation`` (3×3),
    ``jacobian`` (6×n), ``velocity`` = J q̇ (6,) [m/s; rad/s], ``drift`` = J̇ q̇ (6,) [m/s²; rad/s²]."""

    __slots__ = ("drift", "jacobian", "position", "rotation", "velocity")

    def __init__(
        self, position: FloatArray, rotation: FloatArray, jacobian: FloatArray, velocity: FloatArray, drift: FloatArray
    ) -> None:
        self.position = position
        self.rotation = rotation
        self.jacobian = jacobian
        self.velocity = velocity
        self.drift = drift


class ModelState:
    """The model terms at (q, q̇): ``q``, ``qd``, ``mass`` M (n×n), ``bias`` h = C q̇ + g (n,) [N·m],
    ``friction`` τ_f(q̇) (n,) [N·m]; :meth:`frame` gives :class:`FrameKinematics`, computed on first use.

    With Pinocchio the arrays may be views of the evaluator's workspace: a state is valid until the next
    :meth:`ModelEvaluator.evaluate` (the QP built from it copies what it keeps)."""

    __slots__ = ("_evaluator", "_frames", "bias", "friction", "mass", "q", "qd")

    def __init__(
        self,
        evaluator: ModelEvaluator,
        q: FloatArray,
        qd: FloatArray,
        mass: FloatArray,
        bias: FloatArray,
        friction: FloatArray | None,
    ) -> None:
        self._evaluator = evaluator
        self._frames: dict[str | None, FrameKinematics] = {}
        self.q = q
        self.qd = qd
        self.mass = mass
        self.bias = bias
        self.friction = friction

    def frame(self, name: str | None = None) -> FrameKinematics:
        """Kinematics of frame ``name`` (None: the tool frame)."""
        fk = self._frames.get(name)
        if fk is None:
            fk = self._frames[name] = self._evaluator.frame(self, name)
        return fk


class ModelEvaluator:
    """Evaluates :class:`ModelState` for one :class:`~armctl.Dynamics` (holds its workspace; not
    thread-safe)."""

    def __init__(self, dynamics: Dynamics) -> None:
        self.dynamics = dynamics
        self.n = dynamics.n
        self.has_friction = dynamics.model.has_friction
        self._pin: Any = None
        self._fid: dict[str | None, int] = {}
        if getattr(dynamics, "backend", "") == "pinocchio" and hasattr(dynamics, "pin_model"):
            import pinocchio

            self._pin = pinocchio
            self._pm = dynamics.pin_model
            self._pd = self._pm.createData()  # own workspace: the Dynamics object's data stays untouched
            self._lwa = pinocchio.LOCAL_WORLD_ALIGNED
            # M and h as views of the workspace, which computeAllTerms rewrites in place, so that a step reads
            # them without fetching them from Pinocchio again; kept only if they really are views, as for the
            # frame placements below
            pd = self._pd
            shared = np.shares_memory(pd.M, pd.M) and np.shares_memory(pd.nle, pd.nle)
            self._mass_bias: tuple[FloatArray, FloatArray] | None = (pd.M, pd.nle) if shared else None
        # per frame index: (translation, rotation) as views of the frame's placement in the workspace, which
        # every evaluate() rewrites in place; only kept if they really are views (checked when first made),
        # else None and the placement is read afresh from Pinocchio each time
        self._pose_views: dict[int, tuple[FloatArray, FloatArray] | None] = {}

    def __reduce__(self) -> tuple[Any, ...]:
        # rebuilt from the dynamics (which pickle by rebuilding): the workspace and its views are this
        # process's, and a view pickled would arrive as a copy that never changes
        return (ModelEvaluator, (self.dynamics,))

    def frame_id(self, name: str | None) -> int:
        """Pinocchio frame index of ``name`` (checked against the model's frames; UnknownNameError lists them)."""
        fid = self._fid.get(name)
        if fid is None:
            full = self.dynamics.model.frame(name).name  # raises UnknownNameError listing the valid names
            fid = -1 if full == "world" else int(self._pm.getFrameId(full))
            self._fid[name] = fid
        return fid

    def check_frame(self, name: str | None) -> None:
        """Raise :class:`~armctl.errors.UnknownNameError` (listing the valid names) if ``name`` is unknown."""
        self.dynamics.model.frame(name)

    def evaluate(self, q: FloatArray, qd: FloatArray) -> ModelState:
        """Model terms at (q, q̇), which must be finite float (n,) arrays: the controller's ``__call__``,
        ``build`` and ``solve`` check them before they get here, and nothing is checked again (a NaN here gives
        NaN terms, not an error)."""
        fr = self.dynamics.friction.torque(qd) if self.has_friction else None
        if self._pin is not None:
            pd = self._pd
            self._pin.computeAllTerms(self._pm, pd, q, qd)
            self._pin.updateFramePlacements(self._pm, pd)
            mass, bias = self._mass_bias or (pd.M, pd.nle)  # views of the workspace (see ModelState)
            return ModelState(self, q, qd, mass, bias, fr)
        dyn = self.dynamics
        bias = dyn.coriolis_matrix(q, qd) @ qd + dyn.gravity_torque(q)
        return ModelState(self, q, qd, dyn.mass_matrix(q), bias, fr)

    def _placement_views(self, fid: int) -> tuple[FloatArray, FloatArray] | None:
        """(translation, rotation) of frame ``fid`` as views of the workspace's placement, or None if eigenpy
        hands out copies (then they would go stale at the next evaluate)."""
        pose, again = self._pd.oMf[fid], self._pd.oMf[fid]
        p, r = pose.translation, pose.rotation
        if np.shares_memory(p, again.translation) and np.shares_memory(r, again.rotation):
            return p, r
        return None

    def frame(self, state: ModelState, name: str | None) -> FrameKinematics:
        if self._pin is not None:
            fid = self.frame_id(name)
            if fid < 0:
                z6 = np.zeros(6)
                return FrameKinematics(np.zeros(3), np.eye(3), np.zeros((6, self.n)), z6, z6.copy())
            pin, pm, pd = self._pin, self._pm, self._pd
            views: tuple[FloatArray, FloatArray] | Literal[False] | None = self._pose_views.get(fid, False)
            if views is False:
                views = self._pose_views[fid] = self._placement_views(fid)
            if views is None:
                pose = pd.oMf[fid]
                views = (pose.translation, pose.rotation)
            jac = pin.getFrameJacobian(pm, pd, fid, self._lwa)
            if self.n == 1:  # eigenpy squeezes a 6×1 result to (6,)
                jac = jac.reshape(6, 1)
            drift = pin.getFrameClassicalAcceleration(pm, pd, fid, self._lwa).vector
            return FrameKinematics(views[0], views[1], jac, jac.dot(state.qd), drift)
        dyn = self.dynamics
        pose = dyn.frame_pose(state.q, name)
        jac = dyn.jacobian(state.q, name)
        qd = state.qd
        speed = float(np.abs(qd).max())
        if speed == 0.0:
            drift = np.zeros(6)
        else:
            s = _FD_STEP / speed
            drift = (dyn.jacobian(state.q + s * qd, name) - dyn.jacobian(state.q - s * qd, name)) @ qd / (2 * s)
        return FrameKinematics(pose[:3, 3].copy(), pose[:3, :3].copy(), jac, jac @ qd, drift)
