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
wall reached 700 J), and nothing in the states themselves need be non-finite.

The linear map is that of a two-sided spring; a contact is one-sided: it closes and opens, and every switch
re-enters the scheme's discrete dynamics at whatever phase the step happens to have. Below the linear limit
that can still pump energy in, impact after impact (the Euler variants map the true energy's ellipse onto a
tilted one, ever more elongated as ω h → 2; RK4's stages straddle the switch). :func:`impact_gain` measures
it: the same oscillator as a one-sided contact, a unit push into the wall from rest at 21 gaps (0 and 1e-3 …
1e3 static deflections), 3000 steps of the scheme itself, and the largest energy any of them reaches above
what it started with, relative to that plus the static spring energy (the exact motion keeps it, or loses it
to damping). Undamped, the Euler variants' gain is 0.12 at ω h = 0.2 and 0.39 at 0.4, and above that erratic
— the map is chaotic there: between 0.45 and 2 within ±0.5 % of ω h, hundreds by ω h = 1; RK4's is 0.08 at
1.0 and erratic near 2 (0.4 to 1.7), 127 at 2.3 (linear limit 2√2). So the verdict does not rest on one
evaluation: a contact is stable if ρ ≤ 1 and ω h ≤ :data:`SAFE_OMEGA_H` of the scheme, the largest ω h up to
which the impact model passes at every step sampled, for damping ratios 0 to 2. That is conservative for a
well-damped contact (Euler at ζ = 0.3 passes up to ω h ≈ 1.1) and keeps the check free of the model's cost.

The check uses M at the initial configuration and the law's stiffness at first touch (Hunt–Crossley: k for
p = 1; for p > 1 the stiffness grows with depth and this check is skipped); it finds the usual cause of a run
that goes wrong, not every one.
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

#: ω h below which :func:`impact_gain` is not integrated (the gain stays below a quarter there)
IMPACT_CHECK_FROM = 0.25
#: ω h up to which the one-sided impact model's gain stays at most 1 at every step sampled (0.001 apart for
#: the Euler variants, 0.004 for RK4, damping ratios 0 … 2 in steps of 0.05) where the linear check passes
SAFE_OMEGA_H = {"rk4": 1.9, "euler": 0.4, "semi-implicit-euler": 0.4}


@dataclass(frozen=True)
class ContactStability:
    """The stability of one contact point under one integrator at step h: ``omega_h`` = ω h, ``radius`` ρ of
    the linear one-step map, ``linear_dt`` the largest step with ρ ≤ 1 [s] (by bisection on ρ),
    ``one_sided`` the scheme's :data:`SAFE_OMEGA_H`, ``omega`` ω [rad/s]; stable if ρ ≤ 1 and
    ω h ≤ ``one_sided``, and ``max_dt`` [s] the largest step at which both hold."""

    environment: int
    point: int
    omega_h: float
    radius: float
    linear_dt: float
    one_sided: float
    omega: float  # ω [rad/s]

    @property
    def stable(self) -> bool:
        return self.radius <= 1.0 + 1e-12 and self.omega_h <= self.one_sided

    @property
    def max_dt(self) -> float:
        return min(self.linear_dt * (1.0 - 1e-9), self.one_sided / self.omega if self.omega > 0 else math.inf)


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


def impact_gain(scheme: str, omega_h: float, damping_h: float) -> float:
    """The one-sided impact model's largest relative energy gain (see the module; the analysis behind
    :data:`SAFE_OMEGA_H`, not called by the check itself): ẍ = 1 − f(x, ẋ) with the contact force
    f = max(ω² x + c ẋ, 0) for x > 0 (else 0), in units of the step (h = 1), integrated by ``scheme`` from rest
    at 21 gaps for 3000 steps; ``omega_h`` = ω h, ``damping_h`` = c h (c = damping / m_eff). 0.1–0.3 s."""
    if omega_h < IMPACT_CHECK_FROM:
        return 0.0
    wh, ch = float(omega_h), float(damping_h)
    k = wh * wh
    gaps = np.concatenate(([0.0], np.geomspace(1e-3, 1e3, 20))) / k  # in static deflections 1/k
    x, v = -gaps, np.zeros_like(gaps)
    e0 = gaps  # the push's work to the surface: the energy ½ẋ² − x (+ ½k x² inside) the exact motion keeps
    emax = e0.copy()

    def accel(x: FloatArray, v: FloatArray) -> FloatArray:
        return 1.0 - np.where(x > 0.0, np.maximum(k * x + ch * v, 0.0), 0.0)

    with np.errstate(all="ignore"):
        for _ in range(3000):
            if scheme == "rk4":
                a1 = accel(x, v)
                a2 = accel(x + 0.5 * v, v + 0.5 * a1)
                a3 = accel(x + 0.5 * v + 0.25 * a1, v + 0.5 * a2)
                a4 = accel(x + v + 0.5 * a2, v + a3)
                x, v = x + v + (a1 + a2 + a3) / 6.0, v + (a1 + 2.0 * a2 + 2.0 * a3 + a4) / 6.0
            elif scheme == "euler":
                v = v + accel(x, v)
                x = x + v
            else:  # semi-implicit-euler: the contact's damping at the new velocity
                v_in = (v + 1.0 - k * x) / (1.0 + ch)
                pressed = (x > 0.0) & (k * x + ch * v_in >= 0.0)
                v = np.where(pressed, v_in, v + 1.0)
                x = x + v
            e = 0.5 * v * v - x + np.where(x > 0.0, 0.5 * k * x * x, 0.0)
            np.maximum(emax, e, out=emax)
    gain = (emax - e0) / (e0 + 0.5 / k)
    return float(gain.max()) if np.isfinite(gain).all() else math.inf


def checkable(env: Environment) -> bool:
    """True if :func:`contact_stability` can judge ``env``: a plane with a linear normal law (Kelvin–Voigt,
    or Hunt–Crossley with exponent 1)."""
    law = getattr(env, "law", None)
    return isinstance(env, Plane) and (
        isinstance(law, KelvinVoigt) or (isinstance(law, HuntCrossley) and law.exponent == 1.0)
    )


def contact_stability(
    dyn: Dynamics, environments: Sequence[Environment], q: FloatArray, scheme: str, h: float
) -> list[ContactStability]:
    """The stability of every contact point of the planes in ``environments`` at configuration ``q`` for
    integrator ``scheme`` and step ``h`` [s] (empty for ``"implicit-euler"`` and for laws it cannot judge)."""
    if scheme == "implicit-euler":
        return []
    out = []
    minv = None
    for e, env in enumerate(environments):
        if not isinstance(env, Plane) or not checkable(env):
            continue
        law = env.law
        damping = law.damping if isinstance(law, KelvinVoigt) else 0.0  # Hunt–Crossley's vanishes at first touch
        if minv is None:
            minv = np.linalg.inv(dyn.mass_matrix(q))
        for p, (_, jp) in enumerate(env.kinematics(dyn)(q)):
            jn = env.normal @ jp
            inv_mass = float(jn @ minv @ jn)
            if inv_mass <= 0.0:  # the arm cannot move the point along the normal here
                continue
            w2, c = law.stiffness * inv_mass, damping * inv_mass
            omega = math.sqrt(w2)
            out.append(
                ContactStability(
                    e, p, omega * h, _radius(scheme, w2, c, h), _max_step(scheme, w2, c, h), SAFE_OMEGA_H[scheme], omega
                )
            )
    return out
