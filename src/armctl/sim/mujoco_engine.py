"""``simulate(..., engine="mujoco")``: :class:`MujocoEngine`, the plant advanced by MuJoCo (an
:class:`~armctl.sim.engine.Engine` of :class:`~armctl.sim.loop.ClosedLoop`).

The loop is the native one, the same :class:`~armctl.sim.loop.ClosedLoop`: at every control instant t_k = k·Δt_c
the controller is given the measured state (noise, delay) and the reference; its torque, saturated at the armctl
model's effort limits, is held over [t_k, t_k + Δt_c) (zero-order hold, as ``qfrc_applied`` on the arm's joints)
while MuJoCo integrates m = Δt_c/Δt steps of its own integrator; a state that is not finite or beyond
``max_velocity`` / ``max_position``, or a non-finite torque, ends the run as diverged. What differs is the plant
(:mod:`armctl.sim.mujoco_plant`): MuJoCo's equations, contacts and joint friction (``frictionloss``, a soft
constraint: a joint loaded below its friction level creeps where armctl's stick–slip model holds it exactly), the
scene's geometry.

Each step is ``mj_forward`` then the integrator (what ``mj_step`` does, without MuJoCo's reset of a diverging
state: the loop reports it instead); the forward dynamics of a sample's first step give what is recorded at the
sample: q̈, the friction and external torques, the contact forces and the wrench. ``disturbance`` is held over each
step (its joint torque −J_toolᵀ h_d from the state at the step's start); the work of friction and of the external
forces over a step is that of the forces at its start.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from armctl._checks import FloatArray, real_array, vector
from armctl._mujoco import require_mujoco
from armctl.codegen import compile_mode
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError, UnknownNameError
from armctl.model.robot import RobotModel
from armctl.sim import setup
from armctl.sim.engine import TORQUE_NOT_FINITE, EngineRun, state_code
from armctl.sim.mujoco_plant import MujocoPlant, Readout, available_integrators, integrator_code
from armctl.sim.options import Forces


@dataclass(frozen=True)
class MujocoTarget:
    """The MuJoCo scene a run integrates and the armctl dynamics of its arm (effort limits, tool frame, energy)."""

    plant: MujocoPlant
    dynamics: Dynamics


def target(plant: Any, integrator: Any, forces: Forces, compile: Any) -> MujocoTarget:
    """``simulate``'s plant on MuJoCo, checked: a :class:`~armctl.sim.mujoco_plant.MujocoPlant`, or a Dynamics /
    RobotModel (then :meth:`MujocoPlant.from_model`). ``integrator`` must be one of MuJoCo's, ``"rk4"``,
    ``"euler"``, ``"implicit"``, ``"implicitfast"`` or ``"discrete"``
    (:data:`~armctl.sim.mujoco_plant.MUJOCO_INTEGRATORS`). Joint friction is the plant's ``frictionloss`` and
    ``damping`` (``forces.friction`` must stay at its default); contact is the scene's (``forces.environment`` must
    be None); ``compile`` must not be True.

    Raises
    ------
    InvalidParameterError
        An option MuJoCo does not take, or a plant of another type.
    UnknownNameError
        An integrator that is not MuJoCo's.
    MissingDependencyError
        MuJoCo is not installed.
    """
    require_mujoco("simulate(..., engine='mujoco')")
    if not (isinstance(forces.friction, str) and forces.friction == "stick-slip"):
        _refuse("friction", forces.friction, "the joint friction is MuJoCo's frictionloss and damping of the plant")
    if forces.environment is not None and forces.environment != ():
        why = "contact is the MuJoCo scene's: put the geometry in its MJCF (MujocoPlant)"
        _refuse("environment", forces.environment, why)
    if compile_mode(compile) is True:
        _refuse("compile", compile, "MuJoCo integrates the plant")
    names = available_integrators()
    if integrator not in names:
        raise UnknownNameError("MuJoCo integrator", integrator, names)
    if isinstance(plant, MujocoPlant):
        return MujocoTarget(plant, Dynamics(plant.model))
    if not isinstance(plant, Dynamics | RobotModel):
        raise InvalidParameterError(
            "with engine='mujoco' the plant must be an armctl.sim.MujocoPlant (a MuJoCo scene), an armctl.Dynamics "
            f"or an armctl.RobotModel; got {type(plant).__name__}",
            value=plant,
        )
    dyn = setup.plant_dynamics(plant)
    return MujocoTarget(MujocoPlant.from_model(dyn.model), dyn)


def _refuse(name: str, value: Any, why: str) -> None:
    raise InvalidParameterError(f"{name}={value!r} is not available with engine='mujoco': {why}", value=value)


class MujocoEngine:
    """The scene of ``target`` integrated by MuJoCo's ``integrator`` at step ``dt`` [s], pushed by ``disturbance``
    (t → h_d, or None) (see the module)."""

    def __init__(self, target: MujocoTarget, dyn: Dynamics, integrator: str, dt: float, disturbance: Any) -> None:
        self.mj = mj = require_mujoco("simulate(..., engine='mujoco')")
        self.dyn = dyn
        self.disturbance = disturbance
        self.integrator = integrator
        self.m, chain = m, _ = target.plant.compile()
        m.opt.timestep = dt
        m.opt.integrator = integrator_code(mj, integrator)
        m.opt.disableflags |= int(mj.mjtDisableBit.mjDSBL_ACTUATION)  # the controller's torque is all that drives
        self.d = d = mj.MjData(m)
        self.readout = ro = Readout.of(mj, m, chain)
        self._qadr, self._vadr = ro.qadr, ro.vadr
        self._h = dt
        self._own_step = {"rk4": lambda: mj.mj_RungeKutta(m, d, 4), "euler": lambda: mj.mj_Euler(m, d)}.get(
            integrator, (lambda: mj.mj_implicit(m, d)) if integrator in ("implicit", "implicitfast") else None
        )
        self.contact = not (m.opt.disableflags & mj.mjtDisableBit.mjDSBL_CONTACT) and bool(
            np.any(m.geom_contype) or np.any(m.geom_conaffinity)
        )
        self.has_friction = bool(np.any(m.dof_damping[self._vadr]) or np.any(m.dof_frictionloss[self._vadr]))
        self.simple = not (self.contact or self.has_friction or disturbance is not None or m.neq or m.ntendon)
        self._wf = self._we = 0.0
        self._sensors_read = self.observes = False

    def bind(self, run: EngineRun) -> None:
        self._rec = rec = run.record
        self._hold = run.saturation.hold
        self._substeps = run.substeps
        self._sensors_read = self.observes = run.sensors_read
        self._stop = (run.max_velocity, run.max_position)
        rec.contact_force = np.zeros((rec.samples, self.dyn.n, 3))  # one row per link: the force it exerts
        self.d.qpos[self._qadr] = rec.q[0]
        self.d.qvel[self._vadr] = rec.qd[0]
        self._wf = self._we = 0.0

    def observe(self, k: int, t: float) -> None:
        """The sensors at the state of sample k under the forces still held (τ_{k−1}, zeros at k = 0), where the
        controller reads them: the forward dynamics of a state's contacts depend on the torque applied, and what
        is recorded at sample k (:meth:`advance_period`'s first forward dynamics) is under τ_k."""
        if not self._sensors_read:
            return
        mj, d, rec, ro = self.mj, self.d, self._rec, self.readout
        mj.mj_forward(self.m, d)
        q = d.qpos[self._qadr]
        hs, _, ps, links = ro.contacts(d)
        for i, sensor in enumerate(rec.sensors):
            rec.sensor[k, i] = sensor.reading(self.dyn, q, hs, ps, links)

    def advance_period(self, k: int, t: float, tau: FloatArray) -> int:
        """(:meth:`Engine.advance_period <armctl.sim.engine.Engine.advance_period>`: ``mj_forward`` then the
        integrator, m times; the first forward gives what is recorded at sample k.)"""
        held = self._hold(k, tau)
        if held is None:
            return TORQUE_NOT_FINITE
        self._period(k, t, held, self._substeps)
        rec, d = self._rec, self.d
        rec.q[k + 1] = d.qpos[self._qadr]
        rec.qd[k + 1] = d.qvel[self._vadr]
        if not self.simple:
            rec.work_friction[k + 1], rec.work_external[k + 1] = self._wf, self._we
        return state_code(rec.q[k + 1], rec.qd[k + 1], *self._stop)

    def last_sample(self, k: int, t: float, tau: FloatArray) -> int:
        held = self._hold(k, tau)
        if held is None:
            return TORQUE_NOT_FINITE
        self._period(k, t, held, 0)
        return 0

    def _period(self, k: int, t: float, tau: FloatArray, substeps: int) -> None:
        """The forward dynamics at sample k and what is recorded of them, then ``substeps`` steps (none: the
        forward dynamics only)."""
        mj, m, d, dyn, ro = self.mj, self.m, self.d, self.dyn, self.readout
        qadr, vadr, rec, h = self._qadr, self._vadr, self._rec, self._h
        qfrc = d.qfrc_applied
        q = d.qpos[qadr]
        simple = self.simple
        for s in range(max(substeps, 1)):
            hd = None
            if self.disturbance is not None:
                hd = vector(real_array(self.disturbance(t + s * h), "disturbance(t)"), 6, "disturbance(t) (a wrench)")
                qfrc[vadr] = tau - dyn.jacobian(d.qpos[qadr] if s else q).T @ hd
            else:
                qfrc[vadr] = tau
            mj.mj_forward(m, d)
            if s == 0:
                rec.qdd[k] = d.qacc[vadr]
            if not simple:
                tf, te = ro.torques(d)
                if s == 0:
                    ro.record(rec, d, dyn, k, q, tf, te, hd)
            if substeps == 0:
                return
            before = d.qpos[qadr] if not simple else None
            if self._own_step is not None:
                self._own_step()
            else:
                mj.mj_step(m, d)  # (an integrator without its own entry point: one more forward dynamics)
            if before is not None:
                dq = d.qpos[qadr] - before
                self._wf -= float(tf @ dq)
                self._we -= float(te @ dq)
                if hd is not None:  # −J_toolᵀ h_d is in qfrc_applied, not in te
                    self._we += float((qfrc[vadr] - tau) @ dq)

    def info(self) -> dict[str, Any]:
        return {
            "engine": "mujoco",
            "mujoco": self.mj.__version__,
            "backend": "mujoco",
            "friction": "frictionloss" if self.has_friction else "none",
            "contact": bool(self.contact),
            "compiled": False,
        }
