"""`Engine`: what advances the plant of a run, one control period at a time, for :class:`~armctl.sim.loop.ClosedLoop`.

The loop is one (:mod:`armctl.sim.loop`): at each control instant t_k it checks the state of sample k, measures it,
calls the controller and records its torque τ_k. The engine does the rest — the plant's side of a sample:

* :meth:`Engine.bind` ties it to the run's record (:class:`EngineRun`), whose row 0 holds the initial state;
* :meth:`Engine.observe` records what the plant shows at the state of sample k before the controller is called
  (contact forces, the sensors, the wrench and external torques), so that a controller that reads a force sensor
  (:mod:`armctl.sim.measurement_feed`) is given the reading of this sample;
* :meth:`Engine.advance_period` holds τ_k by the run's one saturation rule (:mod:`armctl.sim.saturation`: τ_k finite,
  clipped at the effort limits, recorded in row k of ``record.tau_applied``), records what the plant does at sample k
  under the held torque (q̈_k, the friction torque, the stuck joints) and integrates the period [t_k, t_k + Δt_c)
  under it, writing the state it reaches and the work so far into row k + 1. It answers with the status of that
  state: the code of :func:`state_code`, the one stop rule (0: the run goes on), which the generated engine
  evaluates in C as the period ends — or :data:`TORQUE_NOT_FINITE` (τ_k is not finite: nothing is held or
  advanced). The loop turns a code into the run's reason. The Python and MuJoCo engines hold τ_k by
  :meth:`Saturation.hold <armctl.sim.saturation.Saturation.hold>`; the generated engine by its C transcription, in
  the same call as the period;
* :meth:`Engine.last_sample` holds τ_k and records the plant's side of the run's last sample (no step after it).

A plant that cannot be advanced from a state (a mass matrix that is not positive definite) raises
:class:`~armctl.sim.stick_slip.NotPositiveDefinite` (or NumPy's ``LinAlgError``): the loop stops the run there as
diverged. What a user's callable raises inside the plant (a disturbance) passes through: the loop keeps the run up
to it.

The engines:

========================================================  =================================================
:class:`~armctl.sim.python_engine.PythonEngine`           the Python step (:mod:`armctl.sim.integrators`,
                                                          :mod:`armctl.sim.stepper`, :class:`~armctl.sim.plant.Plant`)
:class:`~armctl.sim.generated_engine.GeneratedEngine`     the generated C period (:mod:`armctl.sim.compiled_plant`)
:class:`~armctl.sim.mujoco_engine.MujocoEngine`           MuJoCo (``simulate(..., engine="mujoco")``)
========================================================  =================================================
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from armctl._checks import FloatArray
from armctl.sim.recorder import Recorder
from armctl.sim.saturation import Saturation

#: the codes of :func:`state_code`: the state is fine, not finite, a velocity or a position beyond its bound
STATE_OK, STATE_NOT_FINITE, STATE_VELOCITY, STATE_POSITION = 0, 1, 2, 3
#: the code of an engine given a τ_k that is not finite (it held nothing; ``step_period.c``'s copy: the same value)
TORQUE_NOT_FINITE = 4


def state_code(q: FloatArray, qd: FloatArray, max_velocity: float, max_position: float) -> int:
    """Why the state (q, q̇) stops a run, by the run's stop rules (:class:`~armctl.sim.options.StopRules`).

    Parameters
    ----------
    q, qd : (n,) ndarray
        The state [rad or m, rad/s or m/s].
    max_velocity, max_position : float
        The bounds on |q̇_i| and |q_i| (inf: none).

    Returns
    -------
    int
        :data:`STATE_NOT_FINITE` (an entry is not finite), :data:`STATE_VELOCITY` (some |q̇_i| > ``max_velocity``),
        :data:`STATE_POSITION` (some |q_i| > ``max_position``), tested in this order, or :data:`STATE_OK` (0).

    Notes
    -----
    C copy: ``step_period.c``'s ``armctl_state_check`` (the generated engine's); tests/sim/test_period.py fails
    when they disagree.
    """
    ql, vl = q.tolist(), qd.tolist()
    if not math.isfinite(sum(ql) + sum(vl)) and not (np.isfinite(q).all() and np.isfinite(qd).all()):
        return STATE_NOT_FINITE  # (the sum of finite entries can overflow: the entries decide)
    if max(vl) > max_velocity or -min(vl) > max_velocity:
        return STATE_VELOCITY
    if max_position < math.inf and (max(ql) > max_position or -min(ql) > max_position):
        return STATE_POSITION
    return STATE_OK


@dataclass(frozen=True)
class EngineRun:
    """What an engine is bound to: the run's record and how a control period is integrated.

    Parameters
    ----------
    record : Recorder
        The run's record; its row 0 holds the initial state (q₀, q̇₀).
    saturation : Saturation
        How τ_k is held (:mod:`armctl.sim.saturation`), writing ``record.tau_applied``.
    substeps : int
        Integration steps m per control period.
    dt : float
        The integration step h = Δt_c / m [s].
    accel_at_start : bool
        q̈_k by an evaluation at t_k (the implicit schemes, whose step gives none at its start).
    max_velocity, max_position : float
        The run's stop rules [rad/s, rad] (:func:`state_code`).
    sensors_read : bool
        The controller reads the first force sensor at every sample (:meth:`Engine.observe` must record it).
    """

    record: Recorder
    saturation: Saturation
    substeps: int
    dt: float
    accel_at_start: bool
    max_velocity: float = math.inf
    max_position: float = math.inf
    sensors_read: bool = False


class Engine(Protocol):
    """What advances the plant of a run (see the module)."""

    #: whether :meth:`observe` records anything for the run it is bound to (False: the loop does not call it)
    observes: bool

    def bind(self, run: EngineRun) -> None:
        """Tie the engine to ``run``'s record, starting from the state in its row 0."""
        ...

    def observe(self, k: int, t: float) -> None:
        """Record what the plant shows at the state of sample k (time t [s]) before the controller is called."""
        ...

    def advance_period(self, k: int, t: float, tau: FloatArray) -> int:
        """Hold ``tau`` (τ_k as the controller gave it, recorded in row k of ``record.tau``) by the run's
        saturation, record the plant's side of sample k (time t [s]) and integrate [t, t + Δt_c) under the torque
        held; the state reached goes into row k + 1. Returns :func:`state_code` of that state (0: the run goes on),
        or :data:`TORQUE_NOT_FINITE` (nothing held or advanced)."""
        ...

    def last_sample(self, k: int, t: float, tau: FloatArray) -> int:
        """Hold ``tau`` and record the plant's side of the run's last sample k under it (no step after it).
        Returns 0, or :data:`TORQUE_NOT_FINITE`."""
        ...

    def info(self) -> dict[str, Any]:
        """What the run's ``info`` says of the engine and the plant it integrated (after the run)."""
        ...
