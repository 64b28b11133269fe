"""One integration step with stick–slip events.

Within a step the stuck set and the sliding directions are fixed, so the right-hand side is smooth and the
integrator keeps its order. A sliding joint whose velocity reaches zero during the step is an *event*: the step
is cut at the crossing (located by linear interpolation of the velocity), the joint's velocity is set to exactly
zero — the kinetic energy this removes, ½q̇ᵀMq̇ before minus after, is booked as friction work — and the rest
of the step starts with a new stick solve, which holds the joint (stick) or releases it the other way (a
reversal). A joint released at rest that does not move in its breakaway direction is held instead and the
step redone.
"""

from __future__ import annotations

import numpy as np

from armctl._checks import BoolArray, FloatArray
from armctl.sim.integrators import Step
from armctl.sim.plant import Plant


def advance(
    plant: Plant, step: Step, t: float, q: FloatArray, v: FloatArray, tau: FloatArray, h: float, begun: bool = False
) -> tuple[FloatArray, FloatArray, FloatArray | None, float, float]:
    """Integrate from (t, q, q̇) over h under τ; returns (q₁, q̇₁, a at the start or None, W_f, W_e).
    ``begun``: :meth:`Plant.begin` was already called for this state. A plant with a disturbance samples it
    for the step (:meth:`Plant.sample_disturbance`). (C copy: ``step_events.c``'s ``armctl_advance``;
    tests/sim/test_compiled_plant.py fails when they disagree.)"""
    if plant.disturbance is None:
        if plant.sticky is None:  # no events to find (or the step finds them itself: the generated step)
            return step(t, q, v, tau, h)
        return _advance(plant, step, t, q, v, tau, h, begun)
    plant.sample_disturbance(t, h)
    try:
        return _advance(plant, step, t, q, v, tau, h, begun)
    finally:
        plant.end_step()


def _advance(
    plant: Plant, step: Step, t: float, q: FloatArray, v: FloatArray, tau: FloatArray, h: float, begun: bool
) -> tuple[FloatArray, FloatArray, FloatArray | None, float, float]:
    if plant.sticky is None:
        return step(t, q, v, tau, h)
    wf = we = 0.0
    a_first: FloatArray | None = None
    at_start = True
    remaining = h
    held: BoolArray | None = None
    budget = 4 * plant.n + 8
    for attempt in range(budget + 1):
        if not begun:
            plant.begin(t, q, v, tau, held)
        begun = False
        if plant.all_stuck:  # nothing moves: q̈ = 0, no power
            if at_start:
                a_first = np.zeros(plant.n)
            return q, v, a_first, wf, we
        q1, v1, a0, dwf, dwe = step(t, q, v, tau, remaining)
        cross = plant.crossings(v1)
        if cross is None or attempt == budget:
            if at_start:
                a_first = a0
            if cross is not None:  # too many events in one step: stop the crossing joints where they are
                plant.stats["event_overflow"] = plant.stats.get("event_overflow", 0) + 1
                before = plant.kinetic(q1, v1)
                v1 = np.where(cross, 0.0, v1)
                dwf += plant.kinetic(q1, v1) - before
            return q1, v1, a_first, wf + dwf, we + dwe
        resting = cross & (v == 0.0)
        if resting.any():  # released but did not move its way: hold it and redo the step
            held = resting if held is None else (held | resting)
            continue
        d0 = (plant.direction * v)[cross]
        d1 = (plant.direction * v1)[cross]
        frac = d0 / (d0 - d1)
        s = float(np.min(frac))
        if s < 1.0 - 1e-12:
            q1, v1, a0, dwf, dwe = step(t, q, v, tau, s * remaining)
        if at_start:
            a_first = a0
        at_start = False
        wf += dwf
        we += dwe
        # zero the joint that reached zero velocity first (and any that crossed in the shortened step)
        zero = (plant.direction != 0.0) & (plant.direction * v1 <= 0.0)
        zero[np.flatnonzero(cross)[int(np.argmin(frac))]] = True
        before = plant.kinetic(q1, v1)
        v1 = np.where(zero, 0.0, v1)
        wf += plant.kinetic(q1, v1) - before
        plant.stats["stick_events"] += int(zero.sum())
        t += s * remaining
        remaining -= s * remaining
        q, v, held = q1, v1, None
        if remaining <= 1e-14 * h:
            break
    return q, v, a_first, wf, we
