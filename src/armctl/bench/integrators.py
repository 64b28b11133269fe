"""Benchmark section: the simulator's integrators, cost per simulated second against trajectory error.

Scenario (fixed, no friction, no contact): the two-link arm of :func:`armctl.models.planar_2r` (geared
motors, no friction) driven open loop for :data:`DURATION` seconds by a feed-forward torque profile — its own
inverse dynamics along the sinusoid :data:`REFERENCE`, sampled every :data:`CONTROL_DT` seconds and held
constant over each period (zero-order hold). Being open loop, the held torques are the same for every
integrator and step size, so the runs differ only by how they integrate

    M(q) q̈ + C(q, q̇) q̇ + g(q) = τ_k,     t ∈ [t_k, t_k + Δt_c).

On this arm, without friction or contact, "implicit-euler" has nothing to treat implicitly (it treats the
friction, damping and contact forces so) and is the "euler" scheme (q̇₁ = q̇ + h q̈, q₁ = q + h q̇₁), to rounding:
its figures here are that scheme's.

Each integrator ("rk4", "semi-implicit-euler", "implicit-euler") runs through :func:`armctl.sim.simulate` with
step h = Δt_c / m for m in :data:`SUBSTEPS` (the steps align with the control instants, so the torque jumps
never fall inside a step); "rk4-compiled" is RK4 again with ``compile=True`` (the step as generated C code,
:mod:`armctl.sim.compiled`): the same errors to rounding, at its own cost.

* error [rad]: max over control instants and joints of |q − q_ref|, where q_ref is the independent reference
  solution: ``scipy.integrate.solve_ivp`` with DOP853, rtol 1e-11 and atol 1e-12, on
  ``Dynamics.forward_dynamics`` of the same plant with the same held torques, restarted at every control
  instant. Its own error is estimated against a second solve at rtol 1e-13 (``reference_error``); observed
  orders are computed only where the error is well above it.
* cost [s/s]: the simulator's wall time (``res.info["wall_time"]``, the loop only) per simulated second; the
  minimum over ``repeats`` runs (the least disturbed one on a shared machine).
* observed order between two consecutive step sizes: p = log(e(h) / e(h/2)) / log 2 (4 for RK4 in its
  asymptotic range, 1 for the Euler schemes).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from armctl._checks import FloatArray
from armctl.bench.charts import pyplot, save_figure
from armctl.bench.standalone import section_main

if TYPE_CHECKING:
    from armctl.dynamics.base import Dynamics
    from armctl.references import Reference

INTEGRATORS: tuple[str, ...] = ("rk4", "semi-implicit-euler", "implicit-euler")
#: the chart's series: name → (integrator, compile)
SERIES: dict[str, tuple[str, bool]] = {**{name: (name, False) for name in INTEGRATORS}, "rk4-compiled": ("rk4", True)}
#: control (torque-hold) period Δt_c [s]
CONTROL_DT = 0.01
#: simulated time [s]
DURATION = 1.0
#: sub-steps per control period: step sizes h = Δt_c / m
SUBSTEPS = {True: (1, 2, 4, 8, 16), False: (1, 2, 4, 8, 16, 32, 64)}
#: the sinusoid the feed-forward torque is computed along: centre [rad], amplitude [rad], frequency [Hz]
REFERENCE = {"center": [0.0, 0.0], "amplitude": [0.5, 0.5], "frequency": [1.0, 1.0]}
REFERENCE_RTOL = 1e-11
REFERENCE_ATOL = 1e-12
#: an observed order is computed only where the finer error exceeds this many times the reference's own error
FLOOR_FACTOR = 100.0


@dataclass(frozen=True)
class Scenario:
    """The fixed open-loop scenario: plant, initial state, and the held torque of every control period."""

    dynamics: Dynamics
    q0: FloatArray
    qd0: FloatArray
    torques: FloatArray  # (N + 1, n) [N·m]: τ_k held over [t_k, t_k + Δt_c); the last row is never applied
    control_dt: float
    duration: float

    @property
    def periods(self) -> int:
        return round(self.duration / self.control_dt)

    def controller(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        """The open-loop torque profile as a controller: τ(t_k) regardless of the state."""
        return self.torques[round(t / self.control_dt)]


def scenario(control_dt: float = CONTROL_DT, duration: float = DURATION) -> Scenario:
    """The planar 2R arm with the feed-forward torques of :data:`REFERENCE` sampled every ``control_dt`` [s]."""
    import armctl
    from armctl.references import Sinusoid

    dyn = armctl.Dynamics(armctl.models.planar_2r())
    ref = Sinusoid(**REFERENCE)
    n_periods = round(duration / control_dt)
    rows = []
    for k in range(n_periods + 1):
        r = ref(k * control_dt)
        rows.append(dyn.inverse_dynamics(r.q, r.qd, r.qdd))
    r0 = ref(0.0)
    return Scenario(dyn, r0.q, r0.qd, np.array(rows), control_dt, duration)


def reference_solution(sc: Scenario, rtol: float = REFERENCE_RTOL, atol: float = REFERENCE_ATOL) -> FloatArray:
    """q [rad] at every control instant (N + 1, n) from scipy's DOP853 on ``forward_dynamics`` with the held
    torques, restarted at every control instant (the torque is smooth inside a period)."""
    from scipy.integrate import solve_ivp

    dyn, n = sc.dynamics, sc.dynamics.n
    x = np.concatenate([sc.q0, sc.qd0])
    out = [x[:n].copy()]
    for k in range(sc.periods):
        tau = sc.torques[k]

        def f(t: float, x: FloatArray, tau: FloatArray = tau) -> FloatArray:
            return np.concatenate([x[n:], dyn.forward_dynamics(x[:n], x[n:], tau)])

        sol = solve_ivp(f, (k * sc.control_dt, (k + 1) * sc.control_dt), x, method="DOP853", rtol=rtol, atol=atol)
        if not sol.success:  # pragma: no cover - a smooth 2-DOF problem
            raise RuntimeError(f"reference solution failed in period {k}: {sol.message}")
        x = sol.y[:, -1]
        out.append(x[:n].copy())
    return np.array(out)


def run_case(
    sc: Scenario, q_ref: FloatArray, integrator: str, substeps: int, repeats: int = 1, compile: bool = False
) -> dict[str, Any]:
    """One integrator at step Δt_c / ``substeps``: error [rad] against ``q_ref`` and cost [s per simulated s]
    (``compile``: with simulate's compiled step, built or loaded before the loop's clock starts)."""
    from armctl.sim import simulate

    walls, err = [], math.nan
    for _ in range(repeats):
        res = simulate(
            sc.dynamics,
            sc.controller,
            _hold(sc),
            sc.duration,
            q0=sc.q0,
            qd0=sc.qd0,
            control_dt=sc.control_dt,
            dt=sc.control_dt / substeps,
            integrator=integrator,
            saturate=False,
            energy=False,
            compile=compile,
        )
        if res.diverged:
            return {
                "step": sc.control_dt / substeps,
                "substeps": substeps,
                "error": math.inf,
                "cost": math.nan,
                "diverged": True,
            }
        walls.append(float(res.info["wall_time"]))
        err = float(np.abs(res.q - q_ref).max())
    wall = min(walls)
    return {
        "step": sc.control_dt / substeps,
        "substeps": substeps,
        "error": err,
        "cost": wall / sc.duration,
        "wall_s": wall,
        "cost_per_step": wall / (sc.periods * substeps),
        "diverged": False,
    }


def _hold(sc: Scenario) -> Reference:
    """A constant Reference (the open-loop controller ignores it)."""
    from armctl.references import Reference

    return Reference(sc.q0)


def observed_orders(steps: list[float], errors: list[float], floor: float) -> list[float | None]:
    """p_i = log(e_i / e_{i+1}) / log(h_i / h_{i+1}) for consecutive step sizes, None where the finer error is
    below ``floor`` (there the reference's own error would bias the estimate)."""
    out: list[float | None] = []
    for (h0, e0), (h1, e1) in zip(
        zip(steps, errors, strict=True), zip(steps[1:], errors[1:], strict=True), strict=False
    ):
        ok = all(math.isfinite(e) and e > 0 for e in (e0, e1)) and e1 > floor
        out.append(math.log(e0 / e1) / math.log(h0 / h1) if ok else None)
    return out


def run(quick: bool = False) -> dict[str, Any]:
    """Measure; returns every number behind the chart (JSON-serialisable). Steps in [s], errors in [rad],
    costs in [s of wall time per s simulated]."""
    sc = scenario()
    q_ref = reference_solution(sc)
    q_check = reference_solution(sc, rtol=1e-13, atol=1e-14)
    ref_err = float(np.abs(q_ref - q_check).max())
    floor = FLOOR_FACTOR * max(ref_err, 1e-15)
    repeats = 1 if quick else 3
    data: dict[str, Any] = {
        "scenario": {
            "plant": sc.dynamics.model.name,
            "backend": sc.dynamics.backend,
            "duration": sc.duration,
            "control_dt": sc.control_dt,
            "torque": "open-loop feed-forward: inverse dynamics along the sinusoid, zero-order held",
            "sinusoid": REFERENCE,
            "friction": "none",
            "repeats": repeats,
        },
        "reference": {
            "method": "scipy.integrate.solve_ivp DOP853",
            "rtol": REFERENCE_RTOL,
            "atol": REFERENCE_ATOL,
            "restarted_each_control_period": True,
            "error_estimate": ref_err,
            "error_estimate_against": "DOP853 rtol 1e-13, atol 1e-14",
        },
        "error_floor": floor,
        "integrators": {},
    }
    from armctl.bench.progress import steps as progress

    for name, (integrator, compiled) in progress(SERIES.items(), "integrators", total=len(SERIES)):
        cases = [run_case(sc, q_ref, integrator, m, repeats, compiled) for m in SUBSTEPS[quick]]
        steps, errors = [c["step"] for c in cases], [c["error"] for c in cases]
        orders = observed_orders(steps, errors, floor)
        valid = [p for p in orders if p is not None]
        data["integrators"][name] = {"cases": cases, "orders": orders, "asymptotic_order": valid[-1] if valid else None}
    return data


def summary(data: dict[str, Any]) -> str:
    """A few lines: per integrator, the error and cost range and the observed order."""
    s = data["scenario"]
    lines = [
        f"integrators on {s['plant']} ({s['duration']:g} s open loop, torque held every "
        f"{s['control_dt'] * 1e3:g} ms); error vs {data['reference']['method']} "
        f"(own error ~{data['reference']['error_estimate']:.1e} rad)"
    ]
    for name, d in data["integrators"].items():
        c = d["cases"]
        order = d["asymptotic_order"]
        lines.append(
            f"  {name:20s} h {c[0]['step'] * 1e3:g}…{c[-1]['step'] * 1e3:g} ms: error "
            f"{c[0]['error']:.1e}…{c[-1]['error']:.1e} rad, cost {c[0]['cost']:.3g}…{c[-1]['cost']:.3g} s/s, "
            f"order {'n/a' if order is None else f'{order:.2f}'}"
        )
    return "\n".join(lines)


def plot(data: dict[str, Any], path: Path) -> None:
    """Log-log chart: cost per simulated second against max joint-angle error, one line per integrator, each
    point labelled by its step size [ms]; writes a PNG to ``path``."""
    plt = pyplot()

    fig, ax = plt.subplots(figsize=(8.0, 5.4))
    offsets = [((5, 3), "left"), ((-5, 3), "right"), ((5, -10), "left"), ((6, -4), "left")]
    for i, (name, d) in enumerate(data["integrators"].items()):
        pts = [
            (c["error"], c["cost"], c["step"])
            for c in d["cases"]
            if math.isfinite(c["error"]) and c["error"] > 0 and math.isfinite(c["cost"])
        ]
        if not pts:
            continue
        order = d["asymptotic_order"]
        label = f"{name} (order {order:.2f})" if order is not None else name
        if name == "implicit-euler":  # nothing stiff here to treat implicitly (see the module)
            label += ', = "euler" here'
        ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", label=label)
        xytext, ha = offsets[i % len(offsets)]
        for e, c, h in pts:
            ax.annotate(f"{h * 1e3:g}", (e, c), textcoords="offset points", xytext=xytext, ha=ha, fontsize=9)
    ax.axvline(data["error_floor"], color="0.6", ls=":", lw=1, label="order-estimate floor")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("max joint-angle error vs DOP853 reference [rad]")
    ax.set_ylabel("simulator wall time per simulated second [s/s]")
    s = data["scenario"]
    ax.set_title(f"Integrators on {s['plant']}: cost vs accuracy (labels: step [ms])", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=9)
    save_figure(fig, path)


def main() -> None:
    section_main(run, summary, plot, "integrators.png")


if __name__ == "__main__":
    main()
