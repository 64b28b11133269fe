"""Closed-loop simulation: ``armctl.sim.simulate(plant, controller, reference, duration, ...)``.

The plant is the truth (friction with real stiction, contact environments, disturbances, payload); the
controller runs at its own rate with a zero-order hold. :func:`~armctl.simulate` returns a
:class:`~armctl.SimResult` (its samples, status, limit report, plots and a 3D :func:`playback`); the plant's
parts are :class:`StickSlip` and :class:`SmoothFriction`, contact :class:`Plane` environments with a
:class:`KelvinVoigt` or :class:`HuntCrossley` normal force and a :class:`ForceSensor`; the options come in groups
(:class:`Forces`, :class:`Sensing`, :class:`StopRules`); :func:`sweep` runs many cases through an Executor
(:class:`SweepResult`); :class:`MujocoPlant` hands the plant to MuJoCo (``engine="mujoco"``). Whether a run
tracked what was asked is judged on :class:`ErrorSummary` values within :data:`TRACKING_TOLERANCE`.
"""

# The modules, for a reader of the source: ``simulate`` (the loop; ``setup`` checks its arguments, ``recorder``
# keeps the samples), ``plant`` (the equations of motion), ``integrators`` and ``implicit`` (the schemes),
# ``stepper`` (a step with stick–slip events), ``compiled`` (the choice of the generated step: ``compiled_plant``,
# ``generated_plant``, ``plant_layout``, the C driver ``step_*.c``), ``friction`` and ``stick_slip``, ``contact``
# and ``normal_force``, ``result`` (with ``sampled_reference``, ``limits`` and ``tracking``; its readers ``plot``,
# ``tables`` and ``playback`` (``visuals``: the arm's shapes; ``playback_page``: the page) read a run through
# ``run_record`` and sit below it), ``sweep`` (``sweep_result`` with ``sweep_store`` and ``sweep_table``,
# ``case_failure`` and ``case_settings`` below them, ``sweep_pool``, ``sweep_progress``); ``mujoco_engine`` and
# ``mujoco_plant``: the same loop on a MuJoCo plant.

from armctl.sim.case_failure import CaseFailure
from armctl.sim.contact import ContactPoint, Environment, ForceSensor, Plane
from armctl.sim.friction import FrictionModel, SmoothFriction, StickSlip
from armctl.sim.integrators import INTEGRATORS
from armctl.sim.limits import LimitReport
from armctl.sim.mujoco_plant import MujocoPlant
from armctl.sim.normal_force import HuntCrossley, KelvinVoigt, NormalForce
from armctl.sim.options import Forces, Sensing, StopRules
from armctl.sim.playback import playback
from armctl.sim.result import SimResult
from armctl.sim.simulate import simulate
from armctl.sim.sweep import sweep
from armctl.sim.sweep_result import SweepResult
from armctl.sim.tracking import TRACKING_TOLERANCE, ErrorSummary

__all__ = [
    "INTEGRATORS",
    "TRACKING_TOLERANCE",
    "CaseFailure",
    "ContactPoint",
    "Environment",
    "ErrorSummary",
    "ForceSensor",
    "Forces",
    "FrictionModel",
    "HuntCrossley",
    "KelvinVoigt",
    "LimitReport",
    "MujocoPlant",
    "NormalForce",
    "Plane",
    "Sensing",
    "SimResult",
    "SmoothFriction",
    "StickSlip",
    "StopRules",
    "SweepResult",
    "playback",
    "simulate",
    "sweep",
]
