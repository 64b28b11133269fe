"""What a plant that integrates a whole control period in one call gives :class:`~armctl.sim.loop.ClosedLoop`.

Such a plant (the generated step, :class:`~armctl.sim.compiled_plant.CompiledPlant`) is bound to the run's record
once (``bind_record``) and then does, for each control period k, what the loop does in Python for other plants:
the checks of the controller's torque τ_k (row k of the record) and its saturation, the stick solve at t_k and its
records, the sub-steps and the work, and the check of the state it leaves. It answers with a code: why that state
stops the run (``code & STATE_MASK``) plus the flags below; 0: the run goes on.
"""

from __future__ import annotations

from typing import Protocol

from armctl._checks import FloatArray

#: code & STATE_MASK: why the state a period left stops the run — 0 it does not, 1 it is not finite, 2 a velocity is
#: beyond max_velocity, 3 a position beyond max_position (the reasons of :meth:`ClosedLoop.check
#: <armctl.sim.loop.ClosedLoop.check>`)
STATE_MASK = 3
#: τ_k was clipped at the effort limits (the period held the clipped torque)
CLIPPED = 4
#: τ_k is not finite: the period did nothing else
TORQUE_NOT_FINITE = 8
#: the period failed (a factorisation): :meth:`WholePeriods.raise_failure` raises why
FAILED = 16


class WholePeriods(Protocol):
    """A plant that integrates a whole control period in one call (see the module)."""

    def bind_record(
        self,
        tau: FloatArray,
        q: FloatArray,
        qd: FloatArray,
        qdd: FloatArray,
        tau_friction: FloatArray,
        stuck: FloatArray,
        work_friction: FloatArray,
        work_external: FloatArray,
        effort_limit: FloatArray,
        saturate: bool,
        substeps: int,
        dt: float,
        accel_at_start: bool,
        max_velocity: float,
        max_position: float,
    ) -> None: ...

    def period(self, k: int, t: float) -> float: ...

    def last_sample(self, k: int, t: float) -> float: ...

    def raise_failure(self) -> None: ...
