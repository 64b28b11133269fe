"""Speed of the closed-loop simulator, against MuJoCo stepping the same arm from a Python loop.

Run: ``python -m armctl.bench.sim_speed [--quick] [--runs N] [--workers W]``. Prints:

* Panda (7 joints), a computed-torque controller at 1 kHz tracking a joint-space sine, 1 ms steps, 10 s of
  simulated time: armctl's real-time factor and cost per control step for RK4 (the default) and the
  cheapest scheme ("euler"), each with the step in Python (calling Pinocchio's ABA) and compiled
  (``compile=True``: C code generated for the plant, :mod:`armctl.sim.compiled`); and the same closed loop
  with MuJoCo stepping the Panda (loaded from the same URDF, RK4 at 1 ms) from a Python loop — same
  controller, same reference — plus MuJoCo's bare ``mj_step`` loop.
  Medians over interleaved rounds, so that a busy shared machine slows both alike.
* A sweep of ``--runs`` (default 200) 5 s planar_2r scenes (PD + gravity compensation with different gains,
  stick–slip joint friction) through a process pool of ``--workers`` (default 2) against the same runs
  one after the other; the speed-up.

:data:`TARGETS` are the benchmark's own checks (its tests use them); they are not printed.
"""

from __future__ import annotations

import argparse
import functools
import math
import re
import statistics
import time
from typing import Any

import numpy as np

import armctl
from armctl.controllers import ComputedTorque, PDGravity
from armctl.references import Reference
from armctl.sim import simulate, sweep

TARGETS = {"real_time_factor": 30.0, "ratio_to_mujoco": 2.0, "sweep_speedup": 1.7}
#: the simulator configurations timed: name → (integrator, compile)
VARIANTS = {
    "rk4": ("rk4", False),
    "rk4_compiled": ("rk4", True),
    "euler": ("euler", False),
    "euler_compiled": ("euler", True),
}


class SampledSine:
    """q_r(t) = q0 + a sin(ω t), precomputed at the control instants (a table lookup per call)."""

    def __init__(self, q0: np.ndarray, amplitude: float, omega: float, period: float, duration: float) -> None:
        n_samples = round(duration / period) + 1
        self.period = period
        self.table = []
        for k in range(n_samples):
            t = k * period
            s, c = math.sin(omega * t), math.cos(omega * t)
            self.table.append(
                Reference(
                    q0 + amplitude * s,
                    np.full(len(q0), amplitude * omega * c),
                    np.full(len(q0), -amplitude * omega**2 * s),
                )
            )

    def __call__(self, t: float) -> Reference:
        return self.table[min(round(t / self.period), len(self.table) - 1)]


def panda_mujoco() -> tuple[Any, Any]:
    """The Panda in MuJoCo from the same URDF: meshes stripped, fingers fixed, no damping, armature,
    limits or contacts; RK4 at 1 ms."""
    import mujoco

    text = armctl.models.robot_description("panda_description/urdf/panda.urdf").read_text()
    for tag in ("visual", "collision"):
        text = re.sub(rf"<{tag}>.*?</{tag}>", "", text, flags=re.S)
    text = re.sub(r"<dynamics[^>]*/>", "", text)
    text = re.sub(r'(<joint name="panda_finger_joint[12]"[^>]*type=)"prismatic"', r'\1"fixed"', text)
    text = re.sub(
        r"(<robot[^>]*>)",
        r'\1<mujoco><compiler discardvisual="true" fusestatic="false" '
        r'balanceinertia="false"/></mujoco>',
        text,
        count=1,
    )
    m = mujoco.MjModel.from_xml_string(text)
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT) | int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    m.dof_damping[:] = 0.0
    m.dof_armature[:] = 0.0
    m.dof_frictionloss[:] = 0.0
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    m.opt.timestep = 1e-3
    if m.nv != 7:
        raise RuntimeError(f"expected the 7 Panda arm joints in MuJoCo, got {m.nv}")
    return m, mujoco.MjData(m)


