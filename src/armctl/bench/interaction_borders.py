"""Where interaction control fails, predicted and then simulated: the Panda presses on a compliant table (a
Kelvin–Voigt plane at the tool's height, or just above it for force control, :data:`PRELOAD`), with a force/torque
sensor at the tool in world axes and one control period of measurement delay at 1 kHz.

* Force control (:class:`~armctl.controllers.ForceControl`, proportional, inner computed torque): the critical
  force gain K_F* against the table's stiffness k_e, predicted by the sampled-data model of
  :mod:`armctl.tuning.force_stability` and found in closed loop by bisection over K_F.
* Cartesian impedance (:class:`~armctl.controllers.CartesianImpedance`, default critical damping): the table
  stiffness k_e*(k_d) where the contact starts to chatter, predicted by :mod:`armctl.tuning.impedance_stability`
  from the controller's own Λ(q), K and D at the pose (:func:`~armctl.tuning.impedance_model`), found in closed
  loop by bisection over k_e, and a grid of impedance and table stiffnesses around it.

A run is ``"stable"`` when, after the first 0.3 s, the tool never leaves the table and the normal force's
oscillation shrinks from the first half of the rest of the run to the second; ``"chatter"`` when the contact is
lost (the oscillation grew until the force hit zero) or the oscillation does not shrink; ``"diverged"`` when the
simulator stopped the run.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

import armctl
from armctl.tuning.force_stability import critical_force_gain, normal_inertia
from armctl.tuning.impedance_stability import critical_environment_stiffness, impedance_model

Q_READY = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
PERIOD = 1e-3
DELAY = 1
#: the inner motion loop of force control [1/s², 1/s] and the force wanted [N]
INNER_KP, INNER_KD, FORCE = 400.0, 40.0, 10.0
SETTLE = 0.3
#: the force-control runs start pressing with 9 N of the 10 wanted: a 1 N step excites the loop while the motion
#: stays small (the model is linear about the pose; at the critical gain on a soft table a 10 N error would command
#: a motion of decimetres, and the torque would saturate)
PRELOAD = 9.0


def _setup() -> tuple[armctl.RobotModel, armctl.Dynamics, float, float]:
    model = armctl.models.panda()
    dyn = armctl.Dynamics(model)
    return model, dyn, float(dyn.frame_pose(Q_READY)[2, 3]), normal_inertia(dyn, Q_READY)


def press(
    controller: Any, stiffness: float, duration: float = 1.0, dt: float | None = None, preload: float = 0.0
) -> Any:
    """The Panda at its ready pose on a table of ``stiffness`` [N/m] under ``controller``: the table at the tool's
    height, or ``preload``/k_e above it (the tool starts pressing with ``preload`` newtons)."""
    from armctl.sim import Forces, ForceSensor, KelvinVoigt, Plane, Sensing, simulate

    model, _, z, _ = _setup()
    table = Plane(KelvinVoigt(stiffness, 0.0), point=(0.0, 0.0, z + preload / stiffness))
    sensing = Sensing(sensors=ForceSensor(world_axes=True), delay=DELAY)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # saturation and energy warnings of runs that chatter: the outcome says it
        ref = armctl.Reference(Q_READY)
        return simulate(
            model, controller, ref, duration, q0=Q_READY, dt=dt, forces=Forces(environment=table), sensing=sensing
        )


def outcome(res: Any) -> str:
    """``"stable"``, ``"chatter"`` or ``"diverged"`` (see the module)."""
    if res.diverged:
        return "diverged"
    f = res.contact_force_on_robot[:, 0, 2]
    after = res.t >= SETTLE
    if (f[after] <= 0.0).any():
        return "chatter"
    half = SETTLE + 0.5 * (res.t[-1] - SETTLE)
    early, late = f[after & (res.t < half)], f[res.t >= half]
    return "stable" if late.std() < early.std() or late.std() < 1e-6 * FORCE else "chatter"


def force_control(force_gain: float) -> Any:
    """Proportional force control along z, pressing FORCE newtons down, inner computed torque."""
    from armctl.controllers import ForceControl

    return ForceControl(armctl.Dynamics(armctl.models.panda()), [0.0, 0.0, -FORCE], force_gain,
                        directions=[0.0, 0.0, 1.0], kp=INNER_KP, kd=INNER_KD)  # fmt: skip


def predicted_force_gain(stiffness: float) -> float:
    """K_F* [m/N] of the sampled-data model for the Panda's inertia along z at its ready pose."""
    lam = _setup()[3]
    return critical_force_gain(stiffness, kp=INNER_KP, kd=INNER_KD, inertia=lam, period=PERIOD, delay=DELAY)


