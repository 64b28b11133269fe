"""What ``armctl bench`` runs and how it reads: the sections by key, in order, with their titles; the scenes; what
the run covers (stated in the report, so a reader does not infer it); each section's results as text; and the
parts a run may leave out, with the command that adds each one."""

from __future__ import annotations

import json
from collections.abc import Callable
from importlib.util import find_spec
from typing import Any

import numpy as np

from armctl.bench.outcomes import scenes_summary

#: the scenes of the scene matrix, in the order they run
SCENE_NAMES = ("pendulum", "planar_2r", "panda_topp", "panda_contact", "panda_press", "panda_wipe", "panda_collision")

#: the report's title of each section, in the order they run (``engines`` only where MuJoCo is installed)
SECTION_TITLES = {
    "scenes": "Scenes × controllers",
    "stability_maps": "Stability maps",
    "topp_convergence": "TOPP convergence",
    "backends": "Dynamics backends: cost against accuracy",
    "integrators": "Integrators: cost against accuracy",
    "fidelity": "Model fidelity: the cheapest sufficient model",
    "engines": "Plant engines: armctl's and MuJoCo's integrators, cost against accuracy",
    "interaction": "Interaction control: force tracking, stability borders, the momentum observer",
    "dynamics_speed": "Dynamics speed",
    "controller_speed": "Controller step speed",
    "osc_speed": "Operational-space QP step speed",
}

#: the duration of a run on 2 cores, as stated by ``armctl bench --help``: measured, with the generated C code
#: already built (a first run builds it, a few minutes more)
DURATION = {"quick": "under a minute", "full": "about 3 minutes"}

#: the extras that add a part of the report: the part, the module it needs, the command that installs it
EXTRAS = {
    "playback": ("3D playback of the scenes", "meshcat", 'pip install -e ".[view]"  (or: pip install meshcat)'),
    "engines": ("the plant engines section (MuJoCo)", "mujoco", 'pip install -e ".[mujoco]"  (or: pip install mujoco)'),
}

#: what the run covers and what it leaves out, stated in the report
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
    "contact (see the simulation guide's section on contact).",
    "Plant engines (with MuJoCo installed): the same closed loop on armctl's and on MuJoCo's integrators, the Panda "
    "without friction against a DOP853 reference, and held below breakaway with Coulomb friction, where the error "
    "is the creep (armctl's stick–slip model holds exactly; MuJoCo's frictionloss is a soft constraint).",
    "Interaction control: the Panda at its ready pose pressing on a table at 1 kHz with one period of measurement "
    "delay; each controller's gains fixed across the table stiffnesses; the stability borders at that pose (the "
    "sampled-data model is linear about it); the observer's trade-off for one push at the tool with white "
    "velocity noise; panda_collision's controller is computed torque (the scene matrix times it with the "
    "observer and the reaction).",
)


def model_sections() -> dict[str, Any]:
    """The sections that are a module with ``run(quick)``, ``plot(data, path)`` and ``summary(data)``, by key:
    backends, integrators, fidelity, the plant engines where MuJoCo is installed, and interaction control (their
    modules, in the order of :data:`SECTION_TITLES`)."""
    from armctl.bench import backends, fidelity, integrators, interaction

    sections: dict[str, Any] = {"backends": backends, "integrators": integrators, "fidelity": fidelity}
    if find_spec("mujoco") is not None:
        from armctl.bench import engines

        sections["engines"] = engines
    sections["interaction"] = interaction
    return sections


def available_sections() -> tuple[str, ...]:
    """The keys of the sections this installation can run, in order (``engines`` needs MuJoCo)."""
    mujoco = find_spec("mujoco") is not None
    return tuple(k for k in SECTION_TITLES if k != "engines" or mujoco)


def missing_extra(part: str) -> dict[str, str] | None:
    """Whether a part of the report (a key of :data:`EXTRAS`) cannot be made here: None if its package is
    installed, else {"part", "reason", "command"} to say so in the console and the report."""
    what, module, command = EXTRAS[part]
    if find_spec(module) is not None:
        return None
    return {"part": what, "reason": f"the {module} package is not installed", "command": command}


def _json_default(x: Any) -> Any:
    if isinstance(x, np.floating | np.integer):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    return str(x)


def to_json(figures: dict[str, Any]) -> str:
    """``figures`` as the text of ``figures.json`` (NumPy numbers and arrays as JSON numbers and lists)."""
    return json.dumps(figures, indent=1, default=_json_default)


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
    """TOPP-RA's duration error and compute time against the grid size."""
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
        **{k: mod.summary for k, mod in model_sections().items()},
        "dynamics_speed": dynamics_speed.report,
        "controller_speed": controller_speed.report,
        "osc_speed": osc_speed.report,
    }
    return texts[key](data) if key in texts else to_json(data)[:2000]


def warnings_summary(said: list[dict[str, Any]]) -> str:
    """The warnings a section's runs raised, one line each with its count (``said``: {"category", "message",
    "count"}), or "" if there were none."""
    if not said:
        return ""
    total = sum(w["count"] for w in said)
    lines = [f"{total} warning{'s' if total != 1 else ''} raised by this section's runs:"]
    lines += [f"  {w['count']} × {w['category']}: {w['message']}" for w in said]
    return "\n".join(lines)


def duration_text(seconds: float | None) -> str:
    """A measured duration for the report and the console: "0.42 s", "12 s", "3 min 5 s", or "not measured"."""
    if seconds is None or not np.isfinite(seconds):
        return "not measured"
    if seconds < 10.0:
        return f"{seconds:.2g} s"
    if seconds < 120.0:
        return f"{seconds:.0f} s"
    return f"{int(seconds // 60)} min {round(seconds % 60):d} s"


def summary(figures: dict[str, Any]) -> str:
    """Every section's text, in order, with the warnings its runs raised, and the parts left out (the report keeps
    it, below its tables).

    Parameters
    ----------
    figures : dict
        The figures of :func:`armctl.bench.suite.run_suite`.

    Returns
    -------
    str
    """
    parts = []
    for key in SECTION_TITLES:
        if key in figures:
            parts.append(section_summary(key, figures[key]))
            said = warnings_summary(figures.get("section_warnings", {}).get(key, []))
            if said:
                parts.append(said)
    parts += [skipped_text(s) for s in figures.get("skipped", [])]
    parts.append(f"total {duration_text(figures.get('total_seconds'))}")
    return "\n\n".join(parts)


def skipped_text(s: dict[str, str]) -> str:
    """One part a run left out, as a line: what, why, and the command that adds it."""
    return f"not in this report: {s['part']} ({s['reason']}); add with: {s['command']}"
