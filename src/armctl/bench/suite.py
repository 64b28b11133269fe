"""``armctl bench``: every scene × controller, stability maps, TOPP convergence, the dynamics backends', the
integrators' and the models' cost against accuracy — written to ``figures.json`` (every number behind the
charts), charts, a 3D playback of each scene and ``report.html``.

Sections run in turn, under a progress bar (:mod:`armctl.bench.progress`), and each one's results are printed
as it finishes; the simulation-heavy ones go through an ``Executor`` (a process pool by default). ``quick``
shrinks grids, repetitions and runs so the whole bench takes a few minutes on 2 cores.
"""

from __future__ import annotations

import json
import math
import textwrap
import time
import warnings
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


def run_scene_method(scene: str, method: str, playback: str | None = None) -> dict[str, Any]:
    """Simulate one method on one scene (runs in a worker process): its metrics, untimed, the run's status
    and limit report, and the window of recorded states that :func:`time_controllers` replays to time it.
    ``playback``: write the run's 3D playback to this path (collision meshes: a small page). A method that
    fails — its controller raises an :class:`~armctl.errors.ArmctlError` (an infeasible QP, say), or the scene
    cannot be built (a plan its limits refuse) — is a result too: a row with ``failed`` (the error's type and
    message) and NaN measures, so the rest of the benchmark still runs and shows it. The run's warnings
    (saturation, limit overruns, …) are kept in the row, not printed: the outcome column says them."""
    from armctl.errors import ArmctlError, BackendError, SimulationWarning
    from armctl.scenes import scene as make

    try:
        sc = make(scene)
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always", SimulationWarning)
            res = sc.run(method)
    except ArmctlError as exc:
        return _failed_row(scene, method, exc)
    row = {
        "scene": scene,
        "method": method,
        "plant": sc.plant.name,
        "joints": sc.plant.n,
        "description": sc.description,
        **sc.metrics(res, method, timing_rounds=0),
        "status": res.status,
        "limits": res.limits.as_dict() if res.limits is not None else None,
        "warnings": sorted({str(w.message) for w in said if issubclass(w.category, SimulationWarning)}),
        "window": sc.replay_window(res, sc.timing_samples),
    }
    if playback is not None:
        try:
            title = f"{scene}, {method.replace('_', ' ')} ({res.info.get('plant', '')}): {res.status}"
            env = sc.sim_options.get("environment")
            row["playback"] = res.playback(playback, meshes="collision", environment=env, title=title).name
        except BackendError as exc:  # meshcat not installed: the report says so instead
            row["playback_unavailable"] = str(exc)
    return row


def showcase(methods: tuple[str, ...]) -> str:
    """The method whose run a scene's playback shows: computed torque where the scene has it, else its first."""
    return "computed_torque" if "computed_torque" in methods else methods[0]


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


def scene_matrix(
    executor: Executor | str | None = None, rounds: int = 9, playback_dir: Path | None = None
) -> list[dict[str, Any]]:
    """Every method on every scene (:func:`run_scene_method`), timed afterwards (:func:`time_controllers`);
    with ``playback_dir``, each scene's :func:`showcase` run is also written there as
    ``playback_<scene>.html``."""
    from armctl.errors import ArmctlError
    from armctl.scenes import SCENES, scene
    from armctl.sim import sweep

    cases: list[dict[str, Any]] = []
    unbuilt = []
    for name in SCENE_NAMES:
        if name not in SCENES:
            continue
        try:
            methods = scene(name).methods
        except ArmctlError as exc:  # the scene itself cannot be built: one failed row stands for it
            unbuilt.append(_failed_row(name, "(scene)", exc))
            continue
        for m in methods:
            case: dict[str, Any] = {"scene": name, "method": m}
            if playback_dir is not None and m == showcase(methods):
                case["playback"] = str(Path(playback_dir) / f"playback_{name}.html")
            cases.append(case)
    rows = sweep(cases, run=run_scene_method, executor=executor, progress=True) + unbuilt
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


def outcome(r: dict[str, Any]) -> str:
    """A scene row's outcome in words: how it failed or diverged, else what it did beyond the plant's limits
    (the share of samples saturated, over the velocity limit, outside the position range) and whether a
    contact was lost; "ok" for a run within every limit."""
    failure = _failure_note(r, brief=False)
    if failure:
        return failure
    notes = []
    for key, words in (
        ("torque_violation_share", "saturated"),
        ("velocity_violation_share", "over velocity limit"),
        ("position_violation_share", "outside position range"),
    ):
        share = r.get(key, 0.0)
        if isinstance(share, float) and share > 0.0:
            notes.append(f"{words} on {share:.1%}")
    if r.get("contact_lost"):
        notes.append("contact lost")
    return "; ".join(notes) if notes else "ok"