def border(outcome_at: Callable[[float], str], guess: float, steps: int = 7) -> dict[str, Any]:
    """The value x where ``outcome_at(x)`` turns from "stable" to anything else, by bisection on log x between
    ``guess``/2 and 2·``guess`` (widened if both ends agree); the runs' (x, outcome) are kept."""
    runs: list[tuple[float, str]] = []

    def stable(x: float) -> bool:
        o = outcome_at(x)
        runs.append((x, o))
        return o == "stable"

    lo, hi = 0.5 * guess, 2.0 * guess
    while not stable(lo):
        lo, hi = 0.5 * lo, lo
    while stable(hi):
        lo, hi = hi, 2.0 * hi
    for _ in range(steps):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return {"border": math.sqrt(lo * hi), "bracket": [lo, hi], "runs": runs}


def simulated_force_gain(stiffness: float, guess: float, steps: int = 7, duration: float = 1.0) -> dict[str, Any]:
    """The force gain where the closed loop on a table of ``stiffness`` [N/m] turns from stable to chatter
    (:func:`border` from ``guess``)."""
    return border(lambda k: outcome(press(force_control(k), stiffness, duration, preload=PRELOAD)), guess, steps)


def force_border(quick: bool = False) -> dict[str, Any]:
    """Predicted and simulated K_F* over a range of table stiffnesses."""
    stiffnesses = [3e3, 3e4, 3e5] if quick else [1e3, 3e3, 1e4, 3e4, 1e5, 3e5]
    rows = []
    for k_e in stiffnesses:
        pred = predicted_force_gain(k_e)
        sim = simulated_force_gain(k_e, pred, steps=5 if quick else 7)
        rows.append({"stiffness": k_e, "predicted": pred, **sim, "ratio": sim["border"] / pred})
    return {"rows": rows, "kp": INNER_KP, "kd": INNER_KD, "period": PERIOD, "delay": DELAY, "inertia": _setup()[3]}


def impedance(k_d: float) -> Any:
    """Cartesian impedance of translational stiffness ``k_d`` [N/m] (rotation 50 N·m/rad), its target 5 mm below
    the table, default (critical) damping."""
    from armctl.controllers import CartesianImpedance

    dyn = armctl.Dynamics(armctl.models.panda())
    c = CartesianImpedance(dyn, [k_d, k_d, k_d, 50.0, 50.0, 50.0], nullspace_stiffness=5.0, posture=Q_READY)
    target = dyn.frame_pose(Q_READY)
    target[2, 3] -= 0.005
    c.set_target(target)
    return c


def predicted_environment_stiffness(k_d: float) -> float:
    """k_e* [N/m] of the sampled-data model for :func:`impedance` (its Λ, K and D at the ready pose)."""
    model = impedance_model(impedance(k_d), Q_READY)
    return critical_environment_stiffness(period=PERIOD, delay=DELAY, **model)


def impedance_outcome(k_d: float, stiffness: float, duration: float = 1.0) -> str:
    """:func:`outcome` of :func:`impedance` pressing on a table of ``stiffness`` [N/m], the simulator's step short
    enough for the contact mode (RK4 well inside its accuracy)."""
    dt = min(PERIOD, 0.3 / math.sqrt(stiffness / _setup()[3]))
    return outcome(press(impedance(k_d), stiffness, duration, dt=PERIOD / math.ceil(PERIOD / dt)))


def simulated_environment_stiffness(k_d: float, guess: float, steps: int = 7, duration: float = 1.0) -> dict[str, Any]:
    """The table stiffness where impedance of stiffness ``k_d`` turns from stable to chatter (:func:`border` from
    ``guess``)."""
    return border(lambda k_e: impedance_outcome(k_d, k_e, duration), guess, steps)


def impedance_map(quick: bool = False) -> dict[str, Any]:
    """The predicted and simulated border k_e*(k_d) of impedance pressing on a table, and the outcomes on a grid of
    table stiffnesses around the prediction."""
    k_ds = [300.0, 3000.0] if quick else [100.0, 300.0, 1000.0, 3000.0]
    border = [predicted_environment_stiffness(k) for k in k_ds]
    factors = [0.7, 1.4] if quick else [0.5, 0.7, 0.85, 1.15, 1.4, 2.0]
    cells, rows = [], []
    for k_d, k_star in zip(k_ds, border, strict=True):
        sim = simulated_environment_stiffness(k_d, k_star, steps=5 if quick else 7, duration=0.6 if quick else 1.0)
        rows.append({"k_d": k_d, "predicted": k_star, **sim, "ratio": sim["border"] / k_star})
        for f in factors:
            k_e = f * k_star
            cells.append({"k_d": k_d, "stiffness": k_e, "factor": f,
                          "outcome": impedance_outcome(k_d, k_e, 0.6 if quick else 1.0)})  # fmt: skip
    return {"k_d": k_ds, "predicted": border, "rows": rows, "cells": cells}
