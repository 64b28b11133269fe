"""``report.html``: the charts and the summary of an ``armctl bench`` run, in one self-contained page
(images referenced next to it)."""

from __future__ import annotations

import html
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any


def pyplot() -> Any:
    """``matplotlib.pyplot`` on the non-interactive Agg backend, imported on first use."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plain_log_ticks(ax: Any) -> None:
    """Log axes of ``ax`` ticked at 1, 2, 5 × 10^k and labelled plainly ("20", "0.005"), without minor labels
    (over less than a decade matplotlib labels the minor ticks, which collide)."""
    import matplotlib.ticker

    for axis in (ax.xaxis, ax.yaxis):
        if axis.get_scale() == "log":
            axis.set_major_locator(matplotlib.ticker.LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
            axis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
            axis.set_minor_formatter(matplotlib.ticker.NullFormatter())


def save_figure(fig: Any, path: Path, dpi: int = 110) -> None:
    """Write ``fig`` to ``path`` and free it."""
    fig.savefig(path, dpi=dpi)
    pyplot().close(fig)


def section_main(
    run: Callable[..., dict[str, Any]],
    summary: Callable[[dict[str, Any]], str],
    plot: Callable[[dict[str, Any], Path], None],
    chart: str,
) -> None:
    """Command line of a bench section: ``run`` (``--quick`` for the short version), print ``summary``, write
    the chart ``chart`` in the working directory."""
    data = run(quick="--quick" in sys.argv)
    print(summary(data))
    plot(data, Path(chart))


#: what the run covers and what it leaves out, stated in the report (so a reader does not infer it)
SCOPE = (
    "Scenes × controllers: the five joint-space laws (PD+gravity, computed torque with the exact and with a "
    "reduced model, passivity-based, adaptive) on the three joint-space scenes; the operational-space QP and "
    "its closed-form baseline on panda_contact. Not run: the joint-space laws on panda_contact (its task is a "
    "contact force and a tool motion, which a law tracking a joint reference does not pursue), and the "
    "operational-space controllers on the joint-space scenes (with a posture task alone they are computed "
    "torque through a QP).",
    "Compute time per step: each controller replays a window of recorded states of its own run, in this "
    "process after every simulation, in interleaved rounds; the median is charted (quartiles in figures.json).",
    "Limits: a sample counts as beyond them if the commanded torque exceeds the effort limit, a joint speed "
    "the velocity limit by more than 1 %, or a joint its position range (shares per kind in the summary).",
    "Stability maps: one-joint pendulum in a horizontal plane with one period of measurement delay; no map for "
    "the operational-space controllers (on one joint they reduce to computed torque) and no gain × model-error "
    "map for PD+gravity (its loop gain does not depend on an inertia estimate). The adaptive law runs with its "
    "preset's Γ; its dashed border is for θ̂ frozen.",
    'Integrators: a frictionless, contact-free arm, on which "implicit-euler" has nothing to treat implicitly '
    'and is the "euler" scheme (velocity form, q₁ = q + h q̇₁); the implicit schemes earn their cost on stiff '
    "contact (tests/sim/test_contact.py).",
    "Plant engines (with MuJoCo installed): the same closed loop on armctl's and on MuJoCo's integrators, the Panda "
    "without friction against a DOP853 reference, and held below breakaway with Coulomb friction, where the error "
    "is the creep (armctl's stick–slip model holds exactly; MuJoCo's frictionloss is a soft constraint).",
)


def write_report(out: Path, figures: dict[str, Any], charts: dict[str, str], summary: str) -> Path:
    parts = [
        "<!doctype html><html><head><meta charset='utf-8'><title>armctl bench</title>",
        "<style>body{font-family:sans-serif;max-width:1200px;margin:2em auto;color:#222}"
        "img{max-width:100%;border:1px solid #ddd;margin:.5em 0}pre{background:#f6f6f6;padding:1em;"
        "overflow-x:auto;font-size:12px}</style></head><body>",
        "<h1>armctl bench</h1>",
        f"<p>{'Quick run' if figures.get('quick') else 'Full run'} started {html.escape(figures['started'])}, "
        f"{figures.get('total_seconds', 0):.0f} s. Every number behind the charts is in "
        "<a href='figures.json'>figures.json</a>.</p>",
        "<h2>Summary</h2>",
        f"<pre>{html.escape(summary)}</pre>",
        "<h2>Scope</h2><ul>" + "".join(f"<li>{html.escape(n)}</li>" for n in SCOPE) + "</ul>",
    ]
    for name, caption in charts.items():
        parts.append(f"<h2>{html.escape(caption)}</h2><img src='{html.escape(name)}' alt='{html.escape(caption)}'>")
    parts.append("</body></html>")
    path = out / "report.html"
    path.write_text("\n".join(parts))
    return path
