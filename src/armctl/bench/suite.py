"""``armctl bench``: every scene × controller, stability maps, TOPP convergence, the dynamics backends', the
integrators' and the models' cost against accuracy — written to ``figures.json`` (every number behind the
charts), charts, a 3D playback of each scene and ``report.html``.

Sections run in turn, under a progress bar (:mod:`armctl.bench.progress`), and each one's results are printed
as it finishes; the simulation-heavy ones go through an ``Executor`` (a process pool by default). ``quick``
shrinks grids, repetitions and runs so the whole bench takes a few minutes on 2 cores; ``sections`` and
``scenes`` run a part of it. The warnings a section's runs raise are counted into its results (the report shows
them under the section), not printed as they come; the parts a run leaves out (a section not asked for, the
playbacks without meshcat, the engines without MuJoCo) are named in the console and the report, each with the
command that adds it.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from concurrent.futures import Executor
from pathlib import Path
from typing import Any

import numpy as np

from armctl.bench.outcomes import outcome, scene_title
from armctl.bench.pareto import pareto_front, plot_pareto
from armctl.bench.sections import (
    SCENE_NAMES,
    SECTION_TITLES,
    available_sections,
    duration_text,
    missing_extra,
    model_sections,
    section_summary,
    skipped_text,
    summary,
    to_json,
    warnings_summary,
)

__all__ = ["outcome", "pareto_front", "plot_pareto", "run_suite", "scene_matrix", "scene_title", "summary"]


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
            title = f"{scene}: {method.replace('_', ' ')} on {res.info.get('plant', sc.plant.name)}, {res.status}"
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
    executor: Executor | str | None = None,
    rounds: int = 9,
    playback_dir: Path | None = None,
    scenes: tuple[str, ...] | list[str] | None = None,
) -> list[dict[str, Any]]:
    """Every method on every scene (:func:`run_scene_method`), timed afterwards (:func:`time_controllers`);
    with ``playback_dir``, each scene's :func:`showcase` run is also written there as
    ``playback_<scene>.html``.

    Parameters
    ----------
    executor : concurrent.futures.Executor or "serial", optional
        Where the runs go (see :func:`armctl.sim.sweep`).
    rounds : int, optional
        Timing rounds of each controller.
    playback_dir : pathlib.Path, optional
        Where the playbacks go (None: none written).
    scenes : sequence of str, optional
        The scenes to run, among ``SCENE_NAMES`` (None: all of them).

    Returns
    -------
    list of dict
        One row per scene and method.
    """
    from armctl.errors import ArmctlError
    from armctl.scenes import SCENES, scene
    from armctl.sim import sweep

    cases: list[dict[str, Any]] = []
    unbuilt = []
    for name in SCENE_NAMES:
        if name not in SCENES or (scenes is not None and name not in scenes):
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
    rows = sweep(cases, run=run_scene_method, executor=executor, progress=True, on_error="raise") + unbuilt
    time_controllers(rows, rounds)
    return rows


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
    from armctl.bench.charts import plain_log_ticks

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


def _chosen(names: Any, valid: tuple[str, ...], kind: str) -> tuple[str, ...] | None:
    """``names`` (None, a name or names) checked against ``valid``: the names in ``valid``'s order, or None."""
    from armctl.errors import UnknownNameError

    if names is None:
        return None
    given = (names,) if isinstance(names, str) else tuple(names)
    for name in given:
        if name not in valid:
            raise UnknownNameError(kind, name, valid)
    return tuple(v for v in valid if v in given)


def _counted(said: list[warnings.WarningMessage]) -> list[dict[str, Any]]:
    """The warnings caught in a section, one entry per category and message with its count, most frequent first."""
    counts: dict[tuple[str, str], int] = {}
    for w in said:
        key = (w.category.__name__, str(w.message))
        counts[key] = counts.get(key, 0) + 1
    ranked = sorted(counts.items(), key=lambda kv: -kv[1])
    return [{"category": c, "message": m, "count": n} for (c, m), n in ranked]