def mujoco_loop(m: Any, d: Any, controller: Any, reference: Any, q0: np.ndarray, steps: int) -> float:
    """Seconds for ``steps`` closed-loop steps: read the state, control, apply, mj_step."""
    import mujoco

    d.qpos[:] = q0
    d.qvel[:] = 0.0
    mujoco.mj_forward(m, d)
    step, qpos, qvel, qfrc = mujoco.mj_step, d.qpos, d.qvel, d.qfrc_applied
    t0 = time.perf_counter()
    for k in range(steps):
        t = k * 1e-3
        qfrc[:] = controller(t, qpos.copy(), qvel.copy(), reference(t))
        step(m, d)
    return time.perf_counter() - t0


def mujoco_bare(m: Any, d: Any, q0: np.ndarray, steps: int) -> float:
    import mujoco

    d.qpos[:] = q0
    d.qvel[:] = 0.0
    step = mujoco.mj_step
    t0 = time.perf_counter()
    for _ in range(steps):
        step(m, d)
    return time.perf_counter() - t0


def panda_figures(duration: float = 10.0, rounds: int = 3) -> dict[str, Any]:
    model = armctl.models.panda()
    dyn = armctl.Dynamics(model)
    q0 = np.array([0.0, -0.4, 0.0, -2.0, 0.0, 1.6, 0.8])
    ref = SampledSine(q0, 0.3, 2.0, 1e-3, duration)
    ctrl = ComputedTorque(armctl.Dynamics(model), 400.0, 40.0)
    steps = round(duration / 1e-3)
    out: dict[str, Any] = {"controller": "armctl.controllers.ComputedTorque", "steps": steps, "duration_s": duration}
    try:
        m, d = panda_mujoco()
    except ImportError:
        m = d = None
    samples: dict[str, list[float]] = {name: [] for name in (*VARIANTS, "mujoco_closed_loop", "mujoco_bare")}
    error = {}
    t0 = time.perf_counter()
    for integ in ("rk4", "euler"):  # build (or load) the compiled steps before any timing
        simulate(dyn, ctrl, ref, 1e-3, q0=q0, integrator=integ, compile=True)
    out["compile_or_load_s"] = time.perf_counter() - t0
    for _ in range(rounds):
        for name, (integ, comp) in VARIANTS.items():
            t0 = time.perf_counter()  # the whole call: checks, loading the compiled step, loop, energies, result
            res = simulate(dyn, ctrl, ref, duration, q0=q0, integrator=integ, compile=comp)
            samples[name].append(time.perf_counter() - t0)
            error[name] = float(np.abs(res.q[-1] - ref(duration).q).max())
        if m is not None:
            samples["mujoco_closed_loop"].append(mujoco_loop(m, d, ctrl, ref, q0, steps))
            samples["mujoco_bare"].append(mujoco_bare(m, d, q0, steps))
    for name, vals in samples.items():
        if vals:
            wall = statistics.median(vals)
            out[name] = {"wall_s": wall, "us_per_step": 1e6 * wall / steps, "real_time_factor": duration / wall}
    out["final_tracking_error_rad"] = error
    if "mujoco_closed_loop" in out:
        base = out["mujoco_closed_loop"]["us_per_step"]
        for name in VARIANTS:
            out[name]["ratio_to_mujoco"] = out[name]["us_per_step"] / base
    return out


@functools.cache
def _sine_table(q0: tuple[float, ...], amplitude: float, omega: float) -> SampledSine:
    return SampledSine(np.array(q0), amplitude, omega, period=1e-3, duration=5.0)


