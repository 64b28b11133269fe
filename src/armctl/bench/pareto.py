"""The speed/accuracy chart of the scene matrix: tracking error against compute time per step, and its
Pareto front."""

from __future__ import annotations

import math
import textwrap
from pathlib import Path
from typing import Any

from armctl.bench.outcomes import failure_note, outcome, scene_title


def pareto_front(points: list[tuple[float, float]], spans: list[tuple[float, float]] | None = None) -> list[int]:
    """Indices of the points (x, y) no other point beats (both minimised; non-finite points are never on it).

    ``spans``: an interval (lo, hi) around each x — the quartiles of a noisy timing. Then x is compared by
    the intervals: j is faster than i only if hi_j < lo_i, and overlapping intervals are a tie, so timing noise
    alone cannot move a point on or off the front. j beats i if it is faster and no less accurate, or tied and
    more accurate. Without spans this is the usual strict Pareto order.

    Parameters
    ----------
    points : list of tuple of float
        (x, y) each: compute time [s], error.
    spans : list of tuple of float, optional
        An interval (lo, hi) around each x.

    Returns
    -------
    list of int
    """
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


def plot_pareto(rows: list[dict[str, Any]], path: Path) -> None:
    """Tracking error against compute time per step, log-log, one panel per scene (two columns): the
    quartiles of the timing as horizontal bars, the Pareto front (:func:`pareto_front` on those quartiles)
    marked, and every method that diverged or failed listed in its panel (a cross at the top where its time is
    known); a legend explains the markers.

    Parameters
    ----------
    rows : list of dict
        The rows of :func:`scene_matrix`.
    path : pathlib.Path
        The chart (PNG) to write.
    """
    from matplotlib.lines import Line2D

    from armctl.bench.charts import plain_log_ticks, pyplot

    plt = pyplot()
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    cols = min(2, len(scenes))
    nrows = math.ceil(len(scenes) / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(6.4 * cols, 4.9 * nrows), squeeze=False)
    for ax in axes.flat[len(scenes) :]:
        ax.set_visible(False)
    for ax, name in zip(axes.flat, scenes, strict=False):
        mine = [r for r in rows if r["scene"] == name and failure_note(r) is None]
        pts = [(r["compute_s"] * 1e6, r["rms_error"]) for r in mine]
        spans = [tuple(1e6 * v for v in r.get("compute_s_iqr", (r["compute_s"],) * 2)) for r in mine]
        front = set(pareto_front(pts, spans))
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
        failed = [(r, note) for r in rows if r["scene"] == name and (note := failure_note(r)) is not None]
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
    from armctl.bench.charts import save_figure

    save_figure(fig, path, dpi=110, rect=(0, 0.08, 1, 1))
