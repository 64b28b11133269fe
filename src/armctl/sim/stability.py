"""Will an explicit scheme integrate this contact stably? A check made once, before the run.

A point pressed into a compliant plane moves, along the normal, as a damped oscillator

    m_eff ẍ + c ẋ + k x = 0,     m_eff = 1 / (nᵀ J_p M(q)⁻¹ J_pᵀ n)

(m_eff: the arm's effective mass at the point along the normal n, J_p the point's velocity Jacobian). One step
h of an integrator maps (x, ẋ) linearly, and the run is stable only if that map's spectral radius ρ ≤ 1:

* ``"rk4"``: ρ of R(hA) = I + hA + (hA)²/2 + (hA)³/6 + (hA)⁴/24, A = [[0, 1], [−k/m, −c/m]]; undamped, stable
  for ω h ≤ 2√2 (ω = √(k/m_eff));
* ``"euler"``: ẋ₁ = ẋ + h ẍ(x, ẋ), x₁ = x + h ẋ₁; undamped, ω h < 2;
* ``"semi-implicit-euler"``: the contact's damping implicit, its stiffness explicit (ẋ₁ = ẋ + h ẍ(x, ẋ₁)):
  also ω h < 2 undamped, damping no longer limits the step;
* ``"implicit-euler"``: stable for every step (it is not checked).

Beyond the limit an impact throws the arm off with energy the contact never had (a 10 N push into a 1e9 N/m
wall reached 700 J), and nothing in the states themselves need be non-finite. The check uses M at the initial
configuration and the law's stiffness at first touch (Hunt–Crossley: k for p = 1; for p > 1 the stiffness grows
with depth and this check is skipped); it finds the usual cause of a run that goes wrong, not every one.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from armctl._checks import FloatArray
from armctl.dynamics.base import Dynamics
from armctl.sim.contact import Environment, Plane
from armctl.sim.normal_force import HuntCrossley, KelvinVoigt


@dataclass(frozen=True)
class ContactStability:
    """The linear stability of one contact point under one integrator: ``omega_h`` = ω h, ``radius`` ρ of the
    one-step map, ``max_dt`` the largest stable step [s] for this integrator (by bisection on ρ)."""

    environment: int
    point: int
    omega_h: float
    radius: float
    max_dt: float

    @property
    def stable(self) -> bool:
        return self.radius <= 1.0 + 1e-12


def _step_matrix(scheme: str, w2: float, c: float, h: float) -> FloatArray:
    """One step of ``scheme`` on ẍ = −w2 x − c ẋ, as a map of (x, ẋ)."""
    if scheme == "rk4":
        a = h * np.array([[0.0, 1.0], [-w2, -c]])
        return np.eye(2) + a + a @ a / 2 + a @ a @ a / 6 + a @ a @ a @ a / 24
    if scheme == "euler":  # v₁ = v + h(−w2 x − c v), x₁ = x + h v₁
        v1 = np.array([-h * w2, 1.0 - h * c])
        return np.array([[1.0, 0.0], [0.0, 0.0]]) + np.outer([h, 1.0], v1)
    # semi-implicit-euler: v₁ = (v − h w2 x) / (1 + h c), x₁ = x + h v₁
    v1 = np.array([-h * w2, 1.0]) / (1.0 + h * c)
    return np.array([[1.0, 0.0], [0.0, 0.0]]) + np.outer([h, 1.0], v1)


def _radius(scheme: str, w2: float, c: float, h: float) -> float:
    return float(np.abs(np.linalg.eigvals(_step_matrix(scheme, w2, c, h))).max())


def _max_step(scheme: str, w2: float, c: float, h: float) -> float:
    """The largest step with ρ ≤ 1 (the stable steps of these schemes form an interval from 0)."""
    hi = h
    while _radius(scheme, w2, c, hi) <= 1.0 + 1e-12:
        hi *= 2.0
        if hi > 1e6 * h:  # stable for any step we would take
            return math.inf
    lo = 0.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _radius(scheme, w2, c, mid) <= 1.0 + 1e-12 else (lo, mid)
    return lo


def checkable(env: Environment) -> bool:
    """True if :func:`contact_stability` can judge ``env``: a plane with a linear normal law (Kelvin–Voigt,
    or Hunt–Crossley with exponent 1)."""
    law = getattr(env, "law", None)
    return isinstance(env, Plane) and (isinstance(law, KelvinVoigt)
                                       or (isinstance(law, HuntCrossley) and law.exponent == 1.0))


def contact_stability(dyn: Dynamics, environments: Sequence[Environment], q: FloatArray, scheme: str, h: float
                      ) -> list[ContactStability]:
    """The stability of every contact point of the planes in ``environments`` at configuration ``q`` for
    integrator ``scheme`` and step ``h`` [s] (empty for ``"implicit-euler"`` and for laws it cannot judge)."""
    if scheme == "implicit-euler":
        return []
    out = []
    minv = None
    for e, env in enumerate(environments):
        if not checkable(env):
            continue
        law = env.law  # type: ignore[attr-defined]
        damping = law.damping if isinstance(law, KelvinVoigt) else 0.0  # Hunt–Crossley's vanishes at first touch
        if minv is None:
            minv = np.linalg.inv(dyn.mass_matrix(q))
        for p, (_, jp) in enumerate(env.kinematics(dyn)(q)):
            jn = env.normal @ jp
            inv_mass = float(jn @ minv @ jn)
            if inv_mass <= 0.0:  # the arm cannot move the point along the normal here
                continue
            w2, c = law.stiffness * inv_mass, damping * inv_mass
            out.append(ContactStability(e, p, math.sqrt(w2) * h, _radius(scheme, w2, c, h),
                                        _max_step(scheme, w2, c, h)))
    return out
