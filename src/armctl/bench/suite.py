"""``armctl bench``: every scene × controller, stability maps, TOPP convergence, the dynamics backends', the
integrators' and the models' cost against accuracy — written to ``figures.json`` (every number behind the
charts), PNG charts and ``report.html``, with a summary table printed.

Sections run in turn; the simulation-heavy ones go through an ``Executor`` (a process pool by default).
``quick`` shrinks grids and repetitions so the whole run takes 1–2 minutes on 2 cores.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from concurrent.futures import Executor
from pathlib import Path
from typing import Any

import numpy as np

SCENE_NAMES = ("pendulum", "planar_2r", "panda_topp", "panda_contact")


#: the measures of a scene row, NaN in the row of a method that failed
_MEASURES = (
    "rms_error",
    "max_error",
    "torque_rms",
    "compute_s",
    "limit_violation_share",
    "torque_violation_share",
    "velocity_violation_share",
    "position_violation_share",
)


def run_scene_method(scene: str, method: str) -> dict[str, Any]:
    """Simulate one method on one scene (runs in a worker process): its metrics, untimed, and the window of
    recorded states that :func:`time_controllers` replays to time it. A method that fails — its controller
    raises an :class:`~armctl.errors.ArmctlError` (an infeasible QP, say), or the scene cannot be built (a plan
    its limits refuse) — is a result too: a row with ``failed`` (the error's type and message) and NaN
    measures, so the rest of the benchmark still runs and shows it."""
    from armctl.errors import ArmctlError
    from armctl.scenes import scene as make

    try:
        sc = make(scene)
        res = sc.run(method)
    except ArmctlError as exc:
        return _failed_row(scene, method, exc)
    return {
        "scene": scene,
        "method": method,
        **sc.metrics(res, method, timing_rounds=0),
        "window": sc.replay_window(res, sc.timing_samples),
    }


def _failed_row(scene: str, method: str, exc: Exception) -> dict[str, Any]:
    """The row of a method (or, as method "(scene)", a whole scene) that failed with ``exc``."""
    return {
        "scene": scene,
        "method": method,
        **dict.fromkeys(_MEASURES, float("nan")),
        "diverged": False,
        "diverged_at": None,
        "failed": f"{type(exc).__name__}: {exc}",
        "window": {"t": [], "q": np.zeros((0, 0)), "qd": np.zeros((0, 0)), "ref": []},
    }


def time_controllers(rows: list[dict[str, Any]], rounds: int) -> None:
    """Replace each row's ``compute_s`` by a figure measured in this process once every simulation is done
    (in a worker it ran beside another simulation on a 2-core machine, and one pass swung ×5 from run to
    run): per scene, every method's controller replays its window in interleaved rounds (one warm-up
    round), and ``compute_s`` is the median, with its quartiles in ``compute_s_iqr``."""
    from armctl._checks import whole_number
    from armctl.scenes import scene as make
    from armctl.scenes.base import replay_times

    rounds = whole_number(rounds, "rounds", 1)
    for r in rows:
        if not len(r["window"]["t"]):  # a run without samples: nothing to replay
            r["compute_s"], r["compute_s_iqr"] = float("nan"), [float("nan"), float("nan")]
            r["compute_timing"] = "no recorded steps to replay"
    for name in dict.fromkeys(r["scene"] for r in rows if len(r["window"]["t"])):
        sc = make(name)
        mine = [r for r in rows if r["scene"] == name and len(r["window"]["t"])]
        ctrls = [sc.controller(r["method"]) for r in mine]
        times: list[list[float]] = [[] for _ in mine]
        for _ in range(rounds + 1):
            for ctrl, r, out in zip(ctrls, mine, times, strict=True):
                out += replay_times(ctrl, r["window"], 1)
        for r, out in zip(mine, times, strict=True):
            q1, med, q3 = np.quantile(out[1:], [0.25, 0.5, 0.75])
            r["compute_s"], r["compute_s_iqr"] = float(med), [float(q1), float(q3)]
            r["compute_timing"] = f"median of {rounds} interleaved replays of {len(r['window']['t'])} recorded steps"
    for r in rows:
        del r["window"]


def scene_matrix(executor: Executor | str | None = None, rounds: int = 9) -> list[dict[str, Any]]:
    from armctl.errors import ArmctlError
    from armctl.scenes import SCENES, scene
    from armctl.sim import sweep

    cases, unbuilt = [], []
    for name in SCENE_NAMES:
        if name not in SCENES:
            continue
        try:
            methods = scene(name).methods
        except ArmctlError as exc:  # the scene itself cannot be built: one failed row stands for it
            unbuilt.append(_failed_row(name, "(scene)", exc))
            continue
        cases += [{"scene": name, "method": m} for m in methods]
    rows = sweep(cases, run=run_scene_method, executor=executor, progress=True, on_error="raise") + unbuilt
    time_controllers(rows, rounds)
    return rows


def pareto_front(points: list[tuple[float, float]], spans: list[tuple[float, float]] | None = None) -> list[int]:
    """Indices of the points (x, y) no other point beats (both minimised; non-finite points are never on it).

    ``spans``: an interval (lo, hi) around each x — the quartiles of a noisy timing. Then x is compared by
    the intervals: j is faster than i only if hi_j < lo_i, and overlapping intervals are a tie, so timing noise
    alone cannot move a point on or off the front. j beats i if it is faster and no less accurate, or tied and
    more accurate. Without spans this is the usual strict Pareto order."""
    spans = (
        [(x, x) for x, _ in points]
        if spans is None
        else [
            (lo, hi) if math.isfinite(lo) and math.isfinite(hi) else (x, x)  # no quartiles: the point itself
            for (x, _), (lo, hi) in zip(points, spans, strict=True)
        ]
    )
    finite = [math.isfinite(x) and math.isfinite(y) for x, y in points]

    def beats(j: int, i: int) -> bool:
        (lo_i, hi_i), (lo_j, hi_j) = spans[i], spans[j]
        yi, yj = points[i][1], points[j][1]
        faster, slower = hi_j < lo_i, hi_i < lo_j
        return (faster and yj <= yi) or (not faster and not slower and yj < yi)

    return [
        i
        for i in range(len(points))
        if finite[i] and not any(finite[j] and beats(j, i) for j in range(len(points)) if j != i)
    ]


def _failure_note(r: dict[str, Any], brief: bool = True) -> str | None:
    """How a method failed on its scene, or None: the error's type (``brief``, for a chart) or its whole text."""
    if r.get("failed"):
        return f"failed: {r['failed'].split(':')[0]}" if brief else f"FAILED ({r['failed']})"
    if r["diverged"]:
        return f"diverged at {r['diverged_at']:.2f} s"
    return None


