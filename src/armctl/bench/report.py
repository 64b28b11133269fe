"""``report.html``: the charts and the summary of an ``armctl bench`` run, in one self-contained page
(images referenced next to it)."""

from __future__ import annotations

import html
from pathlib import Path
from typing import Any


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
