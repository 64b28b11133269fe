"""The report's tables: each section's figures (as in ``figures.json``) as rows of cells, for
:mod:`armctl.bench.report`. A cell is ``(text, sort key)``; the key is a number where the column is one, so that
the report can sort it as such."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

Cell = tuple[str, Any]


@dataclass
class Table:
    """``columns`` (header texts), ``rows`` (lists of cells), a ``caption`` and ``notes`` under it."""

    caption: str
    columns: list[str]
    rows: list[list[Cell]] = field(default_factory=list)
    notes: str = ""


def num(x: Any, fmt: str = ".3g", scale: float = 1.0, unit: str = "") -> Cell:
    """A number cell (``–`` and no key for NaN, None or a non-number)."""
    if isinstance(x, bool) or not isinstance(x, int | float) or not math.isfinite(float(x)):
        return ("–", None)
    v = float(x) * scale
    return (f"{round(v):d}{unit}" if fmt == "d" else f"{v:{fmt}}{unit}", v)


def text(s: Any) -> Cell:
    return (str(s), str(s))


def scenes(rows: list[dict[str, Any]]) -> list[Table]:
    from armctl.bench.outcomes import error_units, outcome, scene_title

    names = list(dict.fromkeys(r["scene"] for r in rows))
    t = Table(
        "Every controller on every scene",
        [
            "scene",
            "method",
            "RMS error",
            "max error",
            "force error [N]",
            "step [µs]",
            "τ RMS [N·m]",
            "saturated",
            "over q̇ limit",
            "outside q range",
            "outcome",
        ],
        notes="Scenes: " + "; ".join(f"{n}: {scene_title(n, rows)}" for n in names) + ". "
        f"Errors in each scene's unit: {error_units(rows)} (panda_contact: the tool's position in the table plane; "
        "panda_press and panda_wipe: the normal force); force error: RMS normal-force error after settling. "
        "Saturated: share of samples whose command exceeded the effort limit (clipped); over q̇ limit: beyond the "
        "velocity limit by more than 1 %; outside q range: outside the position limits. A run that diverged has "
        "no error (its error until then is in figures.json). Click a header to sort.",
    )
    for r in rows:
        t.rows.append(
            [
                text(r["scene"]),
                text(r["method"].replace("_", " ")),
                num(r["rms_error"], ".2e"),
                num(r["max_error"], ".2e"),
                num(r.get("force_rms_error"), ".3g"),
                num(r["compute_s"], ".1f", 1e6),
                num(r["torque_rms"], ".3g"),
                num(r.get("torque_violation_share"), ".1f", 100.0, " %"),
                num(r.get("velocity_violation_share"), ".1f", 100.0, " %"),
                num(r.get("position_violation_share"), ".1f", 100.0, " %"),
                text(outcome(r)),
            ]
        )
    return [t]


def backends(data: dict[str, Any]) -> list[Table]:
    t = Table(
        f"Inverse dynamics per backend (reference: {data.get('reference', '')})",
        ["arm", "joints", "backend", "time per call [µs]", "relative RMS error"],
    )
    for name, arm in data["arms"].items():
        for k, c in sorted(arm["candidates"].items(), key=lambda kv: kv[1]["cost_s"]):
            t.rows.append(
                [text(name), num(arm["n"], "d"), text(k), num(c["cost_s"], ".2f", 1e6), num(c["error"], ".1e")]
            )
    return [t]


def integrators(data: dict[str, Any]) -> list[Table]:
    s = data["scenario"]
    t = Table(
        f"Integrators on {s['plant']} ({s['duration']:g} s open loop): error against {data['reference']['method']}",
        ["integrator", "step [ms]", "max joint error [rad]", "cost [s per simulated s]", "observed order"],
    )
    for name, d in data["integrators"].items():
        orders = [None, *d.get("orders", [])]
        for c, order in zip(d["cases"], orders, strict=False):
            t.rows.append(
                [
                    text(name),
                    num(c["step"], ".3g", 1e3),
                    num(c["error"], ".2e"),
                    num(c["cost"], ".3g"),
                    num(order, ".2f"),
                ]
            )
    return [t]


def fidelity(data: dict[str, Any]) -> list[Table]:
    shares = Table(
        "Share of each term in the torque along each scene's reference",
        ["scene", *data["terms"]],
    )
    models = Table(
        f"Computed torque on candidate models: the cheapest within {data['factor']:g}× the full model's error",
        ["scene", "model", "backend", "RMS error [rad]", "step [µs]", "outcome"],
    )
    for name, s in data["scenes"].items():
        shares.rows.append([text(name), *(num(s["shares"][k], ".1f", 100.0, " %") for k in data["terms"])])
        cl = s["closed_loop"]
        for key, c in cl["candidates"].items():
            notes = ["diverged" if c["diverged"] else "chosen" if key == cl["choice"] else ""]
            notes.append("full model" if key == cl["baseline"] else "")
            notes.append(c.get("status", "ok") if c.get("status", "ok") not in ("ok", "diverged") else "")
            state = ", ".join(n for n in notes if n)
            models.rows.append(
                [
                    text(name),
                    text(c["variant"]),
                    text(c["backend"]),
                    num(c["rms_error"], ".2e"),
                    num(c["compute_s"], ".1f", 1e6),
                    text(state),
                ]
            )
    return [shares, models]


def _speed_rows(t: Table, figs: dict[str, Any], names: Any, label: str = "") -> None:
    for name in names:
        if name not in figs:
            continue
        f = figs[name]
        q1, q3 = f["ratio_iqr"]
        api = f.get("api_s", f.get("step_s"))
        raw = f.get("raw_s", f.get("rnea_s"))
        t.rows.append(
            [
                text(name.replace("compiled_", "").replace("_", " ") + label),
                num(api, ".2f", 1e6),
                num(raw, ".2f", 1e6),
                num(f["ratio"], ".2f"),
                text(f"[{q1:.2f}, {q3:.2f}]"),
            ]
        )


def dynamics_speed(fig: dict[str, Any]) -> list[Table]:
    t = Table(
        f"Dynamics through armctl's API against raw Pinocchio on {fig['model']} ({fig['n']} joints)",
        ["call", "armctl [µs]", "raw Pinocchio [µs]", "ratio (median)", "quartiles"],
        notes="Ratios are medians of per-round ratios measured in interleaved rounds of the same run.",
    )
    _speed_rows(t, fig, ("mass_matrix", "inverse_dynamics", "regressor", "passivity_regressor"))
    _speed_rows(t, fig, ("compiled_regressor", "compiled_passivity_regressor"), " (compile=True)")
    return [t]


def controller_speed(fig: dict[str, Any]) -> list[Table]:
    t = Table(
        f"One control step on {fig['model']}, against one raw RNEA call",
        ["controller", "step [µs]", "RNEA [µs]", "ratio (median)", "quartiles"],
        notes="Ratios are medians of per-round ratios measured in interleaved rounds of the same run.",
    )
    names = [k for k, v in fig.items() if isinstance(v, dict) and "ratio" in v]
    _speed_rows(t, fig, names)
    _speed_rows(t, fig.get("compiled", {}), list(fig.get("compiled", {})), " (compile=True)")
    return [t]


def osc_speed(fig: dict[str, Any]) -> list[Table]:
    s = fig["qp_size"]
    t = Table(
        f"Operational-space QP step on {fig['model']} ({s['variables']} variables, {s['equalities']} equalities, "
        f"{s['inequalities']} inequalities; solved on q̈ alone)",
        ["states", "step [µs]", "against one RNEA", "against the bare solve", "optimality check [µs]", "fallbacks"],
    )
    names = (("circle", "along a 10 cm circle"), ("random", "random near the ready pose"))
    sets = [(fig[name], label) for name, label in names]
    sets += [(fig["numpy"][name], f"{label}, compile=False") for name, label in names if "numpy" in fig]
    for f, label in sets:
        t.rows.append(
            [
                text(label),
                num(f["step_s"], ".1f", 1e6),
                num(f["ratio_rnea"], ".2f", 1.0, "×"),
                num(f["ratio_bare"], ".2f", 1.0, "×"),
                num(f["check_s"], ".2f", 1e6),
                num(f["fallbacks"], "d"),
            ]
        )
    return [t]


def engines(data: dict[str, Any]) -> list[Table]:
    t = Table(
        f"Plant engines on {data['plant']}: error and cost per simulated second at each step",
        ["series", "scene", "step [ms]", "error [rad]", "cost [s per simulated s]"],
    )
    for name, d in data["series"].items():
        for scene in ("frictionless", "stiction"):
            for c in d.get(scene, []):
                t.rows.append(
                    [text(name), text(scene), num(c["step"], ".3g", 1e3), num(c["error"], ".2e"), num(c["cost"], ".3g")]
                )
    return [t]


def topp(data: dict[str, Any]) -> list[Table]:
    t = Table(
        f"TOPP-RA on a planar 2R arm: duration against the analytic {data['analytic_duration']:.6f} s",
        ["grid size N", "duration [s]", "|T_N − T| / T", "compute time [ms]"],
    )
    for n, d, e, c in zip(data["grids"], data["durations"], data["errors"], data["compute_s"], strict=True):
        t.rows.append([num(n, "d"), num(d, ".6f"), num(e, ".2e"), num(c, ".2f", 1e3)])
    return [t]


def stability(maps: dict[str, Any]) -> list[Table]:
    t = Table("Cells of each stability map", ["controller", "map", "stable", "marginal", "unstable"])
    for c, kinds in maps.items():
        if not isinstance(kinds, dict) or "rate_gain" not in kinds:
            continue
        for kind, d in kinds.items():
            cells = [o for row in d["outcome"] for o in row]
            t.rows.append(
                [
                    text(c.replace("_", " ")),
                    text(kind.replace("_", " × ")),
                    *(num(cells.count(o), "d") for o in ("stable", "marginal", "unstable")),
                ]
            )
    return [t]


def interaction(data: dict[str, Any]) -> list[Table]:
    """The interaction section's tables: force error against stiffness, the force-control and impedance borders,
    the observer's gain and its speed (see :mod:`armctl.bench.interaction`)."""
    tracking = data["force_tracking"]
    force = Table(
        f"Force error |f − {tracking['force']:g} N| at the end of a press [N], against the table's stiffness [N/m]",
        ["controller", *(f"{k:.0e}" for k in tracking["stiffness"])],
    )
    for name, rows in tracking["controllers"].items():
        force.rows.append([text(name), *(num(r["error"]) if r["outcome"] == "stable" else text(r["outcome"])
                                         for r in rows)])  # fmt: skip
    border = Table(
        "Force control: critical force gain K_F* [m/N], sampled-data prediction against closed-loop bisection",
        ["k_e [N/m]", "predicted", "simulated", "simulated / predicted"],
    )
    for r in data["force_border"]["rows"]:
        border.rows.append([num(r["stiffness"], ".0e"), num(r["predicted"]), num(r["border"]), num(r["ratio"])])
    impedance = Table(
        "Cartesian impedance: table stiffness k_e* [N/m] where the contact chatters, sampled-data prediction from the "
        "controller's Λ, K and D against closed-loop bisection",
        ["k_d [N/m]", "predicted", "simulated", "simulated / predicted"],
    )
    for r in data["impedance_map"]["rows"]:
        impedance.rows.append([num(r["k_d"], "g"), num(r["predicted"]), num(r["border"]), num(r["ratio"])])
    obs = Table(
        "Momentum observer: gain against noise, error and detection delay",
        ["K_O [1/s]", "noise [N·m]", "noise, closed form", "error after 5/K_O [N·m]", "delay [ms]", "lag's [ms]"],
    )
    for r in data["observer"]["rows"]:
        delay = text("false alarm") if r["false_alarm"] else num(r["delay"], ".1f", 1e3)
        obs.rows.append([num(r["gain"], "g"), num(r["noise"]), num(r["noise_predicted"]), num(r["error"]), delay,
                         num(r["lag_delay"], ".1f", 1e3)])  # fmt: skip
    speed = Table(
        "Momentum observer: one update(t, q, qd, tau_applied) on the Panda against one raw RNEA in the same run",
        ["variant", "update [µs]", "RNEA [µs]", "ratio", "ratio quartiles"],
    )
    for name, f in data["observer_speed"].items():
        if isinstance(f, dict):
            q1, q3 = f["ratio_iqr"]
            speed.rows.append([text(name), num(f["step_s"], ".2f", 1e6), num(f["rnea_s"], ".2f", 1e6),
                               num(f["ratio"], ".2f"), text(f"[{q1:.2f}, {q3:.2f}]")])  # fmt: skip
    return [force, border, impedance, obs, speed]


#: the table makers of the sections that have them
TABLES: dict[str, Callable[[Any], list[Table]]] = {
    "scenes": scenes,
    "stability_maps": stability,
    "topp_convergence": topp,
    "backends": backends,
    "integrators": integrators,
    "fidelity": fidelity,
    "engines": engines,
    "interaction": interaction,
    "dynamics_speed": dynamics_speed,
    "controller_speed": controller_speed,
    "osc_speed": osc_speed,
}