def plot_pareto(rows: list[dict[str, Any]], path: Path) -> None:
    """Tracking error against compute time per step, log-log, one panel per scene: the quartiles of the
    timing as horizontal bars, the Pareto front (:func:`pareto_front` on those quartiles) marked, and every
    method that diverged or failed listed in its panel (a cross at the top where its time is known)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from armctl.bench.report import plain_log_ticks

    scenes = [s for s in SCENE_NAMES if any(r["scene"] == s for r in rows)]
    fig, axes = plt.subplots(1, len(scenes), figsize=(4.6 * len(scenes), 4.0), squeeze=False)
    for ax, name in zip(axes[0], scenes, strict=True):
        mine = [r for r in rows if r["scene"] == name and _failure_note(r) is None]
        pts = [(r["compute_s"] * 1e6, r["rms_error"]) for r in mine]
        spans = [tuple(1e6 * v for v in r.get("compute_s_iqr", (r["compute_s"],) * 2)) for r in mine]
        front = set(pareto_front(pts, spans))  # type: ignore[arg-type]
        placed: list[tuple[float, float]] = []
        for i, (r, (x, y), (lo, hi)) in enumerate(zip(mine, pts, spans, strict=True)):
            color = "#d62828" if i in front else "#577590"
            ax.errorbar(
                x,
                y,
                xerr=[[max(x - lo, 0.0)], [max(hi - x, 0.0)]],
                fmt="o",
                ms=7,
                color=color,
                zorder=3,
                capsize=2,
                lw=1,
            )
            # a label near an earlier one's point (in decades) goes one line lower for each such neighbour
            near = sum(
                1
                for px, py in placed
                if x > 0 and y > 0 and abs(math.log10(x / px)) < 0.25 and abs(math.log10(y / py)) < 0.25
            )
            placed.append((x, y))
            ax.annotate(
                r["method"].replace("_", " "), (x, y), fontsize=7, xytext=(4, 3 - 10 * near), textcoords="offset points"
            )
        fx = sorted(pts[i] for i in front)
        if fx:
            ax.plot(*zip(*fx, strict=True), color="#d62828", lw=1, label="Pareto front")
        failed = [(r, note) for r in rows if r["scene"] == name and (note := _failure_note(r)) is not None]
        for r, _ in failed:
            if math.isfinite(r["compute_s"]):
                ax.plot(
                    r["compute_s"] * 1e6,
                    0.97,
                    "x",
                    color="#d62828",
                    ms=9,
                    mew=2,
                    transform=ax.get_xaxis_transform(),
                    clip_on=False,
                    zorder=4,
                )
        if failed:  # under the axis label, where no point can sit
            ax.text(
                0.0,
                -0.2,
                "\n".join(f"✕ {r['method'].replace('_', ' ')}: {note}" for r, note in failed),
                transform=ax.transAxes,
                fontsize=7,
                color="#d62828",
                va="top",
            )
        ax.margins(x=0.15, y=0.25)
        ax.set(
            xscale="log",
            yscale="log",
            xlabel="compute time per control step [µs]",
            ylabel="RMS tracking error [rad]" if name != "panda_contact" else "RMS tool position error [m]",
            title=name,
        )
        plain_log_ticks(ax)
        if fx:
            ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def topp_convergence(quick: bool) -> dict[str, Any]:
    import armctl
    from armctl.planning import grid_convergence

    dyn = armctl.Dynamics(armctl.models.planar_2r())
    grids = (10, 20, 50, 100, 200) if quick else (10, 20, 50, 100, 200, 500, 1000)
    study = grid_convergence(
        dyn, [0.0, 0.0], [1.0, -0.8], [1.0, 1.5], [3.0, 4.0], grids=grids, repeat=1 if quick else 3
    )
    return {
        "grids": study.grids.tolist(),
        "durations": study.durations.tolist(),
        "errors": study.errors.tolist(),
        "compute_s": study.compute_times.tolist(),
        "analytic_duration": study.reference,
    }


def plot_topp(data: dict[str, Any], path: Path) -> None:
    from armctl.planning.convergence import ConvergenceStudy, plot_convergence

    study = ConvergenceStudy(
        np.array(data["grids"]),
        np.array(data["durations"]),
        np.array(data["errors"]),
        np.array(data["compute_s"]),
        data["analytic_duration"],
    )
    plot_convergence(study).savefig(path, dpi=90)


def _model_sections() -> dict[str, Any]:
    """The sections on the models' cost against accuracy, by key: backends, integrators, fidelity, and the plant
    engines where MuJoCo is installed."""
    from importlib.util import find_spec

    from armctl.bench import backends, fidelity, integrators

    sections = {"backends": backends, "integrators": integrators, "fidelity": fidelity}
    if find_spec("mujoco") is not None:
        from armctl.bench import engines

        sections["engines"] = engines
    return sections


def run_suite(
    quick: bool = False, out: Path = Path("bench-out"), executor: Executor | str | None = None
) -> dict[str, Any]:
    from armctl.bench import controller_speed, dynamics_speed, osc_speed, stability

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    figures: dict[str, Any] = {"quick": quick, "started": time.strftime("%Y-%m-%d %H:%M:%S")}
    charts: dict[str, str] = {}
    number, rounds = (100, 15) if quick else (200, 75)  # paired rounds: see bench.timing.paired_ratio
    t_all = time.perf_counter()

    def section(key: str, fn: Callable[[], Any]) -> Any:
        print(f"\n== {key}", flush=True)
        t0 = time.perf_counter()
        figures[key] = fn()
        figures.setdefault("section_seconds", {})[key] = time.perf_counter() - t0
        return figures[key]

    section("scenes", lambda: scene_matrix(executor, rounds=5 if quick else 15))
    plot_pareto(figures["scenes"], out / "speed_accuracy.png")
    charts["speed_accuracy.png"] = (
        "Tracking error against compute time per control step, per scene (bars: "
        "timing quartiles; diverged or failed methods listed in their panel)"
    )
    section("stability_maps", lambda: stability.maps(quick=quick, executor=executor))
    for name in stability.plot(figures["stability_maps"], lambda n: out / n):
        key = name.removeprefix("stability_").removesuffix(".png")
        charts[name] = stability.caption(key, figures["stability_maps"])
    section("topp_convergence", lambda: topp_convergence(quick))
    plot_topp(figures["topp_convergence"], out / "topp_convergence.png")
    charts["topp_convergence.png"] = "TOPP-RA duration error and compute time against grid size"
    for key, mod in _model_sections().items():
        section(key, lambda mod=mod: mod.run(quick=quick))
        mod.plot(figures[key], out / f"{key}.png")
        charts[f"{key}.png"] = (mod.__doc__ or key).strip().splitlines()[0]
    section("dynamics_speed", lambda: dynamics_speed.run(number=number, rounds=rounds, compile_if_needed=not quick))
    section("controller_speed", lambda: controller_speed.run(number=number, rounds=rounds))
    section("osc_speed", lambda: osc_speed.run(quick=quick))
    figures["total_seconds"] = time.perf_counter() - t_all
    figures["charts"] = charts
    (out / "figures.json").write_text(json.dumps(figures, indent=1, default=_json_default))
    text = summary(figures)
    print("\n" + text)
    from armctl.bench.report import write_report

    write_report(out, figures, charts, text)
    return figures


def _json_default(x: Any) -> Any:
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    return str(x)


def summary(figures: dict[str, Any]) -> str:
    from armctl.bench import controller_speed, dynamics_speed, osc_speed

    lines = [
        "errors in rad (joint scenes) or m (panda_contact: tool position in the table plane); force: RMS "
        "normal-force error after settling [N]; over limits: share of samples beyond the effort limit / "
        "velocity limit (+1 %) / position range; a run that diverged has no error (its error until then is in "
        "figures.json)",
        f"{'scene':14s} {'method':26s} {'RMS err':>9s} {'max err':>9s} {'force':>6s} {'step µs':>8s} "
        f"{'τ RMS':>8s}  {'over τ / q̇ / q':>17s}  outcome",
    ]
    for r in figures.get("scenes", []):
        force = f"{r['force_rms_error']:6.2f}" if "force_rms_error" in r else f"{'-':>6s}"
        over = " / ".join(
            f"{r.get(f'{k}_violation_share', float('nan')):.1%}" for k in ("torque", "velocity", "position")
        )
        outcome = _failure_note(r, brief=False) or "ok"
        if r.get("contact_lost"):
            outcome += ", contact lost"
        lines.append(
            f"{r['scene']:14s} {r['method']:26s} {r['rms_error']:9.2e} {r['max_error']:9.2e} {force} "
            f"{r['compute_s'] * 1e6:8.1f} {r['torque_rms']:8.2f}  {over:>17s}  {outcome}"
        )
    reports = {
        **{key: mod.summary for key, mod in _model_sections().items()},
        "dynamics_speed": dynamics_speed.report,
        "controller_speed": controller_speed.report,
        "osc_speed": osc_speed.report,
    }
    for key, report in reports.items():
        if key in figures:  # (every section, after a whole run)
            lines += ["", report(figures[key])]
    lines.append(f"\ntotal {figures['total_seconds']:.1f} s")
    return "\n".join(lines)
