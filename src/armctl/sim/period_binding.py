"""`PeriodBinding`: what the generated C period (``step_period.c``) reads and writes of a run's record.

:class:`~armctl.sim.generated_engine.GeneratedEngine` makes it from the run's
:class:`~armctl.sim.recorder.Recorder` and hands it to
:meth:`CompiledPlant.bind_record <armctl.sim.compiled_plant.CompiledPlant.bind_record>`, which keeps the rows'
addresses for every period of the run.
"""

from __future__ import annotations

from dataclasses import dataclass

from armctl._checks import FloatArray


@dataclass(frozen=True)
class PeriodBinding:
    """The rows the generated period reads and writes, and how it integrates a period.

    The arrays are C-contiguous float64 arrays of the run's samples (the generated code reads and writes them by
    row): (samples, n) ones of the controller's torques (read), q, q̇, q̈, the friction torque, the stuck joints (1.0:
    stuck) and the applied torques, and (samples,) ones of the friction and external work [J].

    Parameters
    ----------
    tau, q, qd, qdd, tau_friction, stuck, tau_applied : (samples, n) ndarray
        The record's rows (see above).
    work_friction, work_external : (samples,) ndarray
        The record's work.
    effort_limit : (n,) ndarray
        τ̄ [N·m or N] (inf: none), the limits the torque held is clipped at where ``saturate``.
    saturate : bool
        Clip the torque held at ``effort_limit`` (:class:`~armctl.sim.saturation.Saturation`).
    substeps : int
        Integration steps m per control period.
    dt : float
        The integration step h [s].
    accel_at_start : bool
        q̈ at the period's start by an evaluation (the implicit schemes, whose step gives none).
    max_velocity, max_position : float
        The stop rules the state a period leaves is checked against (:func:`armctl.sim.engine.state_code`).
    contact_force, contact_position : (samples, 3 P) ndarray, optional
        The record's forces h_p [N] of the P contact points on the environment and their positions [m] (written
        where ``record_contacts``).
    tau_ext : (samples, n) ndarray, optional
        The record's external torques τ_ext [N·m or N] (written where ``record_contacts``).
    wrench : (samples, 6) ndarray, optional
        The record's wrench on the environment about the tool frame's origin [N, N·m] (written where
        ``record_contacts``).
    record_contacts : bool, optional
        The period records the contacts at the state it leaves (a plant with contact points and no disturbance;
        the four arrays above are then given). False by default.
    """

    tau: FloatArray
    q: FloatArray
    qd: FloatArray
    qdd: FloatArray
    tau_friction: FloatArray
    stuck: FloatArray
    work_friction: FloatArray
    work_external: FloatArray
    tau_applied: FloatArray
    effort_limit: FloatArray
    saturate: bool
    substeps: int
    dt: float
    accel_at_start: bool
    max_velocity: float
    max_position: float
    contact_force: FloatArray | None = None
    contact_position: FloatArray | None = None
    tau_ext: FloatArray | None = None
    wrench: FloatArray | None = None
    record_contacts: bool = False
