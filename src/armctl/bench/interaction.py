"""Interaction control: force error against table stiffness, stability borders predicted and simulated, observer.

Force tracking against the table's stiffness for each controller, the predicted and simulated stability borders of
force control and impedance, the observer's gain against detection delay and noise, and the collision scene's force
traces.

The bench section ``interaction`` (``armctl bench --section interaction``): :func:`run` gathers
:mod:`armctl.bench.force_tracking`, :mod:`armctl.bench.interaction_borders`, :mod:`armctl.bench.observer_tradeoff`
and the ``panda_collision`` scene; :func:`plot` draws them on one chart; :func:`summary` prints them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from armctl.bench import force_tracking, interaction_borders, interaction_speed, observer_tradeoff

OUTCOME_STYLE = {"stable": ("o", "tab:green"), "chatter": ("x", "tab:red"), "diverged": ("s", "black")}


def collision_traces() -> dict[str, Any]:
    """The ``panda_collision`` scene's contact force, the observer's estimate of it and the detection, per method."""
    from armctl.scenes import scene

    sc = scene("panda_collision")
    out: dict[str, Any] = {}
    for method in sc.methods:
        res = sc.run(method)
        m = sc.metrics(res, method, timing_rounds=0)
        est = np.nan_to_num(np.linalg.norm(res.logs["wrench_estimate"][:, :3], axis=1))
        every = max(1, len(res.t) // 500)
        out[method] = {
            "t": res.t[::every].tolist(),
            "force": np.linalg.norm(res.contact_force_on_environment[::every, 0], axis=1).tolist(),
            "estimate": est[::every].tolist(),
            **{k: m[k] for k in ("contact_at", "detected_at", "peak_force", "force_after", "push_impulse")},
        }
    return out


def run(quick: bool = False) -> dict[str, Any]:
    """Every part of the section (see the module).

    Parameters
    ----------
    quick : bool, optional
        Fewer stiffnesses, gains and bisection steps.

    Returns
    -------
    dict of str
    """
    return {
        "force_tracking": force_tracking.run(quick),
        "force_border": interaction_borders.force_border(quick),
        "impedance_map": interaction_borders.impedance_map(quick),
        "observer": observer_tradeoff.run(quick),
        "collision": collision_traces(),
        "observer_speed": interaction_speed.observer_rows(*((100, 15) if quick else (200, 41))),
    }


def plot(data: dict[str, Any], path: Path) -> None:
    """The section's chart (six panels) at ``path``.

    Parameters
    ----------
    data : dict
        From :func:`run`.
    path : pathlib.Path
        Where to write it (.png or .svg).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 3, figsize=(16.0, 9.0))
    force_tracking.plot_axes(data["force_tracking"], axes[0, 0])
    _force_border(data["force_border"], axes[0, 1])
    _impedance_map(data["impedance_map"], axes[0, 2])
    observer_tradeoff.plot_axes(data["observer"], axes[1, 0], axes[1, 1])
    _collision(data["collision"], axes[1, 2])
    fig.suptitle("Interaction control on the Panda at 1 kHz (one period of measurement delay): where each method "
                 "holds and where it fails, predicted and simulated", fontsize=12)  # fmt: skip
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def _force_border(data: dict[str, Any], ax: Any) -> None:
    rows = data["rows"]
    k = [r["stiffness"] for r in rows]
    ax.loglog(k, [r["predicted"] for r in rows], "k--", label="predicted (sampled-data model)")
    ax.loglog(k, [r["border"] for r in rows], "o", color="tab:blue", label="simulated (bisection)")
    for r in rows:
        ax.plot([r["stiffness"]] * 2, r["bracket"], "-", color="tab:blue", lw=3, alpha=0.4)
    ax.set_xlabel("table stiffness k_e [N/m]")
    ax.set_ylabel("critical force gain K_F* [m/N]")
    ax.set_title(f"force control (inner CT, K_P = {data['kp']:g}): stability border", fontsize=10)
    ax.legend(fontsize=8)


def _impedance_map(data: dict[str, Any], ax: Any) -> None:
    ax.loglog(data["k_d"], data["predicted"], "k--", label="predicted border k_e*(k_d)")
    ax.plot([r["k_d"] for r in data["rows"]], [r["border"] for r in data["rows"]], "D", color="tab:blue", ms=4,
            label="simulated border (bisection)")  # fmt: skip
    for o, (marker, color) in OUTCOME_STYLE.items():
        cells = [(c["k_d"], c["stiffness"]) for c in data["cells"] if c["outcome"] == o]
        if cells:
            ax.plot(*zip(*cells, strict=True), marker, color=color, ls="", label=f"simulated: {o}")
    ax.set_xlabel("impedance stiffness k_d [N/m]")
    ax.set_ylabel("table stiffness k_e [N/m]")
    ax.set_title("Cartesian impedance: where the contact chatters", fontsize=10)
    ax.legend(fontsize=8)


def _collision(data: dict[str, Any], ax: Any) -> None:
    for method, d in data.items():
        (line,) = ax.plot(d["t"], d["force"], label=f"{method.replace('_', ' ')}: contact force")
        ax.plot(d["t"], d["estimate"], ":", color=line.get_color(), label="  observer's estimate")
    first = next(iter(data.values()))
    ax.axvline(first["detected_at"], color="gray", lw=0.8)
    ax.set_xlim(first["contact_at"] - 0.1, first["contact_at"] + 0.6)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("|f| at the tool [N]")
    ax.set_title("panda_collision: the unexpected wall (grey: detection)", fontsize=10)
    ax.legend(fontsize=7)


def summary(data: dict[str, Any]) -> str:
    """The section's text.

    Parameters
    ----------
    data : dict
        From :func:`run`.

    Returns
    -------
    str
    """
    lines = force_tracking.summary_lines(data["force_tracking"])
    lines.append("force control: critical force gain K_F* [m/N], predicted and simulated")
    for r in data["force_border"]["rows"]:
        lines.append(
            f"  k_e = {r['stiffness']:8.0e} N/m   predicted {r['predicted']:.3e}   simulated {r['border']:.3e}   "
            f"ratio {r['ratio']:.3f}"
        )
    imp = data["impedance_map"]
    lines.append("Cartesian impedance: table stiffness k_e* [N/m] where the contact chatters, predicted and simulated")
    for r in imp["rows"]:
        cells = [c for c in imp["cells"] if c["k_d"] == r["k_d"]]
        said = ", ".join(f"{c['factor']:g}×: {c['outcome']}" for c in cells)
        lines.append(
            f"  k_d = {r['k_d']:6.0f}   predicted {r['predicted']:.3e}   simulated {r['border']:.3e}   "
            f"ratio {r['ratio']:.3f}   {said}"
        )
    lines += observer_tradeoff.summary_lines(data["observer"])
    lines.append("panda_collision: contact, detection [s], peak force, force 0.3 s after detection [N], push [N·s]")
    for method, d in data["collision"].items():
        lines.append(
            f"  {method:12s} {d['contact_at']:.3f} {d['detected_at']:.3f}  {d['peak_force']:6.1f} "
            f"{d['force_after']:6.2f} {d['push_impulse']:7.3f}"
        )
    lines.append(interaction_speed.report({"model": "panda", **data["observer_speed"]}))
    return "\n".join(lines)
