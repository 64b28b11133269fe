"""Checks made after a run with contact, on what it recorded: did an explicit scheme gain energy that no force
supplied? The check before the run (:mod:`armctl.sim.stability`) judges a contact's normal stiffness and
damping at the initial configuration; these catch what it cannot see:

* **energy balance** — E(t) − E(0) − W(t) (:meth:`~armctl.sim.result.SimResult.energy_balance`) rising above
  :data:`ENERGY_GAIN_TOLERANCE` of the energy exchanged: the scheme made energy (a Hunt–Crossley law that
  stiffens with depth, a configuration where the arm is lighter than at the start, the friction below);
* **the friction's regularisation** — a plane's tangential friction is a viscous law of slope μ f_n / v_slip
  below its slip velocity, which the check before the run cannot know (there is no normal force yet). Along
  the tangent plane the point's velocity then decays at the rate a = μ f_n λ / v_slip (λ: the largest
  eigenvalue of the tangential block of J_p M⁻¹ J_pᵀ), and an explicit scheme keeps it stable only for
  a h ≤ 2 (Euler) or 2.785 (RK4, the real root of |1 − z + z²/2 − z³/6 + z⁴/24| = 1). Beyond that a point
  that slows below v_slip chatters: its friction swings between ±μ f_n instead of holding it (a slider that
  should creep under 10 N of friction felt 50 N, either way). Checked at the sample of the largest normal
  force of each point; "semi-implicit-euler" and "implicit-euler" take this force implicitly.

Each finding is a :class:`~armctl.errors.SimulationWarning` and an entry of ``res.info``.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np

from armctl.dynamics.base import Dynamics
from armctl.errors import SimulationWarning
from armctl.sim.contact import Environment, Plane
from armctl.sim.result import SimResult
from armctl.sim.stability import checkable

#: energy a run may gain that no force supplied, as a share of the largest energy exchanged (a stable run's
#: balance closes to the integrator's order, ~1e-4 and below; an unstable contact's gains tens of percent)
ENERGY_GAIN_TOLERANCE = 0.01
#: the largest a·h at which ẋ = −a x stays stable, per explicit scheme (see the module)
DAMPING_LIMIT = {"euler": 2.0, "rk4": 2.785}


def _scale(res: SimResult) -> float:
    """The largest energy exchanged in the run [J] (at least 1e-12)."""
    return max(float(np.abs(res.energy - res.energy[0]).max()), float(np.abs(res.work_actuator).max()),
               float(np.abs(res.work_friction).max()), float(np.abs(res.work_external).max()), 1e-12)


def check_energy_gain(res: SimResult, scheme: str) -> None:
    """Warn if the arm gained energy that no force supplied; record it in ``res.info["energy_gain"]`` [J]."""
    balance = res.energy_balance()
    if not len(balance):
        return
    scale = _scale(res)
    gain = float(balance.max())
    res.info["energy_gain"] = gain
    if gain > ENERGY_GAIN_TOLERANCE * scale:
        warnings.warn(f"the arm gained {gain:.3g} J that no force supplied ({100 * gain / scale:.0f}% of the "
                      f"energy exchanged; E − E₀ − W in res.energy_balance()): {scheme!r} was likely unstable on a "
                      "contact (e.g. Hunt–Crossley with an exponent above 1 stiffens with depth, which the check "
                      "before the run cannot judge). Past that point the run is not the arm's motion: use "
                      "integrator='implicit-euler' or a smaller dt", SimulationWarning, stacklevel=4)


def check_friction_slope(res: SimResult, dyn: Dynamics, environments: Sequence[Environment], scheme: str,
                         h: float) -> list[dict[str, Any]]:
    """The contact points whose friction regularisation an explicit ``scheme`` cannot integrate at step h
    (see the module), each warned about; returns them for ``res.info["unstable_friction"]``."""
    limit = DAMPING_LIMIT.get(scheme)
    found: list[dict[str, Any]] = []
    if limit is None or not len(res.t):
        return found
    col = 0
    for e, env in enumerate(environments):
        count = len(env.points)
        if isinstance(env, Plane) and env.friction > 0.0:
            normal = env.normal
            tangent = np.eye(3) - np.outer(normal, normal)
            fn_all = -(res.contact_force[:, col:col + count, :] @ normal)  # normal force on the arm (N, P)
            for p in range(count):
                k = int(np.argmax(fn_all[:, p]))
                fn = float(fn_all[k, p])
                if fn <= 0.0:
                    continue
                _, jp = env.kinematics(dyn)(res.q[k])[p]
                jt = tangent @ jp
                lam = float(np.linalg.eigvalsh(jt @ np.linalg.solve(dyn.mass_matrix(res.q[k]), jt.T)).max())
                rate = env.friction * fn * lam / env.slip_velocity
                if rate * h <= limit:
                    continue
                item = {"environment": e, "point": p, "t": float(res.t[k]), "normal_force": fn,
                        "rate_dt": rate * h, "limit": limit, "max_dt": limit / rate,
                        "min_slip_velocity": env.friction * fn * lam * h / limit}
                found.append(item)
                warnings.warn(
                    f"environment {e}, contact point {p}: below its slip velocity the plane's friction is a viscous "
                    f"law of slope μ f_n / v_slip, which {scheme!r} cannot integrate at dt = {h:g} s (at "
                    f"t = {item['t']:.3g} s, f_n = {fn:.3g} N: decay rate × dt = {rate * h:.3g} > {limit:g}): "
                    f"whenever the point slows below v_slip = {env.slip_velocity:g} m/s its friction swings between "
                    f"±μ f_n instead of holding it. Use dt <= {item['max_dt']:.3g} s, slip_velocity >= "
                    f"{item['min_slip_velocity']:.3g} m/s, or integrator='semi-implicit-euler' or 'implicit-euler' "
                    "(both take it implicitly)",
                    SimulationWarning, stacklevel=4)
        col += count
    return found


def after_run(res: SimResult, dyn: Dynamics, environments: Sequence[Environment], scheme: str, h: float) -> None:
    """The checks of the module on a finished run with contact that did not diverge: the friction's slope for
    the explicit schemes; the energy balance (if ``res.energy`` was asked for) for RK4, and for the other
    explicit schemes where the check before the run could not judge a contact (their first-order work
    quadrature drifts by O(h) over a long contact, too much for a 1 % tolerance on a contact it found
    stable)."""
    if not environments or res.diverged or scheme == "implicit-euler" or not len(res.t):
        return
    unstable = check_friction_slope(res, dyn, environments, scheme, h)
    if unstable:
        res.info["unstable_friction"] = unstable
    if math.isnan(float(res.energy[0])):  # energy=False: nothing to balance
        return
    if scheme == "rk4" or not all(map(checkable, environments)):
        check_energy_gain(res, scheme)
