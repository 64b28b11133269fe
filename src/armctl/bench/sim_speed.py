"""Speed of the closed loop users run — joint friction with stiction, contact, sweeps — against MuJoCo stepping the
same arm from a Python loop with the same controller.

Run: ``python -m armctl.bench.sim_speed [--quick] [--no-sweep] [--json FILE]``. Every figure is a ratio to a
reference measured in the same process, in interleaved rounds (the median of the per-round ratios), so that a busy
shared machine slows both alike. Sections:

* **Panda**: computed torque (K_p = 400, K_d = 40, on the friction-free model) at 1 kHz tracking a joint-space sine
  (:class:`SampledSine`), the plant with viscous 0.2, Coulomb 0.3 and static 0.4 friction, 1 ms steps. Each mode of
  ``simulate`` — the default (RK4, stick–slip, the generated step), the Python step (``compile=False``),
  ``"euler"``, ``"semi-implicit-euler"``, smooth friction, the frictionless arm — as the whole call's cost per
  control step and its ratio to MuJoCo's loop (:func:`armctl.bench.mujoco_loops.closed_loop`: ``implicitfast``,
  damping 0.2 and frictionloss 0.3, the same controller and reference); the tracking errors of both.
* **Chains**: planar chains of N = 2, 4, 7, 12, 20 revolute joints (:func:`planar_chain`: 1 kg, 0.25 m links), the
  same friction, controller and kind of reference, default ``simulate`` against MuJoCo's loop.
* **Sticking chains**: the same chains with friction that makes joints stick at every size: each joint's static
  level is :data:`STICK_PER_INERTIA` times its diagonal inertia M_ii at the hanging pose (Coulomb 0.8 of it), so
  joints stop and break away throughout the run, many at once on the long chains — the cost of the stick solve as
  the stuck set grows, against MuJoCo with the same frictionloss.
* **Contact**: the plant of ``panda_contact`` alone (table: Kelvin–Voigt with Coulomb sliding, joint friction; 0.2 ms
  steps), replaying the torques of one run of the scene — the generated step and the Python step against MuJoCo's
  plant at the same step (:func:`armctl.bench.mujoco_loops.contact_model`); and the scene's whole loop, plant and
  its own OSC controller, against MuJoCo's loop with the same controller (:mod:`armctl.bench.contact_loop`).
* **Sweeps** (:mod:`armctl.bench.sweep_speed`): the speed-up of the sweep's process pool and of a Dask
  ``LocalCluster`` over the same runs one after the other, with the machine's ceiling.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import time
import warnings
from collections.abc import Callable
from typing import Any, cast

import numpy as np

import armctl
from armctl.controllers import ComputedTorque
from armctl.model.parts import Frame, Joint, Link, transform
from armctl.references import Reference
from armctl.sim import Forces, simulate

#: the benchmark's own checks (its tests), not printed: the largest ratio to MuJoCo's loop of the default run on the
#: Panda and of every chain, of the contact plant alone to MuJoCo's plant, of the contact scene's whole loop to
#: MuJoCo's loop with the same controller, of semi-implicit Euler to RK4; the least speed-up of the pool and of Dask
TARGETS = {
    "panda_ratio": 1.0,
    "chain_ratio": 2.0,
    "sticking_chain_ratio": 1.5,
    "contact_plant_ratio": 3.0,
    "contact_loop_ratio": 0.7,
    "semi_implicit_over_rk4": 1.5,
    "pool_speedup": 1.65,
    "dask_speedup": 1.5,
}
#: the Panda's friction: viscous [N·m·s/rad], Coulomb and static [N·m]
FRICTION = {"viscous": 0.2, "coulomb": 0.3, "static": 0.4}
Q_PANDA = np.array([0.0, -0.4, 0.0, -2.0, 0.0, 1.6, 0.8])
CHAINS = (2, 4, 7, 12, 20)
#: the sticking chains' static friction per unit of joint inertia [N·m per kg·m², i.e. rad/s²]: comparable to the
#: reference's peak acceleration (1.2 rad/s²), so that joints stick at each reversal
STICK_PER_INERTIA = 1.0
#: the modes of ``simulate`` timed on the Panda: name → (plant friction, keywords)
PANDA_MODES: dict[str, tuple[bool, dict[str, Any]]] = {
    "default": (True, {}),
    "python step": (True, {"compile": False}),
    "euler": (True, {"integrator": "euler"}),
    "semi-implicit-euler": (True, {"integrator": "semi-implicit-euler"}),
    "semi-implicit-euler, python step": (True, {"integrator": "semi-implicit-euler", "compile": False}),
    "smooth friction": (True, {"forces": Forces(friction="smooth")}),
    "frictionless": (False, {}),
}


class SampledSine:
    """q_r(t) = q0 + a sin(ω t) on every joint, precomputed at the control instants (a table lookup per call)."""

    def __init__(self, q0: np.ndarray, amplitude: float, omega: float, period: float, duration: float) -> None:
        self.period = period
        self.table = []
        for k in range(round(duration / period) + 1):
            s, c = math.sin(omega * k * period), math.cos(omega * k * period)
            n = len(q0)
            self.table.append(
                Reference(q0 + amplitude * s, np.full(n, amplitude * omega * c), np.full(n, -amplitude * omega**2 * s))
            )

    def __call__(self, t: float) -> Reference:
        return self.table[min(round(t / self.period), len(self.table) - 1)]


def planar_chain(n: int, mass: float = 1.0, length: float = 0.25) -> armctl.RobotModel:
    """n uniform rods of ``mass`` [kg] and ``length`` [m] in a vertical plane (axes along −y), the tool at the tip;
    no effort limits (the 20-link chain's base needs up to 1.8 kN·m to track the sine)."""
    inertia = mass * length**2 / 12.0
    link = Link(mass, (length / 2, 0.0, 0.0), np.diag([1e-4, inertia, inertia]))
    joints = tuple(
        Joint(
            f"joint{k + 1}",
            "revolute",
            (0.0, -1.0, 0.0),
            transform(None, (length if k else 0.0, 0.0, 0.0)),
            link,
        )
        for k in range(n)
    )
    tool = Frame("tool", n, transform(None, (length, 0.0, 0.0)))
    return armctl.RobotModel(joints, name=f"chain{n}", frames=(tool,), tool_frame="tool")


def _rms(res: Any) -> float:
    """RMS over the samples of the largest joint error [rad]."""
    return float(np.sqrt(np.mean(np.abs(res.error).max(axis=1) ** 2)))


def _tracking(model: armctl.RobotModel, q0: np.ndarray, duration: float) -> tuple[Any, Any, int]:
    """(controller, reference, control periods) of the tracking runs."""
    ctrl = ComputedTorque(armctl.Dynamics(model.reduced(friction=False)), 400.0, 40.0)
    return ctrl, SampledSine(q0, 0.3, 2.0, 1e-3, duration), round(duration / 1e-3)


def _rounds(candidates: dict[str, Callable[[], float]], rounds: int) -> dict[str, list[float]]:
    """Seconds of each candidate in each of ``rounds`` interleaved rounds (after one warm-up call each)."""
    for fn in candidates.values():
        fn()
    out: dict[str, list[float]] = {k: [] for k in candidates}
    for _ in range(rounds):
        for name, fn in candidates.items():
            out[name].append(fn())
    return out


def _ratios(samples: dict[str, list[float]], base: str) -> dict[str, float]:
    """The median over rounds of each candidate's time over ``base``'s in the same round."""
    return {k: statistics.median(a / b for a, b in zip(v, samples[base], strict=True)) for k, v in samples.items()}


def _timed(run: Callable[[], Any]) -> Callable[[], float]:
    def call() -> float:
        t0 = time.perf_counter()
        run()
        return time.perf_counter() - t0

    return call


# -------------------------------------------------------------------------------------------------- Panda
def panda_figures(duration: float = 10.0, rounds: int = 3) -> dict[str, Any]:
    from armctl.bench import mujoco_loops

    model = armctl.models.panda().with_friction(**FRICTION)
    plants = {True: armctl.Dynamics(model), False: armctl.Dynamics(model.reduced(friction=False))}
    ctrl, ref, steps = _tracking(model, Q_PANDA, duration)
    errors: dict[str, float] = {}
    compiled: dict[str, bool] = {}
    loops: dict[str, list[float]] = {name: [] for name in PANDA_MODES}

    def mode(name: str) -> Callable[[], float]:
        friction, kw = PANDA_MODES[name]

        def run() -> float:  # the simulate call (the tracking error after it, as MuJoCo's loop computes its own)
            t0 = time.perf_counter()
            res = simulate(plants[friction], ctrl, ref, duration, q0=Q_PANDA, **kw)
            wall = time.perf_counter() - t0
            errors[name], compiled[name] = _rms(res), bool(res.info["compiled"])
            loops[name].append(res.info["wall_time"])
            return wall

        return run

    m, d = mujoco_loops.joint_friction_model(model, 1e-3)

    def mujoco() -> float:
        wall, errors["mujoco"] = mujoco_loops.closed_loop(m, d, ctrl, ref, Q_PANDA, steps, 1e-3)
        return wall

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # (the stick–slip arm exceeds joint 7's velocity limit: said per run)
        samples = _rounds({**{name: mode(name) for name in PANDA_MODES}, "mujoco": mujoco}, rounds)
    ratios = _ratios(samples, "mujoco")
    # the loop alone (res.info["wall_time"]: without the checks before it and the result's assembly after it)
    loop_ratios = _ratios({**{k: v[1:] for k, v in loops.items()}, "mujoco": samples["mujoco"]}, "mujoco")
    out: dict[str, Any] = {"steps": steps, "duration_s": duration, "modes": {}}
    for name, vals in samples.items():
        out["modes"][name] = {
            "us_per_step": 1e6 * statistics.median(vals) / steps,
            "ratio_to_mujoco": ratios[name],
            "loop_ratio_to_mujoco": loop_ratios[name],
            "rms_error_rad": errors[name],
            "compiled": compiled.get(name),
        }
    out["semi_implicit_over_rk4"] = _ratios(samples, "default")["semi-implicit-euler"]
    return out


# -------------------------------------------------------------------------------------------------- chains
def sticking_friction(model: armctl.RobotModel, q0: np.ndarray) -> armctl.RobotModel:
    """``model`` with static friction F_s,i = :data:`STICK_PER_INERTIA` · M_ii(q0), Coulomb 0.8 F_s,i, viscous
    0.2 N·m·s/rad."""
    static = STICK_PER_INERTIA * np.diag(armctl.Dynamics(model).mass_matrix(q0))
    return model.with_friction(viscous=FRICTION["viscous"], coulomb=0.8 * static, static=static)


def chain_figures(
    ns: tuple[int, ...] = CHAINS, duration: float = 2.0, rounds: int = 3, sticking: bool = False
) -> dict[str, Any]:
    """The chains' figures (see the module); ``sticking``: with :func:`sticking_friction` instead of the fixed
    levels."""
    from armctl.bench import mujoco_loops

    out: dict[str, Any] = {}
    for n in ns:
        q0 = np.zeros(n)
        q0[0] = -math.pi / 2  # hanging
        model = sticking_friction(planar_chain(n), q0) if sticking else planar_chain(n).with_friction(**FRICTION)
        dyn = armctl.Dynamics(model)
        ctrl, ref, steps = _tracking(model, q0, duration)
        info: dict[str, Any] = {}

        def arm(dyn: Any = dyn, ctrl: Any = ctrl, ref: Any = ref, q0: np.ndarray = q0, info: dict = info) -> None:
            res = simulate(dyn, ctrl, ref, duration, q0=q0)
            info.update(res.info, stuck_fraction=float(res.stuck.mean()), most_stuck=int(res.stuck.sum(axis=1).max()))

        m, d = mujoco_loops.joint_friction_model(model, 1e-3)

        def mujoco(m: Any = m, d: Any = d, c: Any = ctrl, r: Any = ref, q: np.ndarray = q0, s: int = steps) -> float:
            return float(mujoco_loops.closed_loop(m, d, c, r, q, s, 1e-3)[0])

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            samples = _rounds({"armctl": _timed(arm), "mujoco": mujoco}, rounds)
        out[str(n)] = {
            "us_per_step": 1e6 * statistics.median(samples["armctl"]) / steps,
            "mujoco_us_per_step": 1e6 * statistics.median(samples["mujoco"]) / steps,
            "ratio_to_mujoco": _ratios(samples, "mujoco")["armctl"],
            "stick_events": info.get("stick_events"),
            "breakaway_events": info.get("breakaway_events"),
            "stuck_fraction": info.get("stuck_fraction"),
            "most_stuck": info.get("most_stuck"),
            "compiled": info.get("compiled"),
        }
    return out


# ------------------------------------------------------------------------------------------------- contact
def contact_figures(rounds: int = 3) -> dict[str, Any]:
    """The plant of ``panda_contact`` alone (see the module)."""
    from armctl.bench import mujoco_loops
    from armctl.scenes.panda_contact import Q_HOME, ContactScene, panda_contact
    from armctl.sim.compiled import choose_step
    from armctl.sim.friction import StickSlip
    from armctl.sim.plant import Plant
    from armctl.sim.stepper import advance

    scene = panda_contact()
    res = scene.run("osc_qp")
    torques = res.tau_applied[:-1]
    m_sub, h = res.info["substeps"], res.info["dt"]
    plane = scene.sim_options["environment"]
    model = scene.dynamics("plant").model
    dyn = armctl.Dynamics(model)
    end: dict[str, float] = {}

    def ours(compile: bool | str) -> Callable[[], float]:
        def run() -> float:
            chosen = choose_step(dyn, "rk4", Plant(dyn, StickSlip(model), (plane,)), compile)
            pl, step = chosen.plant, chosen.step
            q, v = Q_HOME.copy(), np.zeros(model.n)
            t0 = time.perf_counter()
            for k, tau in enumerate(torques):
                t = k * scene.control_dt
                pl.begin(t, q, v, tau)
                for s in range(m_sub):
                    q, v, _, _, _ = advance(pl, step, t + s * h, q, v, tau, h, begun=s == 0)
            wall = time.perf_counter() - t0
            end[str(compile)] = float(np.abs(q - res.q[-1]).max())
            return wall

        return run

    contact = cast(ContactScene, scene)
    m, d = mujoco_loops.contact_model(model, contact.z_table, contact.mu, h)
    touching = [0]

    def mujoco() -> float:
        wall, touching[0] = mujoco_loops.replay(m, d, torques, Q_HOME, m_sub)
        return wall

    samples = _rounds({"generated": ours("auto"), "mujoco": mujoco}, rounds)
    python = _rounds({"python": ours(False), "mujoco": mujoco}, 1)
    steps = len(torques) * m_sub
    return {
        "steps": steps,
        "dt": h,
        "us_per_step": 1e6 * statistics.median(samples["generated"]) / steps,
        "mujoco_us_per_step": 1e6 * statistics.median(samples["mujoco"]) / steps,
        "ratio_to_mujoco": _ratios(samples, "mujoco")["generated"],
        "python_ratio_to_mujoco": _ratios(python, "mujoco")["python"],
        "replay_matches_run_rad": max(end.values()),
        "mujoco_periods_in_contact": touching[0],
        "periods": len(torques),
    }


# ---------------------------------------------------------------------------------------- report, checks
def report(fig: dict[str, Any]) -> str:
    lines = []
    if "panda" in fig:
        p = fig["panda"]
        lines.append(
            f"Panda, computed torque at 1 kHz, stick-slip friction (viscous {FRICTION['viscous']}, Coulomb "
            f"{FRICTION['coulomb']}, static {FRICTION['static']}), {p['duration_s']:g} s; the whole simulate call per "
            "control step, ratio to MuJoCo's Python loop (implicitfast, damping + frictionloss, same controller)"
        )
        for name, f in p["modes"].items():
            loop = f" (the loop alone {f['loop_ratio_to_mujoco']:.2f}×)" if name != "mujoco" else " " * 23
            lines.append(
                f"  {name:<34} {f['us_per_step']:7.1f} µs/step  {f['ratio_to_mujoco']:5.2f}×{loop}  "
                f"tracking RMS {f['rms_error_rad']:.3g} rad"
            )
        lines.append(f"  semi-implicit Euler / RK4 (both generated): {p['semi_implicit_over_rk4']:.2f}")
    if "chains" in fig:
        lines.append("Planar chains, 1 kg links, stick-slip friction, computed torque: default simulate against MuJoCo")
        for n, f in fig["chains"].items():
            lines.append(
                f"  N = {n:>2}  {f['us_per_step']:7.1f} µs/step  MuJoCo {f['mujoco_us_per_step']:6.1f}  "
                f"{f['ratio_to_mujoco']:5.2f}×  ({f['stick_events']} stops, {f['breakaway_events']} breakaways)"
            )
    if "sticking_chains" in fig:
        lines.append(
            f"Planar chains with static friction {STICK_PER_INERTIA:g}·M_ii (joints stick at every size): default "
            "simulate against MuJoCo"
        )
        for n, f in fig["sticking_chains"].items():
            lines.append(
                f"  N = {n:>2}  {f['us_per_step']:7.1f} µs/step  MuJoCo {f['mujoco_us_per_step']:6.1f}  "
                f"{f['ratio_to_mujoco']:5.2f}×  ({f['stick_events']} stops, {f['breakaway_events']} breakaways, "
                f"{100 * f['stuck_fraction']:.0f} % of joint-samples stuck, up to {f['most_stuck']} at once)"
            )
    if "contact" in fig:
        c = fig["contact"]
        lines.append(
            f"panda_contact, the plant alone at {c['dt'] * 1e3:g} ms steps ({c['steps']} steps replaying one run's "
            f"torques): {c['us_per_step']:.2f} µs/step, MuJoCo's plant {c['mujoco_us_per_step']:.2f}: "
            f"{c['ratio_to_mujoco']:.2f}× (the Python step {c['python_ratio_to_mujoco']:.1f}×)"
        )
    if "contact_loop" in fig:
        from armctl.bench import contact_loop

        lines.append(contact_loop.report(fig["contact_loop"]))
    if fig.get("sweep"):
        s = fig["sweep"]
        dask = f", Dask LocalCluster {s['dask_s']:.1f} s: ×{s['dask_speedup']:.2f}" if "dask_s" in s else ""
        lines.append(
            f"Sweep of {s['runs']} × {s['duration_s']:g} s Panda runs (objects in the cases): serial "
            f"{s['serial_s']:.1f} s, process pool of {s['workers']} {s['pool_s']:.1f} s: "
            f"×{s['pool_speedup']:.2f}{dask}; "
            f"the machine's ceiling ×{s['ceiling']['ceiling']:.2f} (1-min load {min(s['load_average_1min']):.1f}–"
            f"{max(s['load_average_1min']):.1f})"
        )
    return "\n".join(lines)


def checks(fig: dict[str, Any]) -> dict[str, bool]:
    """Each target of :data:`TARGETS` against the figures that measure it (absent sections are not checked)."""
    out: dict[str, bool] = {}
    if "panda" in fig:
        p = fig["panda"]
        out[f"Panda default / MuJoCo <= {TARGETS['panda_ratio']}"] = (
            p["modes"]["default"]["ratio_to_mujoco"] <= TARGETS["panda_ratio"]
        )
        out[f"semi-implicit Euler / RK4 <= {TARGETS['semi_implicit_over_rk4']}"] = (
            p["semi_implicit_over_rk4"] <= TARGETS["semi_implicit_over_rk4"]
        )
    for n, f in fig.get("chains", {}).items():
        out[f"chain N = {n} / MuJoCo <= {TARGETS['chain_ratio']}"] = f["ratio_to_mujoco"] <= TARGETS["chain_ratio"]
    for n, f in fig.get("sticking_chains", {}).items():
        out[f"sticking chain N = {n} / MuJoCo <= {TARGETS['sticking_chain_ratio']}"] = (
            f["ratio_to_mujoco"] <= TARGETS["sticking_chain_ratio"]
        )
    if "contact" in fig:
        out[f"contact plant / MuJoCo's <= {TARGETS['contact_plant_ratio']}"] = (
            fig["contact"]["ratio_to_mujoco"] <= TARGETS["contact_plant_ratio"]
        )
    if "contact_loop" in fig:
        out[f"contact loop / MuJoCo's loop <= {TARGETS['contact_loop_ratio']}"] = (
            fig["contact_loop"]["ratio_to_mujoco"] <= TARGETS["contact_loop_ratio"]
        )
    if fig.get("sweep"):
        s = fig["sweep"]
        out[f"pool speed-up >= {TARGETS['pool_speedup']}"] = s["pool_speedup"] >= TARGETS["pool_speedup"]
        if "dask_speedup" in s:
            out[f"Dask speed-up >= {TARGETS['dask_speedup']}"] = s["dask_speedup"] >= TARGETS["dask_speedup"]
    return out


def beyond_targets(fig: dict[str, Any]) -> list[str]:
    """The checks of :func:`checks` that fail (the benchmark's tests call this; the bench does not print it)."""
    return [name for name, ok in checks(fig).items() if not ok]


def run(quick: bool = False, sweep: bool = True) -> dict[str, Any]:
    fig: dict[str, Any] = {}
    fig["panda"] = panda_figures(2.0 if quick else 10.0, 1 if quick else 3)
    print(report(fig), flush=True)
    fig["chains"] = chain_figures(duration=1.0 if quick else 2.0, rounds=1 if quick else 3)
    print("\n".join(report({"chains": fig["chains"]}).splitlines()), flush=True)
    fig["sticking_chains"] = chain_figures(duration=1.0 if quick else 2.0, rounds=1 if quick else 3, sticking=True)
    print(report({"sticking_chains": fig["sticking_chains"]}), flush=True)
    fig["contact"] = contact_figures(1 if quick else 3)
    print(report({"contact": fig["contact"]}), flush=True)
    from armctl.bench import contact_loop

    fig["contact_loop"] = contact_loop.figures(1 if quick else 3, 0.6 if quick else None)
    print(report({"contact_loop": fig["contact_loop"]}), flush=True)
    if sweep:
        from armctl.bench import sweep_speed

        fig["sweep"] = sweep_speed.figures(20 if quick else 100, 1.0 if quick else 3.0)
        print(report({"sweep": fig["sweep"]}), flush=True)
    return fig


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="shorter runs, one round, a 20-run sweep")
    parser.add_argument("--no-sweep", action="store_true", help="skip the sweeps")
    parser.add_argument("--json", help="also write the figures to this file")
    args = parser.parse_args(argv)
    fig = run(args.quick, not args.no_sweep)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(fig, fh, indent=2, default=float)
    return fig


if __name__ == "__main__":
    main()
