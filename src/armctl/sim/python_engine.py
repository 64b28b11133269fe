"""`PythonEngine`: the plant advanced by the Python step (an :class:`~armctl.sim.engine.Engine`).

At sample k, before the controller is called: the external torques, contact forces and sensors at t_k
(:meth:`Recorder.record_external <armctl.sim.recorder.Recorder.record_external>`). Over the control period
[t_k, t_k + Δt_c) under the held τ_k: the stick solve at t_k
(:meth:`Plant.begin <armctl.sim.plant.Plant.begin>`) and the friction torque and stuck joints it gives, then m
sub-steps of the integrator (:mod:`armctl.sim.integrators`) with their stick–slip events
(:func:`armctl.sim.stepper.advance`) and the friction and external work; a plant without friction, contact or a
disturbance takes the integrator's step of the rigid dynamics alone (:func:`armctl.sim.integrators.fast_step`).

The generated C period (:mod:`armctl.sim.generated_engine`, ``step_period.c``) transcribes this module's
:meth:`PythonEngine.advance_period`: a change here is a change there (tests/sim/test_compiled_plant.py and every
simulator test compare them).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from armctl._checks import FloatArray
from armctl.sim.engine import TORQUE_NOT_FINITE, EngineRun, state_code
from armctl.sim.integrators import Step
from armctl.sim.plant import Plant
from armctl.sim.stepper import advance

#: a step of the rigid dynamics alone: (q, q̇, τ, h) → (q₁, q̇₁, q̈ at the start)
FastStep = Callable[[FloatArray, FloatArray, FloatArray, float], tuple[FloatArray, FloatArray, FloatArray]]


class PythonEngine:
    """``plant`` advanced by ``step`` (:func:`~armctl.sim.stepper.advance`), or by ``fast`` where the plant has no
    friction, contact or disturbance (see the module)."""

    def __init__(self, plant: Plant, step: Step, fast: FastStep | None) -> None:
        self.plant = plant
        self.step = step
        self.fast = fast
        self.q = self.qd = np.zeros(plant.n)
        self._work_friction = self._work_external = 0.0
        self.observes = plant.has_external

    def bind(self, run: EngineRun) -> None:
        self._rec = rec = run.record
        self._hold = run.saturation.hold
        self._m, self._h, self._accel_at_start = run.substeps, run.dt, run.accel_at_start
        self._stop = (run.max_velocity, run.max_position)
        self.q, self.qd = rec.q[0].copy(), rec.qd[0].copy()
        self._work_friction = self._work_external = 0.0
        if not self.plant.simple:  # the friction torque of a sample the run stops at before its stick solve: NaN
            rec.tau_friction.fill(math.nan)

    def observe(self, k: int, t: float) -> None:
        pl = self.plant
        if pl.has_external:
            self._rec.record_external(k, pl, t, self.q, self.qd)

    def advance_period(self, k: int, t: float, tau: FloatArray) -> int:
        """(:meth:`Engine.advance_period <armctl.sim.engine.Engine.advance_period>`; ``step_period.c``'s
        ``period`` is its C transcription.)"""
        held = self._hold(k, tau)
        if held is None:
            return TORQUE_NOT_FINITE
        rec, pl, h = self._rec, self.plant, self._h
        q, qd = self.q, self.qd
        self._begin(k, t, q, qd, held)
        if self._accel_at_start:
            rec.qdd[k] = pl.accel(t, q, qd, held)
        fast = self.fast
        if fast is not None:  # no friction, contact or disturbance
            for i in range(self._m):
                q, qd, a0 = fast(q, qd, held, h)
                if i == 0:
                    rec.qdd[k] = a0
        else:
            step = self.step
            for i in range(self._m):
                q, qd, a_sub, dwf, dwe = advance(pl, step, t + i * h, q, qd, held, h, begun=i == 0)
                if i == 0 and a_sub is not None:
                    rec.qdd[k] = a_sub
                self._work_friction += dwf
                self._work_external += dwe
        self.q, self.qd = q, qd
        rec.q[k + 1] = q
        rec.qd[k + 1] = qd
        if not pl.simple:
            rec.work_friction[k + 1] = self._work_friction
            rec.work_external[k + 1] = self._work_external
        return state_code(q, qd, *self._stop)

    def last_sample(self, k: int, t: float, tau: FloatArray) -> int:
        held = self._hold(k, tau)
        if held is None:
            return TORQUE_NOT_FINITE
        q, qd = self.q, self.qd
        self._begin(k, t, q, qd, held)
        self._rec.qdd[k] = self.plant.accel(t, q, qd, held)
        return 0

    def _begin(self, k: int, t: float, q: FloatArray, qd: FloatArray, tau: FloatArray) -> None:
        """The plant's stick solve at sample k and what it records of it."""
        pl = self.plant
        if not pl.simple:
            pl.begin(t, q, qd, tau)
            self._rec.record_friction(k, pl, qd)

    def info(self) -> dict[str, Any]:
        pl = self.plant
        return {
            "friction": pl.friction.name if pl.friction is not None else "none",
            "compiled": False,
            **pl.stats,
        }
