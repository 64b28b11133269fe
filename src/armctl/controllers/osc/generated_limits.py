"""The bounds of the built-in limits as CasADi expressions of (q, q̇), for generated code
(:mod:`~armctl.controllers.osc.generated_cascade`): what each limit's ``bounds`` computes in NumPy, with the
limit's settings as parameters (:func:`limit_params`, in the order of :func:`limit_bounds`).

* A constant limit (:class:`~armctl.controllers.osc.TorqueLimit`,
  :class:`~armctl.controllers.osc.AccelerationLimit`): its bounds, as parameters.
* :class:`~armctl.controllers.osc.JointVelocityLimit`: (−q̇_max − q̇)/Δt ≤ q̈ ≤ (q̇_max − q̇)/Δt, the upper bound
  raised to at least −a_max and the lower one lowered to at most a_max.
* :class:`~armctl.controllers.osc.JointPositionLimit`: both sides as upper bounds with the gap g = [q_max − q;
  q − q_min] and the velocity towards the limit v = [q̇; −q̇]: the position bound 2(g − Δt v)/Δt², the
  discriminant d = a²Δt² + 8a g − 4aΔt v and the viability bound −v/Δt − a/2 + √max(d, 0)/(2Δt) (a = (1 − ρ)
  a_max), in the affine form the limit evaluates them in; the bound is the viability bound (−a_max where d < 0),
  capped by the position bound and raised to at least −a_max.

The expressions round as the NumPy forms do, up to the order of a product's two terms (a few units in the last
place of the position bound, ~1e-9 rad/s² at Δt = 1 ms).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import cast

import casadi as cs
import numpy as np

from armctl._checks import FloatArray
from armctl.controllers.osc.limits.base import Limit
from armctl.controllers.osc.limits.position import JointPositionLimit
from armctl.controllers.osc.limits.velocity import JointVelocityLimit
from armctl.controllers.osc.state import ModelState


def supported_limits(limits: Sequence[Limit]) -> bool:
    """Whether :func:`limit_bounds` takes every limit: constant ones, and the joint position and velocity limits
    themselves (not subclasses)."""
    return all(lim.constant or type(lim) in (JointPositionLimit, JointVelocityLimit) for lim in limits)


def limit_tag(limits: Sequence[Limit]) -> str:
    """The structure of :func:`limit_bounds` for ``limits`` (part of a generated library's key)."""
    return ",".join("const" if lim.constant else type(lim).__name__ for lim in limits)


def _position_coefficients(lim: JointPositionLimit) -> list[FloatArray]:
    """Per side (2n rows, the upper limits first): the coefficients of q and q̇ and the offset of the position
    bound, the discriminant and the viability bound without its root, computed as the limit's affine form is;
    then −a_max and 1/(2Δt)."""
    dt = lim.dt
    n = lim.upper.shape[0]
    a_full = np.concatenate([lim.max_deceleration] * 2)
    a = (1.0 - lim.reserve) * a_full
    s = np.concatenate((-np.ones(n), np.ones(n)))  # g = gap0 + s q, v = −s q̇
    gap0 = np.concatenate((lim.upper, -lim.lower))
    return [
        2.0 / dt**2 * s,
        -2.0 / dt * -s,
        2.0 / dt**2 * gap0,
        8.0 * a * s,
        -4.0 * dt * a * -s,
        (a * dt) ** 2 + 8.0 * a * gap0,
        s / dt,  # −v/Δt = s q̇/Δt
        -0.5 * a,
        -a_full,
        np.full(2 * n, 0.5 / dt),
    ]


def limit_params(limits: Sequence[Limit]) -> FloatArray:
    """The parameters of :func:`limit_bounds` for ``limits`` (bound to the model), in its order."""
    parts: list[FloatArray] = []
    for lim in limits:
        if lim.constant:
            parts += list(lim.bounds(cast(ModelState, None)))  # a constant limit reads no state
        elif type(lim) is JointVelocityLimit:
            parts += [lim.limit, lim.max_deceleration, np.array([1.0 / lim.dt])]
        else:
            assert type(lim) is JointPositionLimit  # supported_limits
            parts += _position_coefficients(lim)
    return np.concatenate(parts) if parts else np.zeros(0)


def limit_bounds(limits: Sequence[Limit], n: int, q: cs.SX, qd: cs.SX) -> tuple[cs.SX, cs.SX, cs.SX]:
    """(l, u, p): the limits' bounds, their blocks stacked in order, as expressions of q, q̇ and the parameters p
    (:func:`limit_params`)."""
    lows: list[cs.SX] = []
    ups: list[cs.SX] = []
    params: list[cs.SX] = []
    for k, lim in enumerate(limits):
        if lim.constant:
            lo, up = cs.SX.sym(f"lower{k}", n), cs.SX.sym(f"upper{k}", n)
            params += [lo, up]
        elif type(lim) is JointVelocityLimit:
            vmax, amax, inv = cs.SX.sym(f"vmax{k}", n), cs.SX.sym(f"amax{k}", n), cs.SX.sym(f"inv_dt{k}")
            params += [vmax, amax, inv]
            up = cs.fmax((vmax - qd) * inv, -amax)
            lo = cs.fmin((-vmax - qd) * inv, amax)
        else:
            names = ("pos_q", "pos_v", "pos_0", "disc_q", "disc_v", "disc_0", "via_v", "via_0", "neg_a", "root")
            c = [cs.SX.sym(f"{name}{k}", 2 * n) for name in names]
            params += c
            qq, vv = cs.vertcat(q, q), cs.vertcat(qd, qd)
            pos = c[0] * qq + c[1] * vv + c[2]
            disc = c[3] * qq + c[4] * vv + c[5]
            via = c[6] * vv + c[7] + c[9] * cs.sqrt(cs.fmax(disc, 0.0))
            bound = cs.fmax(cs.fmin(cs.if_else(disc < 0.0, c[8], via), pos), c[8])
            lo, up = -bound[n:], bound[:n]
        lows.append(lo)
        ups.append(up)
    return cs.vertcat(*lows), cs.vertcat(*ups), cs.vertcat(*params)
