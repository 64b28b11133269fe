"""Force tracking against the environment's stiffness: the Panda asked for 10 N on tables from 10³ to 3·10⁵ N/m,
each controller with gains fixed for a mid-range table (one period of measurement delay at 1 kHz, a force/torque
sensor at the tool).

* Cartesian impedance and admittance (stiffness 500 N/m, target 2 cm deep): the force is k_e k_d/(k_e + k_d)·δ_c,
  10 N only on a rigid table; softer tables get less.
* Force control, proportional (K_F = 10⁻³ m/N): the error f_d/(1 + k_e K_F) shrinks as the table stiffens, until
  the loop gain k_e K_F passes its sampled-data border (:mod:`armctl.tuning.force_stability`) and the contact
  chatters.
* Parallel force/position control (K_F = 2·10⁻⁴ m/N, K_I = 10⁻³ m/(N·s)): no error at rest, reached at the
  integral's rate k_e K_I (slow on soft tables).

The error is the mean |f − 10 N| over the last 0.3 s of a 1.5 s run; a run that chatters or diverges is marked.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

import armctl
from armctl.bench.interaction_borders import FORCE, Q_READY, outcome, press

DEPTH = 0.02  # [m] the impedance target's depth below the table
K_D, K_F = 500.0, 1e-3  # [N/m] the impedance's stiffness, [m/N] the proportional force gain


def closed_forms(k_e: float) -> dict[str, float]:
    """The force errors at rest [N] of impedance (series springs) and of proportional force control."""
    return {"impedance": abs(FORCE - k_e * K_D / (k_e + K_D) * DEPTH), "force_p": FORCE / (1.0 + k_e * K_F)}


def _target(dyn: armctl.Dynamics) -> np.ndarray:
    pose = dyn.frame_pose(Q_READY)
    pose[2, 3] -= DEPTH
    return pose


def controllers() -> dict[str, Callable[[], Any]]:
    """Name → a function building the controller (new for every run)."""
    from armctl.controllers import Admittance, CartesianImpedance, ForceControl, ParallelForcePosition

    def dyn() -> armctl.Dynamics:
        return armctl.Dynamics(armctl.models.panda())

    k = [K_D, K_D, K_D, 50.0, 50.0, 50.0]
    f_d = [0.0, 0.0, -FORCE]

    def impedance() -> Any:
        d = dyn()
        c = CartesianImpedance(d, k, nullspace_stiffness=5.0, posture=Q_READY)
        c.set_target(_target(d))
        return c

    def admittance() -> Any:
        d = dyn()
        c = Admittance(d, k, kp=900.0)
        c.set_target(_target(d))
        return c

    return {
        "CartesianImpedance": impedance,
        "Admittance": admittance,
        "ForceControl (P)": lambda: ForceControl(dyn(), f_d, K_F, directions=[0.0, 0.0, 1.0], kp=400.0, kd=40.0),
        "ParallelForcePosition (PI)": lambda: ParallelForcePosition(dyn(), f_d, 2e-4, 1e-3, kp=400.0),
    }


def run(quick: bool = False) -> dict[str, Any]:
    """The force error of every controller on every table (see the module)."""
    stiffnesses = [1e3, 1e4, 1e5] if quick else [1e3, 3e3, 1e4, 3e4, 1e5, 3e5]
    duration = 1.0 if quick else 1.5
    out: dict[str, Any] = {
        "stiffness": stiffnesses,
        "force": FORCE,
        "controllers": {},
        "closed_forms": [closed_forms(k) for k in stiffnesses],
    }
    for name, make in controllers().items():
        rows = []
        for k_e in stiffnesses:
            res = press(make(), k_e, duration)
            f = res.contact_force_on_robot[:, 0, 2]
            last = res.t >= res.t[-1] - 0.3
            rows.append({"outcome": outcome(res), "error": float(np.abs(f[last] - FORCE).mean())})
        out["controllers"][name] = rows
    return out


def plot_axes(data: dict[str, Any], ax: Any) -> None:
    """The force error against k_e, one line per controller, chattering runs crossed out."""
    k = data["stiffness"]
    for name, rows in data["controllers"].items():
        err = [r["error"] for r in rows]
        (line,) = ax.loglog(k, np.maximum(err, 1e-4), "o-", label=name)
        bad = [(kk, max(e, 1e-4)) for kk, e, r in zip(k, err, rows, strict=True) if r["outcome"] != "stable"]
        if bad:
            ax.plot(*zip(*bad, strict=True), "x", color=line.get_color(), ms=12, mew=2)
    for key, label in (("impedance", "k_d δ_c series springs"), ("force_p", "f_d / (1 + k_e K_F)")):
        ax.loglog(k, [c[key] for c in data["closed_forms"]], "k:", lw=1)
        ax.annotate(label, (k[0], data["closed_forms"][0][key]), fontsize=7, textcoords="offset points", xytext=(2, 4))
    ax.set_xlabel("table stiffness k_e [N/m]")
    ax.set_ylabel(f"mean |f − {data['force']:g} N| at the end [N]")
    ax.set_title("force-tracking error (×: the contact chatters)", fontsize=10)
    ax.legend(fontsize=8)


def summary_lines(data: dict[str, Any]) -> list[str]:
    """One line per controller."""
    out = ["force-tracking error [N] against table stiffness " + " ".join(f"{k:8.0e}" for k in data["stiffness"])]
    for name, rows in data["controllers"].items():
        cells = " ".join(f"{r['error']:8.3f}" if r["outcome"] == "stable" else f"{r['outcome']:>8s}" for r in rows)
        out.append(f"  {name:44s}{cells}")
    return out