def scene_title(name: str, rows: list[dict[str, Any]]) -> str:
    """A scene's arm and task, from its rows (``plant``, ``joints``, ``description``): e.g. "panda (7 joints):
    Panda tracking a time-optimal path …"; the name alone if no row has them (a scene that failed)."""
    for r in rows:
        if r["scene"] == name and r.get("description"):
            joints = f"{r['joints']} joint{'s' if r['joints'] != 1 else ''}"
            return f"{r['plant']} ({joints}): {r['description']}"
    return name


def plot_pareto(rows: list[dict[str, Any]], path: Path) -> None:
    """Tracking error against compute time per step, log-log, one panel per scene (two columns): the
    quartiles of the timing as horizontal bars, the Pareto front (:func:`pareto_front` on those quartiles)
    marked, and every method that diverged or failed listed in its panel (a cross at the top where its time is
    known); a legend explains the markers."""
    from matplotlib.lines import Line2D

    from armctl.bench.report import plain_log_ticks, pyplot

    plt = pyplot()
    scenes = [s for s in SCENE_NAMES if any(r["scene"] == s for r in rows)]
    cols = min(2, len(scenes))
    nrows = math.ceil(len(scenes) / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(6.4 * cols, 4.9 * nrows), squeeze=False)
    for ax in axes.flat[len(scenes) :]:
        ax.set_visible(False)
    for ax, name in zip(axes.flat, scenes, strict=False):
        mine = [r for r in rows if r["scene"] == name and _failure_note(r) is None]
        pts = [(r["compute_s"] * 1e6, r["rms_error"]) for r in mine]
        spans = [tuple(1e6 * v for v in r.get("compute_s_iqr", (r["compute_s"],) * 2)) for r in mine]
        front = set(pareto_front(pts, spans))  # type: ignore[arg-type]
        placed: list[tuple[float, float]] = []
        for i, (r, (x, y), (lo, hi)) in enumerate(zip(mine, pts, spans, strict=True)):
            color = "#d62828" if i in front else "#577590"
            marker = "o" if outcome(r) == "ok" else "D"
            ax.errorbar(
                x,
                y,
                xerr=[[max(x - lo, 0.0)], [max(hi - x, 0.0)]],
                fmt=marker,
                ms=7,
                color=color,
                zorder=3,
                capsize=3,
                lw=1,
            )
            # a label near an earlier one's point (in decades) goes one line lower for each such neighbour
            near = sum(
                1
                for px, py in placed
                if x > 0 and y > 0 and abs(math.log10(x / px)) < 0.3 and abs(math.log10(y / py)) < 0.3
            )
            placed.append((x, y))
            ax.annotate(
                r["method"].replace("_", " "), (x, y), fontsize=9, xytext=(6, 4 - 12 * near), textcoords="offset points"
            )
        fx = sorted(pts[i] for i in front)
        if fx:
            ax.plot(*zip(*fx, strict=True), color="#d62828", lw=1)
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
                fontsize=9,
                color="#d62828",
                va="top",
            )
        ax.margins(x=0.25, y=0.3)
        ax.set(
            xscale="log",
            yscale="log",
            xlabel="compute time per control step [µs]",
            ylabel="RMS tracking error [rad]" if name != "panda_contact" else "RMS tool position error [m]",
        )
        ax.set_title(f"{name}\n{textwrap.fill(scene_title(name, rows), 60)}", fontsize=10)
        ax.grid(True, which="both", alpha=0.25)
        plain_log_ticks(ax)
    key = [
        Line2D([], [], ls="", marker="o", color="#577590", ms=7, label="method within the plant's limits"),
        Line2D([], [], ls="", marker="D", color="#577590", ms=7, label="method saturated or beyond a limit"),
        Line2D([], [], color="#d62828", marker="o", ms=7, lw=1, label="Pareto front (no method faster and better)"),
        Line2D([], [], color="#577590", marker="|", ms=12, lw=1, label="bar: quartiles of the step's time"),
        Line2D([], [], ls="", marker="x", color="#d62828", ms=9, mew=2, label="diverged or failed (listed)"),
    ]
    fig.legend(handles=key, loc="lower center", ncol=3, fontsize=10, frameon=False)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    save(fig, path)


