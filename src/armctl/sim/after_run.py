"""Checks made after a run with contact, on what it recorded: did an explicit scheme gain energy that no force
supplied? The check before the run (:mod:`armctl.sim.stability`) judges a contact's normal stiffness and
damping at the initial configuration; these catch what it cannot see:

* **energy balance** — E(t) − E(0) − W(t) (:meth:`~armctl.sim.result.SimResult.energy_balance`) rising above
  :data:`ENERGY_GAIN_TOLERANCE` of the energy exchanged: the scheme made energy (a Hunt–Crossley law that
  stiffens with depth, a configuration where the arm is lighter than at the start, the friction below);
* **a passive environment's work** — a compliant plane only gives back what it stored: its work on the arm
  W_e(t) = −U_c(t) − D(t) ≤ 0 (U_c its spring energy, D ≥ 0 its damping and friction losses) for a run that
  starts out of contact. An unstable contact can make energy and book it as the wall's work, so that the
  balance closes (semi-implicit Euler at 1 ms on a stiff Hunt–Crossley wall: the wall "did" +1.3 J); this
  check sees it (runs with a disturbance, whose work W_e includes, are not judged);
* **the friction's regularisation** — a plane's tangential friction is a viscous law of slope μ f_n / v_slip
  below its slip velocity, which the check before the run cannot know (there is no normal force yet). Along
  the tangent plane the point's velocity then decays at the rate a = μ f_n λ / v_slip (λ: the largest
  eigenvalue of the tangential block of J_p M⁻¹ J_pᵀ), and an explicit scheme keeps it stable only for
  a h ≤ 2 (Euler) or 2.785 (RK4, the real root of |1 − z + z²/2 − z³/6 + z⁴/24| = 1). Beyond that a point
  that slows below v_slip chatters: its friction swings between ±μ f_n instead of holding it (a slider that
  should creep under 10 N of friction felt 50 N, either way). Points that stick together add their damping
  (see :func:`check_friction_slope`); "semi-implicit-euler" and "implicit-euler" take this force implicitly.

Each finding is a :class:`~armctl.errors.SimulationWarning` and an entry of ``res.info``.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np

from armctl._checks import FloatArray
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
    """The largest energy exchanged in the run [J] (at least 1e-12; the energy left out if it was not asked
    for, energy=False)."""
    works = (res.work_actuator, res.work_friction, res.work_external)
    change = float(np.abs(res.energy - res.energy[0]).max())
    return max(*(float(np.abs(w).max()) for w in works), change if math.isfinite(change) else 0.0, 1e-12)


#: the energy error a stable first-order scheme may make in contact, as a share of the energy exchanged: its
#: energy oscillates by about ω h / 2 of the contact's, and an impact may gain up to 0.39 of the energy at the
#: ω h = 0.4 the check before the run accepts (:data:`armctl.sim.stability.SAFE_OMEGA_H`)
FIRST_ORDER_TOLERANCE = 0.4


def check_energy_gain(res: SimResult, scheme: str) -> None:
    """Warn if the arm gained energy that no force supplied; record it in ``res.info["energy_gain"]`` [J].

    RK4: the largest E − E₀ − W over the run, against :data:`ENERGY_GAIN_TOLERANCE` of the energy exchanged.
    The first-order schemes make an O(h) energy error while a contact is compressed even when stable, so their
    gain is read where it persists: the largest balance at samples out of contact after the first one, against
    :data:`ENERGY_GAIN_TOLERANCE`; a run that never leaves contact, its last balance against
    :data:`FIRST_ORDER_TOLERANCE`."""
    balance = res.energy_balance()
    if not len(balance):
        return
    scale = _scale(res)
    tolerance = ENERGY_GAIN_TOLERANCE
    if scheme == "rk4":
        gain = float(balance.max())
    else:
        touching = np.abs(res.contact_force_on_environment).reshape(len(balance), -1).max(axis=1) > 0.0
        first = int(np.argmax(touching)) if touching.any() else len(balance)
        apart = ~touching
        apart[:first] = False
        if apart.any():
            gain = float(balance[apart].max())
        else:
            gain, tolerance = float(balance[-1]), FIRST_ORDER_TOLERANCE
    res.info["energy_gain"] = gain
    if gain > tolerance * scale:
        warnings.warn(
            f"the arm gained {gain:.3g} J that no force supplied ({100 * gain / scale:.0f}% of the "
            f"energy exchanged; E − E₀ − W in res.energy_balance()): {scheme!r} was likely unstable on a "
            "contact (e.g. Hunt–Crossley with an exponent above 1 stiffens with depth, which the check "
            "before the run cannot judge). Past that point the run is not the arm's motion: use "
            "integrator='implicit-euler' or a smaller dt",
            SimulationWarning,
            stacklevel=4,
        )


def check_passive_work(res: SimResult, scheme: str) -> None:
    """Warn if the environments, all passive, did positive work on the arm (see the module); record the largest
    ``res.info["environment_work"]`` [J]. The tolerance: :data:`ENERGY_GAIN_TOLERANCE` of the energy exchanged
    for RK4, :data:`FIRST_ORDER_TOLERANCE` for the first-order schemes (a stable impact gains that much)."""
    work = float(res.work_external.max())
    res.info["environment_work"] = work
    scale = _scale(res)
    if work > (ENERGY_GAIN_TOLERANCE if scheme == "rk4" else FIRST_ORDER_TOLERANCE) * scale:
        warnings.warn(
            f"the contact did {work:.3g} J of work on the arm ({100 * work / scale:.0f}% of the energy "
            "exchanged), but a compliant surface only gives back what it stored (from a start out of "
            f"contact its work is <= 0): {scheme!r} was unstable on it. Past that point the run is not the "
            "arm's motion: use integrator='implicit-euler' or a smaller dt",
            SimulationWarning,
            stacklevel=4,
        )


def starts_in_contact(dyn: Dynamics, environments: Sequence[Environment], q: FloatArray) -> bool:
    """True if a contact point of a plane is inside it at configuration q (its spring then holds energy that
    the run may give back)."""
    return any(env.depth(p) > 0.0 for env in environments if isinstance(env, Plane) for p, _ in env.kinematics(dyn)(q))


#: the contact samples at which :func:`check_friction_slope` evaluates the rate, at most (those of the largest
#: friction slopes)
FRICTION_SAMPLES = 400


def check_friction_slope(
    res: SimResult, dyn: Dynamics, environments: Sequence[Environment], scheme: str, h: float
) -> list[dict[str, Any]]:
    """If an explicit ``scheme`` cannot integrate the planes' friction regularisation at step h (see the
    module), a warning and, for ``res.info["unstable_friction"]``, the worst sample: ``t``, ``rate_dt``, the
    ``points`` (environment, point) sticking there, their total ``normal_force``, ``limit``, ``max_dt`` and
    ``min_slip_velocity`` (for one common slip velocity; with several, the largest scaled alike).

    The damping of all points that stick at a sample adds up: D = Σ_p (μ_p f_n,p / v_slip,p) J_tpᵀJ_tp over the
    points whose tangential speed is at most their slip velocity (J_tp: the tangential rows of the point's
    velocity Jacobian), and the fastest decay rate is the largest eigenvalue of M⁻¹D. Evaluated at up to
    :data:`FRICTION_SAMPLES` contact samples, those with the largest total slope first."""
    limit = DAMPING_LIMIT.get(scheme)
    if limit is None or not len(res.t):
        return []
    planes, col = [], 0
    for e, env in enumerate(environments):
        if isinstance(env, Plane) and env.friction > 0.0:
            tangent = np.eye(3) - np.outer(env.normal, env.normal)
            fn = res.contact_force_on_robot[:, col : col + len(env.points), :] @ env.normal  # (N, P)
            planes.append((e, env, env.kinematics(dyn), tangent, np.maximum(fn, 0.0)))
        col += len(env.points)
    if not planes:
        return []
    slope = sum(env.friction * fn.sum(axis=1) / env.slip_velocity for _, env, _, _, fn in planes)
    order = np.argsort(-slope)[: min(FRICTION_SAMPLES, int((slope > 0).sum()))]
    worst: dict[str, Any] | None = None
    for k in order.tolist():
        q, qd = res.q[k], res.qd[k]
        damping = np.zeros((dyn.n, dyn.n))
        points, force, slip = [], 0.0, 0.0
        for e, env, kin, tangent, fn in planes:
            for p, (_, jp) in enumerate(kin(q)):
                if fn[k, p] <= 0.0:
                    continue
                jt = tangent @ jp
                if float(np.linalg.norm(jt @ qd)) > env.slip_velocity:  # sliding: full Coulomb, not this law
                    continue
                damping += (env.friction * fn[k, p] / env.slip_velocity) * (jt.T @ jt)
                points.append((e, p))
                force += float(fn[k, p])
                slip = max(slip, env.slip_velocity)
        if not points:
            continue
        rate = float(np.linalg.eigvals(np.linalg.solve(dyn.mass_matrix(q), damping)).real.max())
        if rate * h > limit and (worst is None or rate * h > worst["rate_dt"]):
            worst = {
                "t": float(res.t[k]),
                "points": points,
                "normal_force": force,
                "rate_dt": rate * h,
                "limit": limit,
                "max_dt": limit / rate,
                "min_slip_velocity": slip * rate * h / limit,
            }
    if worst is None:
        return []
    where = ", ".join(f"environment {e} point {p}" for e, p in worst["points"])
    warnings.warn(
        f"below their slip velocity the planes' friction is a viscous law of slope μ f_n / v_slip, which "
        f"{scheme!r} cannot integrate at dt = {h:g} s (at t = {worst['t']:.3g} s, {where} sticking under "
        f"f_n = {worst['normal_force']:.3g} N: decay rate × dt = {worst['rate_dt']:.3g} > {limit:g}): the friction "
        f"swings between ±μ f_n instead of holding the contact. Use dt <= {worst['max_dt']:.3g} s, slip_velocity >= "
        f"{worst['min_slip_velocity']:.3g} m/s, or integrator='semi-implicit-euler' or 'implicit-euler' (both take "
        "it implicitly)",
        SimulationWarning,
        stacklevel=4,
    )
    return [worst]


def after_run(
    res: SimResult, dyn: Dynamics, environments: Sequence[Environment], scheme: str, h: float, disturbed: bool = False
) -> None:
    """The checks of the module on a finished run with contact that did not diverge: the friction's slope for
    the explicit schemes; the energy balance (if ``res.energy`` was asked for) for RK4, and for the other
    explicit schemes where the check before the run could not judge a contact; the environments' work when
    there is no disturbance and the run starts out of contact."""
    if not environments or res.diverged or scheme == "implicit-euler" or not len(res.t):
        return
    unstable = check_friction_slope(res, dyn, environments, scheme, h)
    if unstable:
        res.info["unstable_friction"] = unstable
    if not disturbed and not starts_in_contact(dyn, environments, res.q[0]):
        check_passive_work(res, scheme)
    if scheme == "rk4" or not all(map(checkable, environments)):
        if not math.isnan(float(res.energy[0])):  # energy=False: nothing to balance
            check_energy_gain(res, scheme)
