"""`Engine`: what advances the plant of a run, one control period at a time, for :class:`~armctl.sim.loop.ClosedLoop`.

The loop is one (:mod:`armctl.sim.loop`): at each control instant t_k it checks the state of sample k, measures it,
calls the controller and saturates its torque. The engine does the rest — the plant's side of a sample:

* :meth:`Engine.bind` ties it to the run's record (:class:`EngineRun`), whose row 0 holds the initial state;
* :meth:`Engine.observe` records what the plant shows at the state of sample k before the controller is called
  (contact forces, the sensors, the wrench and external torques), so that a controller that reads a force sensor
  (:mod:`armctl.sim.measurement_feed`) is given the reading of this sample;
* :meth:`Engine.advance_period` records what the plant does at sample k under τ_k (q̈_k, the friction torque, the
  stuck joints) and integrates the period [t_k, t_k + Δt_c) under the held torque τ_k (the applied one, also in row k
  of ``record.tau_applied``), writing the state it reaches and the work so far into row k + 1;
* :meth:`Engine.last_sample` records the plant's side of the run's last sample (no step after it).

Both answer with a status: None, or why the plant cannot be advanced from that state (a mass matrix that is not
positive definite): the loop stops the run there as diverged. What a user's callable raises inside the plant (a
disturbance) passes through: the loop keeps the run up to it.

The engines:

========================================================  =================================================
:class:`~armctl.sim.python_engine.PythonEngine`           the Python step (:mod:`armctl.sim.integrators`,
                                                          :mod:`armctl.sim.stepper`, :class:`~armctl.sim.plant.Plant`)
:class:`~armctl.sim.generated_engine.GeneratedEngine`     the generated C period (:mod:`armctl.sim.compiled_plant`)
:class:`~armctl.sim.mujoco_engine.MujocoEngine`           MuJoCo (``simulate(..., engine="mujoco")``)
========================================================  =================================================
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

from armctl._checks import FloatArray
from armctl.sim.recorder import Recorder


@dataclass(frozen=True)
class EngineRun:
    """What an engine is bound to: the run's record and how a control period is integrated.

    Parameters
    ----------
    record : Recorder
        The run's record; its row 0 holds the initial state (q₀, q̇₀).
    substeps : int
        Integration steps m per control period.
    dt : float
        The integration step h = Δt_c / m [s].
    accel_at_start : bool
        q̈_k by an evaluation at t_k (the implicit schemes, whose step gives none at its start).
    sensors_read : bool
        The controller reads the first force sensor at every sample (:meth:`Engine.observe` must record it).
    """

    record: Recorder
    substeps: int
    dt: float
    accel_at_start: bool
    sensors_read: bool = False


class Engine(Protocol):
    """What advances the plant of a run (see the module)."""

    def bind(self, run: EngineRun) -> None:
        """Tie the engine to ``run``'s record, starting from the state in its row 0."""
        ...

    def observe(self, k: int, t: float) -> None:
        """Record what the plant shows at the state of sample k (time t [s]) before the controller is called."""
        ...

    def advance_period(self, k: int, t: float, tau: FloatArray) -> str | None:
        """Record the plant's side of sample k (time t [s]) and integrate [t, t + Δt_c) under the held ``tau``
        (the applied torque, row k of ``record.tau_applied``); the state reached goes into row k + 1. None, or why
        the plant cannot be advanced."""
        ...

    def last_sample(self, k: int, t: float, tau: FloatArray) -> str | None:
        """Record the plant's side of the run's last sample k under ``tau`` (no step after it). None, or why the
        plant cannot be evaluated there."""
        ...

    def info(self) -> dict[str, Any]:
        """What the run's ``info`` says of the engine and the plant it integrated (after the run)."""
        ...
