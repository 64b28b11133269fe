"""Benchmark section "plant engines": armctl's and MuJoCo's integrators, cost per simulated second against error.

Both engines run the same closed loop (:func:`armctl.simulate`, ``engine="native"`` or ``"mujoco"``) on the same
plant: the Panda of :func:`armctl.models.panda`, which MuJoCo gets as :meth:`~armctl.RobotModel.to_mjcf` (its M(q)
and g(q) are armctl's to ~1e-14). Each series steps at h = Δt_c / m for m in :data:`SUBSTEPS`, Δt_c =
:data:`CONTROL_DT`, over :data:`DURATION` seconds.

* Frictionless scene: computed torque (K_p = 100, K_d = 20) tracking the sinusoid :data:`REFERENCE` from an
  initial error of 0.1 rad on every joint. Error: max over control instants and joints of |q − q_ref| [rad], with
  q_ref from ``scipy.integrate.solve_ivp`` (DOP853, rtol 1e-11, atol 1e-12) on armctl's forward dynamics, the
  controller evaluated on the reference's own state at every control instant and its torque held over the
  period; its own error is estimated against rtol 1e-13.
* Stiction scene: the Panda with Coulomb friction :data:`COULOMB` (and viscous :data:`VISCOUS`), at rest at
  :data:`HOLD`, held open loop by τ = g(q₀) + ½ F_c ∘ s (s = ±1 alternating): every joint is loaded to half its
  Coulomb level, so the exact motion is none. Error: the creep, max |q − q₀| [rad]. armctl's stick–slip model
  holds the joints exactly (error 0); MuJoCo's ``frictionloss`` is a soft constraint and creeps. (The compiled
  native step takes no friction: it has no point here.)
* Cost [s/s]: the loop's wall time (``res.info["wall_time"]``: controller, integration and recording) per simulated
  second, the minimum over the runs of a case (at least :data:`REPEATS`, and until they add up to
  :data:`MIN_WALL` seconds: the least disturbed run on a shared machine).

Native series: ``"rk4"``, ``"euler"`` (q̇₁ = q̇ + h q̈, q₁ = q + h q̇₁) and RK4 with the compiled step; MuJoCo series:
each of its integrators (``"euler"`` is the same scheme as armctl's, its joint damping implicit; ``"implicitfast"``
and ``"discrete"`` equal it on a frictionless arm without contact, having nothing else to treat implicitly), and on
the stiction scene ``"implicitfast"`` with MuJoCo's NoSlip pass (:data:`NOSLIP_ITERATIONS` iterations), which
re-solves the friction rows as hard constraints after the main solver.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from armctl._checks import FloatArray
from armctl.bench.charts import pyplot, save_figure
from armctl.bench.standalone import section_main

if TYPE_CHECKING:
    from armctl.dynamics.base import Dynamics

#: control period Δt_c [s] and simulated time [s]
CONTROL_DT = 0.01
DURATION = 1.0
#: sub-steps per control period: steps h = Δt_c / m
SUBSTEPS = {True: (1, 4, 16), False: (1, 2, 4, 8, 16, 32)}
#: each case runs at least REPEATS times and until its runs add up to MIN_WALL seconds (at most MAX_REPEATS runs)
REPEATS = {True: 3, False: 7}
MIN_WALL = {True: 0.05, False: 0.3}
MAX_REPEATS = 50
#: NoSlip iterations of the "noslip" series (MuJoCo's post-processing pass that re-solves the friction rows hard)
NOSLIP_ITERATIONS = 10
#: the sinusoid the frictionless scene tracks: centre [rad], amplitude [rad], frequency [Hz]
REFERENCE = {
    "center": [0.0, -0.4, 0.0, -2.0, 0.0, 1.6, 0.8],
    "amplitude": [0.4, 0.3, 0.4, 0.3, 0.5, 0.4, 0.6],
    "frequency": [0.5, 0.7, 0.6, 0.9, 0.8, 1.0, 1.1],
}
GAINS = (100.0, 20.0)
INITIAL_ERROR = 0.1
#: stiction scene: Coulomb and viscous friction of the Panda's joints [N·m, N·m·s/rad], the pose held [rad]
COULOMB = (0.6, 0.6, 0.5, 0.5, 0.3, 0.3, 0.2)
VISCOUS = 0.1
HOLD = (0.0, -0.4, 0.0, -2.0, 0.0, 1.6, 0.8)
#: the series: name → (engine, integrator, variant); variant "compiled": the native compiled step (frictionless scene
#: only), "noslip": MuJoCo with :data:`NOSLIP_ITERATIONS` NoSlip iterations (stiction scene only)
SERIES: dict[str, tuple[str, str, str]] = {
    "native rk4": ("native", "rk4", ""),
    "native euler": ("native", "euler", ""),
    "native rk4 compiled": ("native", "rk4", "compiled"),
    "mujoco rk4": ("mujoco", "rk4", ""),
    "mujoco euler": ("mujoco", "euler", ""),
    "mujoco implicit": ("mujoco", "implicit", ""),
    "mujoco implicitfast": ("mujoco", "implicitfast", ""),
    "mujoco discrete": ("mujoco", "discrete", ""),
    "mujoco implicitfast noslip": ("mujoco", "implicitfast", "noslip"),
}
REFERENCE_TOLERANCES = {"rtol": 1e-11, "atol": 1e-12}
#: errors closer than this many times the reference's own error to it are not compared between engines
FLOOR_FACTOR = 100.0


def _tracking() -> tuple[Dynamics, Any, Any, FloatArray]:
    """(plant dynamics, controller, reference, q0) of the frictionless scene."""
    import armctl
    from armctl.controllers import ComputedTorque
    from armctl.references import Sinusoid

    dyn = armctl.Dynamics(armctl.models.panda())
    ref = Sinusoid(**REFERENCE)
    return dyn, ComputedTorque(dyn, *GAINS), ref, ref(0.0).q + INITIAL_ERROR


def reference_solution(rtol: float, atol: float) -> FloatArray:
    """q [rad] of the frictionless scene at every control instant, (N + 1, n): DOP853 from one control instant to
    the next with the torque the controller computes from the solution's own state (see the module)."""
    from scipy.integrate import solve_ivp

    dyn, ctrl, ref, q0 = _tracking()
    n, periods = dyn.n, round(DURATION / CONTROL_DT)
    x = np.concatenate([q0, np.zeros(n)])
    out = [x[:n].copy()]
    ctrl.reset()
    for k in range(periods):
        t = k * CONTROL_DT
        tau = np.asarray(ctrl(t, x[:n].copy(), x[n:].copy(), ref(t)))

        def f(t: float, x: FloatArray, tau: FloatArray = tau) -> FloatArray:
            return np.concatenate([x[n:], dyn.forward_dynamics(x[:n], x[n:], tau)])

        sol = solve_ivp(f, (t, t + CONTROL_DT), x, method="DOP853", rtol=rtol, atol=atol)
        if not sol.success:  # pragma: no cover - a smooth problem
            raise RuntimeError(f"reference solution failed in period {k}: {sol.message}")
        x = sol.y[:, -1]
        out.append(x[:n].copy())
    return np.array(out)


