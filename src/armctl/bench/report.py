"""``report.html``: an ``armctl bench`` run in one page — what the run left out (with the command that adds it), a
table of contents, each section's results as HTML tables (sortable by clicking a header), its charts (SVG, and
PNG for the stability maps), the warnings its runs raised, and the scenes' 3D playbacks, all referenced from the
files beside it; nothing is loaded from the network.

The page is assembled by the functions below, one per part; its style and its sorting script are the files of
``report_assets/``, inlined."""

from __future__ import annotations

import html
from importlib.resources import files
from pathlib import Path
from typing import Any

from armctl.bench.outcomes import scene_title
from armctl.bench.sections import SCOPE, SECTION_TITLES, duration_text, section_summary
from armctl.bench.tables import TABLES, Table

esc = html.escape


def _asset(name: str) -> str:
    return files("armctl.bench").joinpath("report_assets").joinpath(name).read_text(encoding="utf-8")


def _anchor(key: str) -> str:
    return "s-" + "".join(ch if ch.isalnum() else "-" for ch in key)


def table(t: Table) -> str:
    """A table of :mod:`armctl.bench.tables` as a sortable HTML table (each cell's sort key as ``data-key``)."""
    head = "".join(f"<th scope='col'>{esc(c)}</th>" for c in t.columns)
    body = []
    for row in t.rows:
        cells = []
        for shown, key in row:
            cls = " class='text'" if isinstance(key, str) else ""
            data = "" if key is None else f" data-key='{esc(str(key))}'"
            cells.append(f"<td{cls}{data}>{esc(shown)}</td>")
        body.append("<tr>" + "".join(cells) + "</tr>")
    note = f"<p class='note'>{esc(t.notes)}</p>" if t.notes else ""
    return (
        f"<div class='wide'><table class='sortable'><caption>{esc(t.caption)}</caption><thead><tr>{head}</tr>"
        f"</thead><tbody>{''.join(body)}</tbody></table></div>{note}"
    )


def skipped(parts: list[dict[str, str]]) -> str:
    """The box naming what the run left out, each part with its reason and the command that adds it."""
    if not parts:
        return ""
    items = "".join(
        f"<li>{esc(s['part'])}: {esc(s['reason'])}. Add with <code>{esc(s['command'])}</code></li>" for s in parts
    )
    return f"<div class='skipped' id='s-skipped'><strong>Not in this report</strong><ul>{items}</ul></div>"


def raised(said: list[dict[str, Any]]) -> str:
    """The warnings a section's runs raised, with their count, folded under a one-line summary."""
    if not said:
        return ""
    total = sum(w["count"] for w in said)
    items = "".join(f"<li>{w['count']} × <code>{esc(w['category'])}</code>: {esc(w['message'])}</li>" for w in said)
    return (
        f"<details class='warnings'><summary>{total} warning{'s' if total != 1 else ''} raised by this section's "
        f"runs</summary><ul>{items}</ul></details>"
    )


def figure(name: str, caption: str) -> str:
    """A chart written beside the page, with its caption."""
    return (
        f"<figure><img src='{esc(name)}' alt='{esc(caption)}' loading='lazy'>"
        f"<figcaption>{esc(caption)}</figcaption></figure>"
    )


def section(key: str, title: str, figures: dict[str, Any], charts: dict[str, dict[str, str]]) -> str:
    """One section: its run time, tables (or text), charts and warnings."""
    parts = [f"<section id='{_anchor(key)}'><h2>{esc(title)}</h2>"]
    seconds = figures.get("section_seconds", {}).get(key)
    if seconds is not None:
        parts.append(f"<p class='note'>Section run time: {esc(duration_text(seconds))}.</p>")
    if key in figures and key in TABLES:
        parts += [table(t) for t in TABLES[key](figures[key])]
    elif key in figures:
        parts.append(f"<pre>{esc(section_summary(key, figures[key]))}</pre>")
    parts += [figure(name, c["caption"]) for name, c in charts.items() if c["section"] == key]
    parts.append(raised(figures.get("section_warnings", {}).get(key, [])))
    parts.append("</section>")
    return "".join(parts)


