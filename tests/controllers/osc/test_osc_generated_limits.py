"""The built-in limits' bounds as CasADi expressions (for generated code) against the limits' own NumPy bounds,
at states that reach every branch: joints near, at and beyond their position limits, fast towards them and away,
so that the viability bound, the a_max floor and a negative discriminant each decide some rows (the position
bound never does by more than a rounding: under a_max > 0 the viability bound implies it)."""

from __future__ import annotations

from typing import cast

import casadi as cs
import numpy as np

import armctl
from armctl.controllers.osc import (
    AccelerationLimit,
    JointPositionLimit,
    JointVelocityLimit,
    TorqueLimit,
)
from armctl.controllers.osc.generated_limits import limit_bounds, limit_params, supported_limits
from armctl.controllers.osc.state import ModelEvaluator, ModelState


def _states(model: armctl.RobotModel, count: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(seed)
    lo, up = model.lower, model.upper
    out = []
    for _ in range(count):
        side = rng.random(model.n) < 0.5
        near = np.where(side, up, lo) + rng.normal(0.0, 0.01, model.n)  # within and beyond the limits
        mid = rng.uniform(lo, up)
        q = np.where(rng.random(model.n) < 0.7, near, mid)
        qd = rng.normal(0.0, 1.5, model.n)
        at = rng.random(model.n) < 0.2  # a hair inside the upper limit, at rest: the position bound binds
        q[at], qd[at] = up[at] - 0.01 - 1e-7, rng.normal(0.0, 1e-5, int(at.sum()))
        out.append((q, qd))
    return out


def test_the_expressions_give_the_limits_bounds_at_states_that_reach_every_branch() -> None:
    """Within 1e-12 relative (a few units in the last place of the position bound's terms), and every branch of
    the first position limit's upper bound decides at least one row over the states."""
    model = armctl.models.panda()
    limits = [
        TorqueLimit(),
        JointPositionLimit(dt=1e-3, max_deceleration=10.0, margin=0.01),
        JointVelocityLimit(dt=1e-3),
        AccelerationLimit(50.0),
        JointPositionLimit(dt=2e-3, max_deceleration=[5, 6, 7, 8, 9, 10, 11], reserve=0.2),
    ]
    for lim in limits:
        lim.bind(model)
    assert supported_limits(limits)
    n = model.n
    q, qd = cs.SX.sym("q", n), cs.SX.sym("qd", n)
    lo, up, p = limit_bounds(limits, n, q, qd)
    fn = cs.Function("bounds", [q, qd, p], [lo, up])
    params = limit_params(limits)
    branches: set[str] = set()
    pos = limits[1]
    assert isinstance(pos, JointPositionLimit)
    for qv, qdv in _states(model, 200, seed=3):
        state = ModelState(cast(ModelEvaluator, None), qv, qdv, np.eye(n), np.zeros(n), None)  # the limits read q, q̇
        want = [lim.bounds(state) for lim in limits]
        got_lo, got_up = (np.asarray(v).ravel() for v in fn(qv, qdv, params))
        np.testing.assert_allclose(got_lo, np.concatenate([w[0] for w in want]), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(got_up, np.concatenate([w[1] for w in want]), rtol=1e-12, atol=1e-12)
        # which branch decided joint by joint, upper side of the first position limit (recomputed from its docs)
        a, dt = (1.0 - pos.reserve) * pos.max_deceleration, pos.dt
        gap, v = pos.upper - qv, qdv
        position = 2.0 * (gap - dt * v) / dt**2
        disc = a**2 * dt**2 + 8.0 * a * gap - 4.0 * a * dt * v
        via = (-(2.0 * dt * v + a * dt**2) + dt * np.sqrt(np.maximum(disc, 0.0))) / (2.0 * dt**2)
        for j in range(n):
            assert disc[j] < 0.0 or via[j] <= position[j] * (1.0 + 1e-9) + 1e-9
            if disc[j] < 0.0:
                branches.add("no stopping")
            elif via[j] < -pos.max_deceleration[j]:
                branches.add("floor")
            else:
                branches.add("viability")
    assert branches == {"no stopping", "viability", "floor"}