class HoldingTorque:
    """τ = g(q₀) + ½ F_c ∘ s, whatever the state (the stiction scene's open-loop load)."""

    def __init__(self, dyn: Dynamics, q0: FloatArray) -> None:
        signs = np.where(np.arange(dyn.n) % 2 == 0, 1.0, -1.0)
        self.tau = dyn.gravity_torque(q0) + 0.5 * np.asarray(COULOMB) * signs

    def __call__(self, t: float, q: FloatArray, qd: FloatArray, ref: Any) -> FloatArray:
        return self.tau


def _scene(scene: str, variant: str) -> tuple[Any, Any, Any, FloatArray]:
    """(plant, controller, reference, q0) of a scene; the plant is a MujocoPlant for the "noslip" variant."""
    import armctl
    from armctl.sim import MujocoPlant

    if scene == "frictionless":
        return _tracking()
    model = armctl.models.panda().with_friction(viscous=VISCOUS, coulomb=COULOMB)
    dyn = armctl.Dynamics(model)
    q0 = np.array(HOLD)
    plant: Any = dyn
    if variant == "noslip":
        xml = model.to_mjcf(meshes=False, contacts=False)
        plant = MujocoPlant(xml.replace("<option ", f'<option noslip_iterations="{NOSLIP_ITERATIONS}" ', 1), model)
    return plant, HoldingTorque(dyn, q0), armctl.Reference.hold(q0), q0


