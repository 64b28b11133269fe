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


def save_figure(fig: Any, path: Path, dpi: int = 110) -> None:
    """Write ``fig`` to ``path`` and free it."""
    fig.savefig(path, dpi=dpi)
    pyplot().close(fig)


def section_main(run: Callable[..., dict[str, Any]], summary: Callable[[dict[str, Any]], str],
                 plot: Callable[[dict[str, Any], Path], None], chart: str) -> None:
    """Command line of a bench section: ``run`` (``--quick`` for the short version), print ``summary``, write
    the chart ``chart`` in the working directory."""
    data = run(quick="--quick" in sys.argv)
    print(summary(data))
    plot(data, Path(chart))


def write_report(out: Path, figures: dict[str, Any], charts: dict[str, str], summary: str) -> Path:
    parts = ["<!doctype html><html><head><meta charset='utf-8'><title>armctl bench</title>",
             "<style>body{font-family:sans-serif;max-width:1200px;margin:2em auto;color:#222}"
             "img{max-width:100%;border:1px solid #ddd;margin:.5em 0}pre{background:#f6f6f6;padding:1em;"
             "overflow-x:auto;font-size:12px}</style></head><body>",
             "<h1>armctl bench</h1>",
             f"<p>{'Quick run' if figures.get('quick') else 'Full run'} started {html.escape(figures['started'])}, "
             f"{figures.get('total_seconds', 0):.0f} s. Every number behind the charts is in "
             "<a href='figures.json'>figures.json</a>.</p>",
             "<h2>Summary</h2>", f"<pre>{html.escape(summary)}</pre>"]
    for name, caption in charts.items():
        parts.append(f"<h2>{html.escape(caption)}</h2><img src='{html.escape(name)}' alt='{html.escape(caption)}'>")
    parts.append("</body></html>")
    path = out / "report.html"
    path.write_text("\n".join(parts))
    return path