class SweepSine:
    """q_r(t) = q0 + a sin(ω t) at the 1 kHz control instants of a 5 s run, tabulated once per process on
    first use (so serial and pooled sweeps pay for it alike, and the table is not pickled)."""

    def __init__(self, q0: list[float], amplitude: float, omega: float) -> None:
        self.args = (tuple(float(x) for x in q0), float(amplitude), float(omega))

    def __call__(self, t: float) -> Reference:
        return _sine_table(*self.args)(t)


def rms_error(res: Any) -> float:
    """Summary returned by each sweep run (run in the worker)."""
    return float(np.sqrt(np.mean(res.q_measured[:, 0] ** 2))) if res.diverged else float(res.q[-1, 0])


def sweep_cases(runs: int) -> list[dict[str, Any]]:
    from armctl.bench import sim_speed as me  # pickled by their importable name, also under "python -m"

    model = armctl.models.planar_2r().with_friction(viscous=10.0, coulomb=30.0, static=40.0)
    ctrl_model = model.reduced(friction=False)
    ref = me.SweepSine([0.3, -0.5], 0.4, 1.5)
    gains = np.geomspace(500.0, 5e4, runs)
    return [
        {
            "plant": model,
            "controller": PDGravity(armctl.Dynamics(ctrl_model), kp, 2 * math.sqrt(kp * 250.0)),
            "reference": ref,
            "duration": 5.0,
        }
        for kp in gains
    ]


def sweep_figures(runs: int = 200, workers: int = 2, blocks: int = 4) -> dict[str, Any]:
    """Pooled and serial sweeps of the same runs, in alternating blocks (pool, serial, pool, …) so that a
    change in the load of a shared machine hits both alike. The pooled blocks share one process pool, as one
    200-run sweep would: its workers start (and import armctl, ~1 s) inside the first pooled block's timing.
    Also the CPU time the work took each way (the workers' from ``getrusage``), whose ratio is the speed-up an
    otherwise idle machine would give at best, and the machine's load average."""
    import os
    import resource
    from concurrent.futures import ProcessPoolExecutor

    from armctl.bench import sim_speed as me

    cases = sweep_cases(runs)
    chunks = [cases[i::blocks] for i in range(blocks)]
    t_pool = t_serial = cpu_serial = 0.0
    pooled: list[float] = []
    serial: list[float] = []
    load = [os.getloadavg()[0]]
    children0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    pool = ProcessPoolExecutor(workers)  # processes start on the first submit, inside the first block's timing
    try:
        for chunk in chunks:
            t0 = time.perf_counter()
            pooled += sweep(chunk, summary=me.rms_error, executor=pool, progress=True, on_error="raise")
            t_pool += time.perf_counter() - t0
            t0, c0 = time.perf_counter(), time.process_time()
            serial += sweep(chunk, summary=me.rms_error, executor="serial", progress=True, on_error="raise")
            t_serial += time.perf_counter() - t0
            cpu_serial += time.process_time() - c0
            load.append(os.getloadavg()[0])
    finally:
        t0 = time.perf_counter()
        pool.shutdown(wait=True)
        t_pool += time.perf_counter() - t0
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu_pool = (children.ru_utime - children0.ru_utime) + (children.ru_stime - children0.ru_stime)
    if pooled != serial:
        raise RuntimeError("pooled and serial sweeps disagree")
    return {
        "runs": runs,
        "workers": workers,
        "serial_s": t_serial,
        "pool_s": t_pool,
        "speedup": t_serial / t_pool,
        "s_per_run_serial": t_serial / runs,
        "cpu_serial_s": cpu_serial,
        "cpu_pool_workers_s": cpu_pool,
        "idle_machine_speedup_bound": workers * cpu_serial / cpu_pool if cpu_pool > 0 else math.nan,
        "load_average_1min": load,
    }


def _serial_block(runs: int) -> None:
    """Run ``runs`` sweep cases one after the other in this process (for :func:`parallel_ceiling`)."""
    for case in sweep_cases(runs):
        simulate(**case)