def _run(
    scene: str, engine: str, integrator: str, variant: str, substeps: int, quick: bool, q_ref: Any
) -> dict[str, Any]:
    """One series at one step: error [rad] and cost [s/s] (see the module)."""
    from armctl.sim import simulate

    plant, ctrl, ref, q0 = _scene(scene, variant)
    walls: list[float] = []
    err, diverged = math.nan, False
    while len(walls) < MAX_REPEATS and (len(walls) < REPEATS[quick] or sum(walls) < MIN_WALL[quick]):
        res = simulate(
            plant,
            ctrl,
            ref,
            DURATION,
            q0=q0,
            qd0=np.zeros(len(q0)),
            control_dt=CONTROL_DT,
            dt=CONTROL_DT / substeps,
            integrator=integrator,
            saturate=False,
            energy=False,
            compile=variant == "compiled",
            engine=engine,
        )
        if res.diverged:
            diverged = True
            break
        walls.append(float(res.info["wall_time"]))
        err = float(np.abs(res.q - (q_ref if scene == "frictionless" else q0)).max())
    step = CONTROL_DT / substeps
    if diverged:
        return {"step": step, "substeps": substeps, "error": None, "cost": None, "diverged": True, "runs": len(walls)}
    cost = min(walls) / DURATION
    return {"step": step, "substeps": substeps, "error": err, "cost": cost, "diverged": False, "runs": len(walls)}


def run(quick: bool = False) -> dict[str, Any]:
    """Measure; returns every number behind the chart (JSON-serialisable): steps [s], errors [rad], costs [s of
    wall time per s simulated], and the checks."""
    from armctl.sim.mujoco_plant import available_integrators

    q_ref = reference_solution(**REFERENCE_TOLERANCES)
    ref_err = float(np.abs(q_ref - reference_solution(rtol=1e-13, atol=1e-14)).max())
    mujoco_integrators = available_integrators()
    series: dict[str, Any] = {}
    for name, (engine, integrator, variant) in SERIES.items():
        if engine == "mujoco" and integrator not in mujoco_integrators:
            continue
        scenes = {"compiled": ("frictionless",), "noslip": ("stiction",)}.get(variant, ("frictionless", "stiction"))
        series[name] = {"engine": engine, "integrator": integrator, "variant": variant}
        for scene in scenes:
            series[name][scene] = [_run(scene, engine, integrator, variant, m, quick, q_ref) for m in SUBSTEPS[quick]]
    data = {
        "plant": "panda",
        "control_dt": CONTROL_DT,
        "duration": DURATION,
        "repeats": {"at_least": REPEATS[quick], "until_seconds": MIN_WALL[quick], "at_most": MAX_REPEATS},
        "noslip_iterations": NOSLIP_ITERATIONS,
        "frictionless": {
            "controller": f"computed torque, K_p = {GAINS[0]:g}, K_d = {GAINS[1]:g}",
            "reference": REFERENCE,
            "initial_error": INITIAL_ERROR,
            "error_against": "scipy DOP853, rtol 1e-11, atol 1e-12, controller on its own state at each instant",
            "reference_error": ref_err,
        },
        "stiction": {
            "coulomb": list(COULOMB),
            "viscous": VISCOUS,
            "hold": list(HOLD),
            "load": "g(q0) + 0.5 F_c, alternating signs: half the Coulomb level on every joint",
            "error_against": "rest (the exact motion under a load below breakaway)",
        },
        "series": series,
    }
    data["checks"] = checks(data)
    return data


def _relative_gap(a: list[dict], b: list[dict], floor: float) -> float:
    """max |e_a − e_b| / e_a over the steps where both errors are above ``floor``."""
    gaps = [
        abs(x["error"] - y["error"]) / x["error"]
        for x, y in zip(a, b, strict=True)
        if x["error"] is not None and y["error"] is not None and min(x["error"], y["error"]) > floor
    ]
    return max(gaps, default=0.0)


def checks(data: dict[str, Any]) -> dict[str, Any]:
    """What must hold whatever the machine: the same scheme on the same equations gives the same error in both
    engines; armctl's stick–slip model holds the loaded joints exactly; MuJoCo's frictionloss creeps."""
    s = data["series"]
    floor = FLOOR_FACTOR * max(data["frictionless"]["reference_error"], 1e-15)
    out: dict[str, Any] = {}
    for scheme in ("rk4", "euler"):
        if f"mujoco {scheme}" in s:
            gap = _relative_gap(s[f"native {scheme}"]["frictionless"], s[f"mujoco {scheme}"]["frictionless"], floor)
            out[f"{scheme}_engines_agree"] = {"relative_gap": gap, "limit": 1e-3, "ok": gap <= 1e-3}
    native = [c["error"] for k, v in s.items() if v["engine"] == "native" and "stiction" in v for c in v["stiction"]]
    out["native_sticks_exactly"] = {"largest_creep": max(native), "ok": all(e == 0.0 for e in native)}
    creep = [
        c["error"]
        for v in s.values()
        if v["engine"] == "mujoco" and "stiction" in v
        for c in v["stiction"]
        if c["error"] is not None
    ]
    out["mujoco_creeps"] = {"smallest_creep": min(creep, default=0.0), "ok": bool(creep) and min(creep) > 0.0}
    return out


