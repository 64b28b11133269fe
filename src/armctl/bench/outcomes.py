"""What a row of the scene matrix says: how a run failed or what it did beyond the plant's limits (its
outcome), which arm and task its scene is, and the matrix as text."""

from __future__ import annotations

from typing import Any


def failure_note(r: dict[str, Any], brief: bool = True) -> str | None:
    """How a method failed on its scene, or None: the error's type (``brief``, for a chart) or its whole text."""
    if r.get("failed"):
        return f"failed: {r['failed'].split(':')[0]}" if brief else f"FAILED ({r['failed']})"
    if r["diverged"]:
        return f"diverged at {r['diverged_at']:.2f} s"
    return None


def outcome(r: dict[str, Any]) -> str:
    """A scene row's outcome in words: how it failed or diverged, else what it did beyond the plant's limits
    (the share of samples saturated, over the velocity limit, outside the position range) and whether a
    contact was lost; "ok" for a run within every limit.

    Parameters
    ----------
    r : dict
        A row of :func:`scene_matrix`.

    Returns
    -------
    str
    """
    failure = failure_note(r, brief=False)
    if failure:
        return failure
    notes = []
    for key, words in (
        ("torque_violation_share", "saturated"),
        ("velocity_violation_share", "over velocity limit"),
        ("position_violation_share", "outside position range"),
    ):
        share = r.get(key, 0.0)
        if isinstance(share, float) and share > 0.0:
            notes.append(f"{words} on {share:.1%}")
    if r.get("contact_lost"):
        notes.append("contact lost")
    return "; ".join(notes) if notes else "ok"


def scene_title(name: str, rows: list[dict[str, Any]]) -> str:
    """A scene's arm and task, from its rows (``plant``, ``joints``, ``description``): e.g. "panda (7 joints):
    Panda tracking a time-optimal path …"; the name alone if no row has them (a scene that failed).

    Parameters
    ----------
    name : str
        The scene.
    rows : list of dict
        Rows of :func:`scene_matrix`.

    Returns
    -------
    str
    """
    for r in rows:
        if r["scene"] == name and r.get("description"):
            joints = f"{r['joints']} joint{'s' if r['joints'] != 1 else ''}"
            return f"{r['plant']} ({joints}): {r['description']}"
    return name


def error_units(rows: list[dict[str, Any]]) -> str:
    """The unit of each scene's errors, as the scenes report it (``error_unit``; rad where a scene does not say),
    e.g. "rad (pendulum, planar_2r), m (panda_contact), N (panda_press)".

    Parameters
    ----------
    rows : list of dict
        The scene matrix's rows.

    Returns
    -------
    str
    """
    units: dict[str, list[str]] = {}
    for r in rows:
        scenes = units.setdefault(str(r.get("error_unit", "rad")), [])
        if r["scene"] not in scenes:
            scenes.append(r["scene"])
    return ", ".join(f"{unit} ({', '.join(scenes)})" for unit, scenes in units.items())


def scenes_summary(rows: list[dict[str, Any]]) -> str:
    """The scene matrix as text: one row per scene and method."""
    lines = [
        f"errors in {error_units(rows)}; force: RMS "
        "normal-force error after settling [N]; over limits: share of samples beyond the effort limit / "
        "velocity limit (+1 %) / position range; a run that diverged has no error (its error until then is in "
        "figures.json)",
        f"{'scene':14s} {'method':26s} {'RMS err':>9s} {'max err':>9s} {'force':>6s} {'step µs':>8s} "
        f"{'τ RMS':>8s}  {'over τ / q̇ / q':>17s}  outcome",
    ]
    for r in rows:
        force = f"{r['force_rms_error']:6.2f}" if "force_rms_error" in r else f"{'-':>6s}"
        over = " / ".join(
            f"{r.get(f'{k}_violation_share', float('nan')):.1%}" for k in ("torque", "velocity", "position")
        )
        lines.append(
            f"{r['scene']:14s} {r['method']:26s} {r['rms_error']:9.2e} {r['max_error']:9.2e} {force} "
            f"{r['compute_s'] * 1e6:8.1f} {r['torque_rms']:8.2f}  {over:>17s}  {outcome(r)}"
        )
    return "\n".join(lines)
