"""`GeneratedEngine`: the plant advanced by the generated C period (an :class:`~armctl.sim.engine.Engine`).

The plant is a :class:`~armctl.sim.compiled_plant.CompiledPlant`; a control period is one call into C
(:meth:`CompiledPlant.period <armctl.sim.compiled_plant.CompiledPlant.period>`, ``step_period.c``), bound once to the
run's record (:class:`~armctl.sim.period_binding.PeriodBinding`): it reads τ_k and the state of sample k from the
record, holds τ_k as :meth:`Saturation.hold <armctl.sim.saturation.Saturation.hold>` does (its C transcription,
``armctl_hold``) and writes what :class:`~armctl.sim.python_engine.PythonEngine` writes — the applied torque, q̈_k, the
friction torque and stuck joints at row k, the state and the work at row k + 1. For a plant with contact points and no
disturbance, the same call records the contacts at the state it leaves, sample k + 1 — the points' forces and positions,
τ_ext and the wrench (the kernel ``pk_sample``, the generated transcription of :meth:`Recorder.record_external
<armctl.sim.recorder.Recorder.record_external>`); sample 0's are recorded when the run is bound, and only the force
sensors' readings are taken in Python, from the recorded forces (:meth:`Recorder.record_sensors
<armctl.sim.recorder.Recorder.record_sensors>`). With a disturbance (a Python callable), the external torques, contact
forces and sensors of a sample are recorded in Python, as the Python engine records them.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, cast

from armctl._checks import FloatArray
from armctl.sim.engine import TORQUE_NOT_FINITE, EngineRun
from armctl.sim.period_binding import PeriodBinding

if TYPE_CHECKING:
    from armctl.sim.compiled_plant import CompiledPlant
    from armctl.sim.plant import Plant


class GeneratedEngine:
    """``plant``'s control periods, each one call into its generated code (see the module)."""

    def __init__(self, plant: CompiledPlant) -> None:
        self.plant = plant
        #: the plant as the recorder takes it (what it reads of a Plant, CompiledPlant has: dyn, environments,
        #: kinematics, external, disturbance_wrench)
        self._duck = cast("Plant", plant)
        #: the period records the contacts (see the module); Python records them with a disturbance
        self._in_c = plant.disturbance is None and bool(plant.layout.points)
        self._external = self.observes = plant.has_external

    def bind(self, run: EngineRun) -> None:
        self._rec = rec = run.record
        if not self.plant.simple:  # the friction torque of a sample the run stops at before its stick solve: NaN
            rec.tau_friction.fill(math.nan)
        rows = ("tau", "q", "qd", "qdd", "tau_friction", "stuck", "work_friction", "work_external", "tau_applied")
        sat = run.saturation
        points = len(rec.points)
        self.plant.bind_record(
            PeriodBinding(
                **{name: getattr(rec, name) for name in rows},
                effort_limit=sat.limit,
                saturate=sat.saturate,
                substeps=run.substeps,
                dt=run.dt,
                accel_at_start=run.accel_at_start,
                max_velocity=run.max_velocity,
                max_position=run.max_position,
                contact_force=rec.contact_force.reshape(len(rec.q), 3 * points),
                contact_position=rec.contact_position.reshape(len(rec.q), 3 * points),
                tau_ext=rec.tau_ext,
                wrench=rec.wrench,
                record_contacts=self._in_c,
            )
        )
        if self._in_c:  # sample 0's contacts (the periods record those of the samples after it)
            self.plant.record_sample(0)
            self._external = self.observes = bool(rec.sensors)
        self._hold = sat.hold
        if self.plant.disturbance is None:
            # a period is the plant's call itself (the same arguments and answer: no Python frame between them)
            self.advance_period = self.plant.period  # type: ignore[method-assign]

    def observe(self, k: int, t: float) -> None:
        if self._external:
            rec, plant = self._rec, self._duck
            if self._in_c:  # the contacts are recorded by the period: the sensors' readings of them
                rec.record_sensors(k, plant, rec.q[k])
            else:
                rec.record_external(k, plant, t, rec.q[k], rec.qd[k])

    def advance_period(self, k: int, t: float, tau: FloatArray) -> int:
        """(:meth:`Engine.advance_period <armctl.sim.engine.Engine.advance_period>`: ``tau`` is read from row k of
        the record's torques, held by ``armctl_hold``; the state code is ``step_period.c``'s
        ``armctl_state_check``.) With a disturbance, τ_k is held in Python first, as the other engines hold it
        before they sample the disturbance (a Python callable, which may raise: the applied torque of the sample
        it fails at is then recorded alike); the C period holds it again, to the same row."""
        if self._hold(k, tau) is None:
            return TORQUE_NOT_FINITE
        return self.plant.period(k, t)

    def last_sample(self, k: int, t: float, tau: FloatArray) -> int:
        return self.plant.last_sample(k, t)

    def info(self) -> dict[str, Any]:
        pl = self.plant
        return {"friction": pl.friction.name if pl.friction is not None else "none", "compiled": True, **pl.stats}