def _span(cases: list[dict], key: str, fmt: str) -> str:
    values = [c[key] for c in cases if c[key] is not None]
    return "diverged" if not values else f"{format(values[0], fmt)}…{format(values[-1], fmt)}"


def summary(data: dict[str, Any]) -> str:
    """Per series: its errors and costs over the steps, both scenes; then the checks."""
    steps = [c["step"] * 1e3 for c in data["series"]["native rk4"]["frictionless"]]
    lines = [
        f"plant engines on {data['plant']} ({data['duration']:g} s, control every {data['control_dt'] * 1e3:g} ms, "
        f"steps {steps[0]:g}…{steps[-1]:g} ms); tracking error vs DOP853 (own error "
        f"~{data['frictionless']['reference_error']:.1e} rad), stiction error = creep under half the Coulomb load"
    ]
    for name, d in data["series"].items():
        parts = []
        if "frictionless" in d:
            cases = d["frictionless"]
            parts.append(f"tracking {_span(cases, 'error', '.1e')} rad at {_span(cases, 'cost', '.3g')} s/s")
        if "stiction" in d:
            cases = d["stiction"]
            parts.append(f"creep {_span(cases, 'error', '.1e')} rad at {_span(cases, 'cost', '.3g')} s/s")
        lines.append(f"  {name:27s} " + "; ".join(parts))
    for key, c in data["checks"].items():
        figures = ", ".join(f"{k} {v:.2g}" for k, v in c.items() if k != "ok")
        lines.append(f"  check {key}: {'ok' if c['ok'] else 'FAILED'} ({figures})")
    return "\n".join(lines)


def plot(data: dict[str, Any], path: Path) -> None:
    """Two log-log panels, cost per simulated second against error: tracking without friction, creep with it (a
    run that does not creep at all is drawn at the panel's left edge, at the tick "0"); labels: step [ms]."""
    import matplotlib.ticker

    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(12.5, 5.2))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    creeps = [c["error"] for d in data["series"].values() for c in d.get("stiction", []) if c["error"]]
    zero_at = min(creeps, default=1e-6) / 10.0
    for ax, scene in zip(axes, ("frictionless", "stiction"), strict=True):
        for i, (name, d) in enumerate(data["series"].items()):
            pts = [
                (c["error"] if c["error"] > 0 else zero_at, c["cost"], c["step"])
                for c in d.get(scene, [])
                if c["error"] is not None and c["cost"]
            ]
            if not pts:
                continue
            style = "o-" if d["engine"] == "native" else "s--"
            ax.plot([p[0] for p in pts], [p[1] for p in pts], style, color=colors[i % len(colors)], label=name, ms=5)
            if name in ("native rk4", "mujoco implicitfast"):  # step labels on two series (the rest share them)
                for e, cost, h in pts:
                    ax.annotate(f"{h * 1e3:g}", (e, cost), textcoords="offset points", xytext=(4, 3), fontsize=7)
        ax.set(xscale="log", yscale="log", ylabel="loop wall time per simulated second [s/s]")
        ax.yaxis.set_major_locator(matplotlib.ticker.LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
        ax.yaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
        if scene == "frictionless":
            ax.set_xlabel("max joint error vs DOP853 reference [rad]")
            ax.set_title("Tracking without friction (computed torque)", fontsize=10)
            continue
        ax.set_xlabel("creep under half the Coulomb load [rad] (exact: 0; stick–slip holds at 0)")
        ax.set_title("Holding below breakaway (Coulomb friction)", fontsize=10)
        ax.set_xlim(zero_at / 2.0, max(creeps, default=1e-3) * 3.0)
        ticks = [t for t in (10.0**k for k in range(-12, 2)) if 3.0 * zero_at < t < max(creeps, default=1e-3) * 3]
        ax.xaxis.set_major_locator(matplotlib.ticker.FixedLocator([zero_at, *ticks]))
        ax.xaxis.set_major_formatter(
            matplotlib.ticker.FuncFormatter(lambda v, _: "0" if abs(v - zero_at) < 1e-3 * zero_at else f"{v:g}")
        )
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.axvspan(zero_at / 2.0, zero_at * 2.0, color="0.93", zorder=0)
    fig.suptitle(f"Plant engines on the {data['plant']}: cost against error (labels: step [ms])", fontsize=11)
    save_figure(fig, path)


def main() -> None:
    section_main(run, summary, plot, "engines.png")


if __name__ == "__main__":
    main()
