"""``report.html``: an ``armctl bench`` run in one page — a table of contents, each section's results as
HTML tables (sortable by clicking a header: a few lines of embedded script), its charts (SVG, and PNG for the
stability maps) and the scenes' 3D playbacks, all referenced from the files beside it; nothing is loaded from
the network."""

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

    plt.rcParams.update({"font.size": 10, "axes.titlesize": 11, "axes.labelsize": 10, "legend.fontsize": 9})
    return plt


def plain_log_ticks(ax: Any) -> None:
    """Log axes of ``ax`` ticked at 1, 2, 5 × 10^k and labelled plainly ("20", "0.005", never "2×10⁰"),
    without minor labels (over less than a decade matplotlib labels the minor ticks, which collide)."""
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


_STYLE = """
body{font-family:system-ui,sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222;line-height:1.45}
h1{margin-bottom:.2em} h2{border-bottom:1px solid #ddd;padding-bottom:.2em;margin-top:2em}
nav ol{columns:2} table{border-collapse:collapse;margin:.6em 0 .2em;font-size:14px}
caption{text-align:left;font-weight:600;padding:.3em 0} div.wide{overflow-x:auto}
th,td{border:1px solid #d5d9de;padding:3px 8px;text-align:right;white-space:nowrap}
th{background:#eef1f4;cursor:pointer;user-select:none} th[aria-sort=ascending]::after{content:" ▲"}
th[aria-sort=descending]::after{content:" ▼"} td.text{text-align:left;white-space:normal}
tr:nth-child(even) td{background:#fafbfc} p.note{font-size:13px;color:#555;margin:.2em 0 1em}
figure{margin:1em 0} figure img{max-width:100%;border:1px solid #ddd}
figcaption{font-size:14px;color:#333;max-width:70em}
iframe{width:100%;height:620px;border:1px solid #ccc} pre{background:#f6f6f6;padding:1em;overflow-x:auto;font-size:12px}
"""

#: sorting a table by a header click; numbers by their data-key, text by its words
_SORT = """
document.querySelectorAll("table.sortable").forEach(function(table){
  table.querySelectorAll("th").forEach(function(th, col){
    th.addEventListener("click", function(){
      const up = th.getAttribute("aria-sort") !== "ascending";
      table.querySelectorAll("th").forEach(h => h.removeAttribute("aria-sort"));
      th.setAttribute("aria-sort", up ? "ascending" : "descending");
      const body = table.tBodies[0], rows = Array.from(body.rows);
      function key(r){ const c = r.cells[col], k = c.getAttribute("data-key");
        return k === null ? null : (c.classList.contains("text") ? k : parseFloat(k)); }
      rows.sort(function(a, b){ const x = key(a), y = key(b);
        if (x === null) return 1; if (y === null) return -1;
        const d = (typeof x === "number") ? x - y : String(x).localeCompare(String(y));
        return up ? d : -d; });
      rows.forEach(r => body.appendChild(r));
    });
  });
});
"""


def _table(t: Any) -> str:
    esc = html.escape
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


def _anchor(key: str) -> str:
    return "s-" + "".join(ch if ch.isalnum() else "-" for ch in key)


def write_report(out: Path, figures: dict[str, Any], charts: dict[str, Any], summary: str) -> Path:
    """Write ``out/report.html``: a table of contents, then per section (in the order of
    :data:`armctl.bench.suite.SECTION_TITLES`, then any other) its tables, charts and playbacks; the scope of
    the run and the console text last. ``charts``: file name → {"section", "caption"} (a bare caption string
    is put under the section "charts")."""
    from armctl.bench.outcomes import scene_title
    from armctl.bench.suite import SECTION_TITLES
    from armctl.bench.tables import TABLES

    esc = html.escape
    charts = {k: (v if isinstance(v, dict) else {"section": "charts", "caption": v}) for k, v in charts.items()}
    keys = [k for k in SECTION_TITLES if k in figures]
    keys += [k for k in figures.get("section_seconds", {}) if k not in keys]
    titles = {k: SECTION_TITLES.get(k, k.replace("_", " ").capitalize()) for k in keys}
    extra = [c["section"] for c in charts.values() if c["section"] not in titles]
    for k in dict.fromkeys(extra):
        keys.append(k)
        titles[k] = k.replace("_", " ").capitalize()
    playbacks = [r for r in figures.get("scenes", []) if r.get("playback")]
    toc = [f"<li><a href='#{_anchor(k)}'>{esc(titles[k])}</a></li>" for k in keys]
    if playbacks:
        toc.insert(1, "<li><a href='#s-playback'>3D playback of the scenes</a></li>")
    toc += ["<li><a href='#s-scope'>Scope</a></li>", "<li><a href='#s-text'>Console text</a></li>"]
    parts = [
        "<!doctype html><html lang='en'><head><meta charset='utf-8'><title>armctl bench</title>",
        f"<style>{_STYLE}</style></head><body>",
        "<h1>armctl bench</h1>",
        f"<p>{'Quick run' if figures.get('quick') else 'Full run'} started {esc(figures['started'])}, "
        f"{figures.get('total_seconds', 0):.0f} s. Every number behind the tables and charts is in "
        "<a href='figures.json'>figures.json</a>.</p>",
        "<nav><h2>Contents</h2><ol>" + "".join(toc) + "</ol></nav>",
    ]
    for k in keys:
        seconds = figures.get("section_seconds", {}).get(k)
        parts.append(f"<section id='{_anchor(k)}'><h2>{esc(titles[k])}</h2>")
        if seconds is not None:
            parts.append(f"<p class='note'>Section run time {seconds:.0f} s.</p>")
        if k in figures and k in TABLES:
            parts += [_table(t) for t in TABLES[k](figures[k])]
        elif k in figures:
            from armctl.bench.suite import section_summary

            parts.append(f"<pre>{esc(section_summary(k, figures[k]))}</pre>")
        for name, c in charts.items():
            if c["section"] == k:
                parts.append(
                    f"<figure><img src='{esc(name)}' alt='{esc(c['caption'])}' loading='lazy'>"
                    f"<figcaption>{esc(c['caption'])}</figcaption></figure>"
                )
        parts.append("</section>")
        if k == "scenes" and playbacks:
            parts.append("<section id='s-playback'><h2>3D playback of the scenes</h2>")
            parts.append(
                "<p class='note'>One run per scene (computed torque where the scene has it), drawn with the arm's "
                "collision meshes: drag to turn the view, scroll to zoom, the slider to move in time. Each page "
                "also opens on its own.</p>"
            )
            for r in playbacks:
                name = r["playback"]
                parts.append(
                    f"<h3>{esc(r['scene'])}, {esc(r['method'].replace('_', ' '))}</h3><p class='note'>"
                    f"{esc(scene_title(r['scene'], figures['scenes']))}</p>"
                    f"<p><a href='{esc(name)}'>open on its own page</a></p>"
                    f"<iframe src='{esc(name)}' title='{esc(r['scene'])} playback' loading='lazy'></iframe>"
                )
            parts.append("</section>")
    parts.append("<section id='s-scope'><h2>Scope</h2><ul>" + "".join(f"<li>{esc(n)}</li>" for n in SCOPE) + "</ul>")
    parts.append("</section>")
    parts.append(
        f"<section id='s-text'><h2>Console text</h2><details><summary>as printed</summary><pre>{esc(summary)}</pre>"
    )
    parts.append(f"</details></section><script>{_SORT}</script></body></html>")
    path = out / "report.html"
    path.write_text("\n".join(parts), encoding="utf-8")
    return path