def playbacks(figures: dict[str, Any]) -> str:
    """The scenes' playbacks, one a scene: its arm and task, the run shown, and the page in a frame; or, where
    none was written, why and how to add them."""
    rows = [r for r in figures.get("scenes", []) if r.get("playback")]
    missing = [s for s in figures.get("skipped", []) if s["part"].startswith("3D playback")]
    parts = ["<section id='s-playback'><h2>3D playback of the scenes</h2>"]
    if not rows:
        why = (
            f"{esc(missing[0]['reason'])}; add them with <code>{esc(missing[0]['command'])}</code>"
            if missing
            else "no scene run wrote one"
        )
        parts.append(f"<p class='note'>No playback in this report: {why}.</p></section>")
        return "".join(parts)
    parts.append(
        "<p class='note'>One run per scene (computed torque where the scene has it), drawn with the arm's "
        "collision meshes: drag to turn the view, scroll to zoom, the slider to move in time, the speed menu and "
        "the loop box to replay. Each page also opens on its own.</p>"
    )
    for r in rows:
        name = r["playback"]
        parts.append(
            f"<h3>{esc(r['scene'])}</h3><p class='note'>{esc(scene_title(r['scene'], figures['scenes']))}. "
            f"Shown: {esc(r['method'].replace('_', ' '))}, {esc(str(r.get('status', '')))}. "
            f"<a href='{esc(name)}'>Open on its own page</a>.</p>"
            f"<iframe src='{esc(name)}' title='{esc(r['scene'])} playback' loading='lazy'></iframe>"
        )
    parts.append("</section>")
    return "".join(parts)


def page(figures: dict[str, Any], charts: dict[str, Any], summary: str) -> str:
    """The whole page (see :func:`write_report`)."""
    charts = {k: (v if isinstance(v, dict) else {"section": "charts", "caption": v}) for k, v in charts.items()}
    keys = [k for k in SECTION_TITLES if k in figures]
    keys += [k for k in figures.get("section_seconds", {}) if k not in keys]
    keys += [c["section"] for c in charts.values() if c["section"] not in keys]
    keys = list(dict.fromkeys(keys))
    titles = {k: SECTION_TITLES.get(k, k.replace("_", " ").capitalize()) for k in keys}
    show_playback = "scenes" in figures
    toc = [f"<li><a href='#{_anchor(k)}'>{esc(titles[k])}</a></li>" for k in keys]
    if show_playback:
        toc.insert(keys.index("scenes") + 1, "<li><a href='#s-playback'>3D playback of the scenes</a></li>")
    toc += ["<li><a href='#s-scope'>Scope</a></li>", "<li><a href='#s-text'>Console text</a></li>"]
    kind = "Quick run" if figures.get("quick") else "Full run"
    parts = [
        "<!doctype html><html lang='en'><head><meta charset='utf-8'><title>armctl bench</title>",
        f"<style>{_asset('report.css')}</style></head><body><h1>armctl bench</h1>",
        f"<p>{kind} started {esc(figures['started'])}, run time {esc(duration_text(figures.get('total_seconds')))}."
        " Every number behind the tables and charts is in <a href='figures.json'>figures.json</a>.</p>",
        skipped(figures.get("skipped", [])),
        "<nav><h2>Contents</h2><ol>" + "".join(toc) + "</ol></nav>",
    ]
    for k in keys:
        parts.append(section(k, titles[k], figures, charts))
        if k == "scenes":
            parts.append(playbacks(figures))
    scope = "".join(f"<li>{esc(n)}</li>" for n in SCOPE)
    parts += [
        f"<section id='s-scope'><h2>Scope</h2><ul>{scope}</ul></section>",
        f"<section id='s-text'><h2>Console text</h2><details><summary>as printed</summary><pre>{esc(summary)}</pre>"
        "</details></section>",
        f"<script>{_asset('sort.js')}</script></body></html>",
    ]
    return "\n".join(p for p in parts if p)


def write_report(out: Path, figures: dict[str, Any], charts: dict[str, Any], summary: str) -> Path:
    """Write ``out/report.html``: what the run left out, a table of contents, then per section (in the order of
    :data:`armctl.bench.sections.SECTION_TITLES`, then any other) its tables, charts, warnings and playbacks;
    the scope of the run and the console text last.

    Parameters
    ----------
    out : pathlib.Path
        The folder of the run (the charts and playbacks are there).
    figures : dict
        The run's figures (as in ``figures.json``).
    charts : dict
        File name → {"section", "caption"} (a bare caption string is put under the section "charts").
    summary : str
        The console text.

    Returns
    -------
    pathlib.Path
        The page written.
    """
    path = Path(out) / "report.html"
    path.write_text(page(figures, charts, summary), encoding="utf-8")
    return path
