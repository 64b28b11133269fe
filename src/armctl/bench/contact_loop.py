"""The whole ``panda_contact`` loop — the plant and the scene's own controller — against MuJoCo's loop with the same
controller (a section of :mod:`armctl.bench.sim_speed`).

armctl's loop is ``simulate`` of the scene's ``osc_qp`` method (:class:`~armctl.scenes.panda_contact.PressAndSlide`:
the OSC QP with a sliding contact switched on at the touch, a normal force ramped to 10 N, a slide of 10 cm) on the
scene's plant (the Panda with joint friction on a Kelvin–Voigt table with Coulomb sliding, 0.2 ms steps, 5 a
control period), timed as ``res.info["wall_time"]`` (the loop, without the checks before it and the result's
assembly after it). MuJoCo's is :func:`armctl.bench.mujoco_loops.closed_loop` with the same controller object on
:func:`~armctl.bench.mujoco_loops.contact_model` (a 5 mm sphere at the tool on a plane at the table's height, friction
μ, ``implicitfast`` at 0.2 ms, 5 steps a control period). Both loops call the controller at every control period; the
controller's cost is alike in both only as far as the runs touch the table alike (the periods in contact are given).

The figure is the ratio of the loops, (plant + controller) / (MuJoCo's plant + controller), the median over
interleaved rounds; beside it the controller alone (replayed on armctl's run in each round), which bounds what any
plant can reach: controller / (MuJoCo's loop), the median of the rounds' ratios.
"""

from __future__ import annotations

import statistics
import time
from typing import Any, cast


def figures(rounds: int = 3, duration: float | None = None) -> dict[str, Any]:
    """The loops' figures (see the module), over ``rounds`` interleaved rounds of runs of ``duration`` [s] (None:
    the scene's)."""
    from armctl.bench import mujoco_loops
    from armctl.scenes.panda_contact import Q_HOME, ContactScene, PressAndSlide, panda_contact
    from armctl.sim import simulate
    from armctl.sim.options import regroup

    scene = cast(ContactScene, panda_contact())
    controller = cast(PressAndSlide, scene.controller("osc_qp"))
    plant = scene.dynamics("plant")
    duration = scene.duration if duration is None else duration
    options = regroup({"control_dt": scene.control_dt, "dt": scene.dt, "q0": Q_HOME, **scene.sim_options})
    h = scene.dt if scene.dt is not None else scene.control_dt  # (the scene's: 0.2 ms)
    periods = round(duration / scene.control_dt)
    substeps = round(scene.control_dt / h)
    m, d = mujoco_loops.contact_model(plant.model, scene.z_table, scene.mu, h)
    seen: dict[str, Any] = {}

    def ours() -> float:
        res = simulate(plant, controller, scene.reference, duration, **options)
        seen["run"], seen["touched"] = res, controller.touched
        return float(res.info["wall_time"])

    def mujoco() -> float:
        controller.reset()
        wall, _ = mujoco_loops.closed_loop(
            m, d, controller, scene.reference, Q_HOME, periods, scene.control_dt, substeps=substeps
        )
        seen["mujoco_touched"] = controller.touched
        return wall

    def alone() -> float:  # the controller on armctl's last run (its states and times), after a reset
        res, call = seen["run"], controller.compute
        controller.reset()
        t0 = time.perf_counter()
        for k in range(periods):
            call(k * scene.control_dt, res.q[k], res.qd[k], scene.reference(k * scene.control_dt))
        return time.perf_counter() - t0

    samples: dict[str, list[float]] = {"armctl": [], "mujoco": [], "controller": []}
    ours(), mujoco()  # warm-up
    for _ in range(rounds):
        samples["armctl"].append(ours())
        samples["mujoco"].append(mujoco())
        samples["controller"].append(alone())
    res = seen["run"]
    mj = samples["mujoco"]
    ratio = statistics.median(a / b for a, b in zip(samples["armctl"], mj, strict=True))
    bound = statistics.median(a / b for a, b in zip(samples["controller"], mj, strict=True))
    ours_s, mj_s, ctrl = (statistics.median(samples[k]) for k in ("armctl", "mujoco", "controller"))
    return {
        "periods": periods,
        "substeps": substeps,
        "dt": h,
        "us_per_period": 1e6 * ours_s / periods,
        "mujoco_us_per_period": 1e6 * mj_s / periods,
        "controller_us_per_period": 1e6 * ctrl / periods,
        "ratio_to_mujoco": ratio,
        "controller_bound": bound,
        "touched_s": seen["touched"],
        "mujoco_touched_s": seen["mujoco_touched"],
        "compiled": bool(res.info["compiled"]),
    }


def report(f: dict[str, Any]) -> str:
    """One line of the figures."""
    return (
        f"panda_contact, the whole loop (plant + the scene's osc_qp controller, {f['periods']} control periods of "
        f"{f['substeps']} × {f['dt'] * 1e3:g} ms): {f['us_per_period']:.1f} µs/period, MuJoCo's loop with the same "
        f"controller {f['mujoco_us_per_period']:.1f}: {f['ratio_to_mujoco']:.2f}×; the controller alone "
        f"{f['controller_us_per_period']:.1f} µs/period, {f['controller_bound']:.2f}× MuJoCo's loop (touching the "
        f"table at {_t(f['touched_s'])} s, in MuJoCo at {_t(f['mujoco_touched_s'])} s)"
    )


def _t(value: float | None) -> str:
    return "never" if value is None else f"{value:.3f}"