def save(fig: Any, path: Path) -> None:
    """Write a chart (the format from the suffix: the report's are SVG) and free it."""
    from armctl.bench.report import save_figure

    save_figure(fig, path, dpi=110)


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
    from armctl.bench.report import plain_log_ticks

    fig = plot_convergence(study)
    fig.set_size_inches(10.0, 4.6)
    fig.suptitle(
        "planar_2r (2 joints), rest to rest from q = (0, 0) to (1, −0.8) rad under velocity and acceleration\n"
        "limits: TOPP-RA's duration against the analytic bang-bang one (each marker: one grid size)",
        fontsize=11,
    )
    import matplotlib.ticker as ticker

    for ax in fig.axes:
        plain_log_ticks(ax)  # grid sizes and milliseconds read plainly: 10, 20, 50 …
        if "compute" not in ax.get_ylabel():  # the error spans decades: powers of ten, labelled as such
            ax.yaxis.set_major_locator(ticker.LogLocator(base=10.0))
            ax.yaxis.set_major_formatter(ticker.LogFormatterSciNotation())
    fig.savefig(path, dpi=110)


def _model_sections() -> dict[str, Any]:
    """The sections on the models' cost against accuracy, by key: backends, integrators, fidelity."""
    from armctl.bench import backends, fidelity, integrators

    return {"backends": backends, "integrators": integrators, "fidelity": fidelity}


#: the report's title of each section, in the order they run
SECTION_TITLES = {
    "scenes": "Scenes × controllers",
    "stability_maps": "Stability maps",
    "topp_convergence": "TOPP convergence",
    "backends": "Dynamics backends: cost against accuracy",
    "integrators": "Integrators: cost against accuracy",
    "fidelity": "Model fidelity: the cheapest sufficient model",
    "dynamics_speed": "Dynamics speed",
    "controller_speed": "Controller step speed",
    "osc_speed": "Operational-space QP step speed",
}


def run_suite(
    quick: bool = False, out: Path = Path("bench-out"), executor: Executor | str | None = None
) -> dict[str, Any]:
    """Run every section in turn (its results printed as it finishes), then write ``figures.json``, the charts,
    the scenes' playbacks and ``report.html`` into ``out``."""
    from armctl.bench import controller_speed, dynamics_speed, osc_speed, stability
    from armctl.bench.progress import sections
    from armctl.bench.report import write_report

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    figures: dict[str, Any] = {"quick": quick, "started": time.strftime("%Y-%m-%d %H:%M:%S")}
    charts: dict[str, dict[str, str]] = {}  # file name → {"section", "caption"}
    number, rounds = (100, 15) if quick else (200, 75)  # paired rounds: see bench.timing.paired_ratio
    t_all = time.perf_counter()

    def chart(name: str, section: str, caption: str) -> None:
        charts[name] = {"section": section, "caption": caption}

    def after_scenes() -> None:
        plot_pareto(figures["scenes"], out / "speed_accuracy.svg")
        chart(
            "speed_accuracy.svg",
            "scenes",
            "RMS tracking error against the controller's compute time per step, one panel per scene (its arm "
            "and task in the title). Circles: within the plant's limits; diamonds: saturated or beyond a limit "
            "(see the outcome column); red: the Pareto front; horizontal bars: the timing's quartiles; crosses: "
            "methods that diverged or failed.",
        )

    def after_stability() -> None:
        for name in stability.plot(figures["stability_maps"], lambda n: out / n):
            key = name.removeprefix("stability_").removesuffix(".png")
            panels = "control rate × gain" + (
                " and model error × gain" if "gain_error" in figures["stability_maps"][key] else ""
            )
            chart(
                name,
                "stability_maps",
                f"{key.replace('_', ' ')} on a one-joint pendulum in a horizontal plane (one period of measurement "
                f"delay): {panels}. Squares: simulated cells (stable, marginal or unstable); dashed line: the "
                "border sampled-data theory predicts.",
            )

    def after_topp() -> None:
        plot_topp(figures["topp_convergence"], out / "topp_convergence.svg")
        chart(
            "topp_convergence.svg",
            "topp_convergence",
            "TOPP-RA on a planar 2R arm: duration error against the analytic bang-bang duration, and compute "
            "time, against the grid size.",
        )

    def after_model_section(key: str, mod: Any) -> Callable[[], None]:
        def after() -> None:
            mod.plot(figures[key], out / f"{key}.svg")
            chart(f"{key}.svg", key, (mod.__doc__ or key).strip().splitlines()[0])

        return after

    plan: list[tuple[str, Callable[[], Any], Callable[[], None] | None]] = [
        ("scenes", lambda: scene_matrix(executor, rounds=5 if quick else 15, playback_dir=out), after_scenes),
        ("stability_maps", lambda: stability.maps(quick=quick, executor=executor), after_stability),
        ("topp_convergence", lambda: topp_convergence(quick), after_topp),
        *(
            (key, (lambda mod=mod: mod.run(quick=quick)), after_model_section(key, mod))
            for key, mod in _model_sections().items()
        ),
        (
            "dynamics_speed",
            lambda: dynamics_speed.run(number=number, rounds=rounds, compile_if_needed=not quick),
            None,
        ),
        ("controller_speed", lambda: controller_speed.run(number=number, rounds=rounds), None),
        ("osc_speed", lambda: osc_speed.run(quick=quick), None),
    ]
    bar = sections(len(plan))
    try:
        for key, fn, after in plan:
            bar.set_description(SECTION_TITLES.get(key, key))
            t0 = time.perf_counter()
            figures[key] = fn()
            if after is not None:
                after()
            figures.setdefault("section_seconds", {})[key] = time.perf_counter() - t0
            bar.clear()
            print(f"\n== {SECTION_TITLES.get(key, key)} ({time.perf_counter() - t0:.0f} s)", flush=True)
            print(section_summary(key, figures[key]), flush=True)
            bar.update()
    finally:
        bar.close()
    figures["total_seconds"] = time.perf_counter() - t_all
    figures["charts"] = charts
    (out / "figures.json").write_text(json.dumps(figures, indent=1, default=_json_default))
    report = write_report(out, figures, charts, summary(figures))
    print(f"\ntotal {figures['total_seconds']:.1f} s ({report.name} in {out})", flush=True)
    return figures