def parallel_ceiling(runs: int = 12, workers: int = 2, rounds: int = 2) -> dict[str, Any]:
    """The machine's own limit on the sweep's speed-up, without any pool: the same block of runs in
    independent Python processes, one alone and then ``workers`` at once (each doing the whole block).
    ceiling = workers × t_alone / t_together: what perfect parallel code could reach on this machine now."""
    import subprocess
    import sys

    cmd = [sys.executable, "-c", f"from armctl.bench.sim_speed import _serial_block; _serial_block({runs})"]
    subprocess.run(cmd, check=True)  # warm the file cache
    alone: list[float] = []
    together: list[float] = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True)
        alone.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        procs = [subprocess.Popen(cmd) for _ in range(workers)]
        if any(p.wait() != 0 for p in procs):
            raise RuntimeError("a block of the parallel-ceiling measurement failed")
        together.append(time.perf_counter() - t0)
    t_alone, t_together = statistics.median(alone), statistics.median(together)
    return {
        "runs": runs,
        "workers": workers,
        "alone_s": t_alone,
        "together_s": t_together,
        "ceiling": workers * t_alone / t_together,
    }


def report(panda: dict[str, Any], sw: dict[str, Any] | None) -> str:
    lines = [
        f"Panda, {panda['controller']} at 1 kHz, 1 ms steps, {panda['duration_s']:g} s "
        f"({panda['steps']} steps); medians of interleaved rounds"
    ]
    for name in (*VARIANTS, "mujoco_closed_loop", "mujoco_bare"):
        if name in panda:
            f = panda[name]
            extra = f", {f['ratio_to_mujoco']:.2f}× the MuJoCo closed loop" if "ratio_to_mujoco" in f else ""
            lines.append(
                f"  {name:<20} {f['us_per_step']:7.1f} µs/step  real-time ×{f['real_time_factor']:6.1f}{extra}"
            )
    if sw is not None:
        lines.append(
            f"Sweep of {sw['runs']} × 5 s planar_2r runs: serial {sw['serial_s']:.1f} s, process pool of "
            f"{sw['workers']} {sw['pool_s']:.1f} s: speed-up ×{sw['speedup']:.2f}; 1-min load average during the sweep "
            f"{min(sw['load_average_1min']):.1f}–{max(sw['load_average_1min']):.1f} on "
            f"{__import__('os').cpu_count()} CPUs; CPU time serial {sw['cpu_serial_s']:.1f} s, pool "
            f"workers {sw['cpu_pool_workers_s']:.1f} s: on an idle machine at most "
            f"×{sw['idle_machine_speedup_bound']:.2f}"
        )
        ceil = sw.get("parallel_ceiling")
        if ceil is not None:
            lines.append(
                f"  machine ceiling: {ceil['runs']} runs in {ceil['workers']} independent processes at once "
                f"{ceil['together_s']:.1f} s vs one alone {ceil['alone_s']:.1f} s: no code can exceed "
                f"×{ceil['ceiling']:.2f} here now"
            )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="2 s Panda runs, one round, a 20-run sweep")
    parser.add_argument("--runs", type=int, default=None, help="sweep runs (default 200; 20 with --quick)")
    parser.add_argument("--workers", type=int, default=2, help="process pool size (default 2)")
    parser.add_argument("--no-sweep", action="store_true", help="skip the sweep")
    args = parser.parse_args(argv)
    panda = panda_figures(2.0 if args.quick else 10.0, 1 if args.quick else 3)
    print(report(panda, None), flush=True)
    sw = None
    if not args.no_sweep:
        sw = sweep_figures(args.runs or (20 if args.quick else 200), args.workers)
        sw["parallel_ceiling"] = parallel_ceiling(4 if args.quick else 12, args.workers, 1 if args.quick else 2)
        print("\n".join(report(panda, sw).splitlines()[-2:]))
    return {"panda": panda, "sweep": sw}


if __name__ == "__main__":
    main()