def _skipped(
    quick: bool, out: Path, sections: tuple[str, ...], scenes: tuple[str, ...] | None, asked: bool
) -> list[dict[str, str]]:
    """The parts this run leaves out, each with the reason and the command that adds it."""
    from importlib.util import find_spec

    whole = f"armctl bench{' --quick' if quick else ''} --out {out}"
    left: list[dict[str, str]] = []
    if asked:
        rest = [k for k in SECTION_TITLES if k not in sections and (k != "engines" or find_spec("mujoco"))]
        if rest:
            left.append({"part": "the sections " + ", ".join(rest), "reason": "not asked for", "command": whole})
    if scenes is not None and "scenes" in sections:
        rest = [s for s in SCENE_NAMES if s not in scenes]
        if rest:
            left.append({"part": "the scenes " + ", ".join(rest), "reason": "not asked for", "command": whole})
    if "scenes" in sections and (s := missing_extra("playback")) is not None:
        left.append(s)
    if not asked and (s := missing_extra("engines")) is not None:
        left.append(s)
    return left


def run_suite(
    quick: bool = False,
    out: Path = Path("bench-out"),
    executor: Executor | str | None = None,
    *,
    sections: str | tuple[str, ...] | list[str] | None = None,
    scenes: str | tuple[str, ...] | list[str] | None = None,
) -> dict[str, Any]:
    """Run the sections in turn (each one's results printed as it finishes), then write ``figures.json``, the
    charts, the scenes' playbacks and ``report.html`` into ``out``.

    Parameters
    ----------
    quick : bool, optional
        Short runs and fewer repetitions (a smoke test of the whole bench).
    out : pathlib.Path, optional
        The folder (created if missing).
    executor : concurrent.futures.Executor or "serial", optional
        Where the scene runs go (see :func:`armctl.sim.sweep`; None: a process pool).
    sections : str or sequence of str, optional
        The sections to run, by key (``"scenes"``, ``"stability_maps"``, … ``"osc_speed"``; ``"engines"`` needs
        MuJoCo). None: every section, or only ``"scenes"`` if ``scenes`` is given.
    scenes : str or sequence of str, optional
        The scenes of the scene matrix to run (``"pendulum"``, ``"planar_2r"``, ``"panda_topp"``,
        ``"panda_contact"``; None: all).

    Returns
    -------
    dict of str
        The figures (also written as ``figures.json``). ``section_warnings``: per section, the warnings its
        runs raised, with their counts; ``skipped``: the parts left out, with the command that adds each.

    Raises
    ------
    UnknownNameError
        A section or scene that is not one (the error lists the valid names).
    InvalidParameterError
        ``scenes`` given with ``sections`` that leave out ``"scenes"``.
    """
    from armctl.bench import controller_speed, dynamics_speed, osc_speed, stability
    from armctl.bench.progress import sections as progress_bar
    from armctl.bench.report import write_report
    from armctl.errors import InvalidParameterError

    chosen_scenes = _chosen(scenes, SCENE_NAMES, "scene")
    asked = _chosen(sections, available_sections(), "section")
    chosen = asked if asked is not None else ("scenes",) if chosen_scenes is not None else available_sections()
    if chosen_scenes is not None and "scenes" not in chosen:
        raise InvalidParameterError(
            f"scenes {list(chosen_scenes)} were given but the sections {list(chosen)} leave out the scene matrix; "
            "add the section 'scenes' (--section scenes) or drop the scenes",
            value=chosen_scenes,
        )
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    figures: dict[str, Any] = {"quick": quick, "started": time.strftime("%Y-%m-%d %H:%M:%S")}
    figures["skipped"] = _skipped(quick, out, chosen, chosen_scenes, asked is not None or chosen_scenes is not None)
    for s in figures["skipped"]:
        print(skipped_text(s), flush=True)
    charts: dict[str, dict[str, str]] = {}  # file name → {"section", "caption"}
    number, rounds = (100, 15) if quick else (200, 75)  # paired rounds: see bench.timing.paired_ratio
    t_all = time.perf_counter()

    def chart(name: str, section: str, caption: str) -> None:
        charts[name] = {"section": section, "caption": caption}

    def one_chart(key: str, plot: Callable[[Any, Path], None], name: str, caption: str) -> Callable[[], None]:
        """What follows a section with one chart: ``plot`` of its figures written to ``out / name``, listed with
        ``caption``."""

        def after() -> None:
            plot(figures[key], out / name)
            chart(name, key, caption)

        return after

    def after_stability() -> None:
        for name in stability.plot(figures["stability_maps"], lambda n: out / n):
            key = name.removeprefix("stability_").removesuffix(".png")
            chart(name, "stability_maps", stability.caption(key, figures["stability_maps"]))

    after_scenes = one_chart(
        "scenes",
        plot_pareto,
        "speed_accuracy.svg",
        "RMS tracking error against the controller's compute time per step, one panel per scene (its arm "
        "and task in the title). Circles: within the plant's limits; diamonds: saturated or beyond a limit "
        "(see the outcome column); red: the Pareto front; horizontal bars: the timing's quartiles; crosses: "
        "methods that diverged or failed.",
    )
    after_topp = one_chart(
        "topp_convergence",
        plot_topp,
        "topp_convergence.svg",
        "TOPP-RA on a planar 2R arm: duration error against the analytic bang-bang duration, and compute "
        "time, against the grid size.",
    )

    def after_model_section(key: str, mod: Any) -> Callable[[], None]:
        return one_chart(key, mod.plot, f"{key}.svg", (mod.__doc__ or key).strip().splitlines()[0])

    playbacks = out if missing_extra("playback") is None else None
    plan: list[tuple[str, Callable[[], Any], Callable[[], None] | None]] = [
        (
            "scenes",
            lambda: scene_matrix(executor, rounds=5 if quick else 15, playback_dir=playbacks, scenes=chosen_scenes),
            after_scenes,
        ),
        ("stability_maps", lambda: stability.maps(quick=quick, executor=executor), after_stability),
        ("topp_convergence", lambda: topp_convergence(quick), after_topp),
        *(
            (key, (lambda mod=mod: mod.run(quick=quick)), after_model_section(key, mod))
            for key, mod in model_sections().items()
        ),
        (
            "dynamics_speed",
            lambda: dynamics_speed.run(number=number, rounds=rounds, compile_if_needed=not quick),
            None,
        ),
        ("controller_speed", lambda: controller_speed.run(number=number, rounds=rounds), None),
        ("osc_speed", lambda: osc_speed.run(quick=quick), None),
    ]
    plan = [p for p in plan if p[0] in chosen]
    bar = progress_bar(len(plan))
    try:
        for key, fn, after in plan:
            bar.set_description(SECTION_TITLES.get(key, key))
            t0 = time.perf_counter()
            with warnings.catch_warnings(record=True) as said:
                warnings.simplefilter("always", UserWarning)  # armctl's warnings, each one counted
                figures[key] = fn()
                if after is not None:
                    after()
            seconds = time.perf_counter() - t0
            figures.setdefault("section_seconds", {})[key] = seconds
            figures.setdefault("section_warnings", {})[key] = _counted(said)
            bar.clear()
            print(f"\n== {SECTION_TITLES.get(key, key)} ({duration_text(seconds)})", flush=True)
            print(section_summary(key, figures[key]), flush=True)
            if said:
                print(warnings_summary(figures["section_warnings"][key]), flush=True)
            bar.update()
    finally:
        bar.close()
    figures["total_seconds"] = time.perf_counter() - t_all
    figures["charts"] = charts
    (out / "figures.json").write_text(to_json(figures))
    report = write_report(out, figures, charts, summary(figures))
    for s in figures["skipped"]:
        print(skipped_text(s), flush=True)
    print(f"\ntotal {duration_text(figures['total_seconds'])} ({report.name} in {out})", flush=True)
    return figures