def _json_default(x: Any) -> Any:
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    return str(x)


def scenes_summary(rows: list[dict[str, Any]]) -> str:
    """The scene matrix as text: one row per scene and method."""
    lines = [
        "errors in rad (joint scenes) or m (panda_contact: tool position in the table plane); force: RMS "
        "normal-force error after settling [N]; over limits: share of samples beyond the effort limit / "
        "velocity limit (+1 %) / position range; a run that diverged has no error (its error until then is in "
        "figures.json)",
        f"{'scene':14s} {'method':26s} {'RMS err':>9s} {'max err':>9s} {'force':>6s} {'step µs':>8s} "
        f"{'τ RMS':>8s}  {'over τ / q̇ / q':>17s}  outcome",
    ]
    for r in rows:
        force = f"{r['force_rms_error']:6.2f}" if "force_rms_error" in r else f"{'-':>6s}"
        over = " / ".join(
            f"{r.get(f'{k}_violation_share', float('nan')):.1%}" for k in ("torque", "velocity", "position")
        )
        lines.append(
            f"{r['scene']:14s} {r['method']:26s} {r['rms_error']:9.2e} {r['max_error']:9.2e} {force} "
            f"{r['compute_s'] * 1e6:8.1f} {r['torque_rms']:8.2f}  {over:>17s}  {outcome(r)}"
        )
    return "\n".join(lines)


def stability_summary(maps: dict[str, Any]) -> str:
    """Per controller and map: how many cells were stable, marginal and unstable."""
    lines = [
        "stability maps (one-joint pendulum in a horizontal plane, one period of delay): cells stable / "
        "marginal / unstable"
    ]
    for c, kinds in maps.items():
        if not isinstance(kinds, dict) or "rate_gain" not in kinds:
            continue
        for kind, data in kinds.items():
            cells = [o for row in data["outcome"] for o in row]
            counts = " / ".join(str(cells.count(o)) for o in ("stable", "marginal", "unstable"))
            lines.append(f"  {c.replace('_', ' '):18s} {kind.replace('_', ' × '):14s} {counts}")
    return "\n".join(lines)


def topp_summary(data: dict[str, Any]) -> str:
    lines = [f"TOPP-RA on planar 2R, analytic duration {data['analytic_duration']:.6f} s"]
    for n, err, t in zip(data["grids"], data["errors"], data["compute_s"], strict=True):
        lines.append(f"  N = {int(n):5d}   |T_N − T|/T = {err:.2e}   {1e3 * t:7.2f} ms")
    return "\n".join(lines)


def section_summary(key: str, data: Any) -> str:
    """The text of one section's results (as printed when it finishes)."""
    from armctl.bench import controller_speed, dynamics_speed, osc_speed

    texts: dict[str, Callable[[Any], str]] = {
        "scenes": scenes_summary,
        "stability_maps": stability_summary,
        "topp_convergence": topp_summary,
        **{k: mod.summary for k, mod in _model_sections().items()},
        "dynamics_speed": dynamics_speed.report,
        "controller_speed": controller_speed.report,
        "osc_speed": osc_speed.report,
    }
    return texts[key](data) if key in texts else json.dumps(data, indent=1, default=_json_default)[:2000]


def summary(figures: dict[str, Any]) -> str:
    """Every section's text, in order (the report keeps it, below its tables)."""
    parts = [section_summary(key, figures[key]) for key in SECTION_TITLES if key in figures]
    parts.append(f"total {figures.get('total_seconds', 0.0):.1f} s")
    return "\n\n".join(parts)
