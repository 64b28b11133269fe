"""Benchmark section: the dynamics backends' cost against their accuracy.

For each arm, the inverse dynamics τ = M q̈ + C q̇ + g + τ_f is evaluated by every candidate on the same
random states, and compared with the exact reference: the ``"lagrange"`` backend with ``rotor_coupling=True``
on the full model (rotors with their gyroscopic coupling k_r I_m q̇_i z_mᵀω_{i−1}, friction).

Candidates (those identical to another on an arm — e.g. "no rotors" on an arm without motors — are skipped):

* ``pinocchio``: full model, rotors as reflected inertia (armature) only;
* ``pinocchio_no_friction``, ``pinocchio_no_rotors``, ``pinocchio_rigid``: the Pinocchio backend on the
  simplified models ``reduced(friction=False)``, ``reduced(rotors=False)`` and both;
* ``lagrange_vm_nc`` / ``lagrange_vm``: CasADi's virtual machine without / with rotor coupling (the latter *is*
  the reference: error 0 by construction);
* ``lagrange_compiled``: generated C code with rotor coupling (compiled once, cached on disk). Only on the
  arms of :data:`COMPILED_ARMS` — in quick mode the small planar 2R only, the compile cost of the larger arms
  (~20 s each on a first build) being outside a quick budget.

accuracy: relative RMS error √(Σ_s ‖τ_s − τ*_s‖²) / √(Σ_s ‖τ*_s‖²) over the states s (dimensionless).
cost: median seconds per ``inverse_dynamics`` call over interleaved rounds (:func:`armctl.bench.timing.
interleaved`), cycling through the states.
states: q uniform within the joint limits (clipped to ±π), q̇ uniform in ±min(velocity limit, 2) rad/s,
q̈ uniform in ±5 rad/s², from a fixed seed.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from armctl._checks import FloatArray
from armctl.bench.charts import pyplot, save_figure
from armctl.bench.standalone import section_main

if TYPE_CHECKING:
    from armctl.dynamics.base import Dynamics
    from armctl.model.robot import RobotModel

ARMS = {True: ("planar_2r", "puma560", "panda"), False: ("planar_2r", "puma560", "panda")}
COMPILED_ARMS = {True: ("planar_2r",), False: ("planar_2r", "puma560", "panda")}
LABELS = {
    "pinocchio": "Pinocchio, full model",
    "pinocchio_no_friction": "Pinocchio, no friction",
    "pinocchio_no_rotors": "Pinocchio, no rotors",
    "pinocchio_rigid": "Pinocchio, no rotors/friction",
    "lagrange_vm_nc": "Lagrange VM, no rotor coupling",
    "lagrange_vm": "Lagrange VM, rotor coupling (reference)",
    "lagrange_compiled": "Lagrange compiled C, rotor coupling",
}
#: a zero error is drawn at this value on the log axis
ZERO_ERROR_PLOT = 1e-17


def arm_model(name: str) -> RobotModel:
    """The arm called ``name``; the Panda with the illustrative joint friction of the ``panda_topp`` scene
    (the bare URDF has none), so that dropping friction is a real simplification on every arm."""
    import armctl

    if name == "panda":
        from armctl.scenes.panda_topp import panda_with_friction

        return panda_with_friction()
    return getattr(armctl.models, name)()


def random_states(model: RobotModel, count: int, seed: int = 0) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``count`` random (q [rad], q̇ [rad/s], q̈ [rad/s²]) rows, see the module docstring."""
    rng = np.random.default_rng(seed)
    lo = np.maximum(np.asarray(model.lower), -math.pi)
    hi = np.minimum(np.asarray(model.upper), math.pi)
    vmax = np.minimum(np.asarray(model.velocity_limit), 2.0)
    q = rng.uniform(lo, hi, (count, model.n))
    qd = rng.uniform(-vmax, vmax, (count, model.n))
    qdd = rng.uniform(-5.0, 5.0, (count, model.n))
    return q, qd, qdd


def candidates(model: RobotModel, compiled: bool) -> dict[str, Callable[[], Dynamics]]:
    """Builders of the candidate Dynamics objects for ``model`` (identical variants left out)."""
    import armctl

    out: dict[str, Callable[[], Dynamics]] = {"pinocchio": lambda: armctl.Dynamics(model)}
    if model.has_friction:
        out["pinocchio_no_friction"] = lambda: armctl.Dynamics(model.reduced(friction=False))
    if model.has_motors:
        out["pinocchio_no_rotors"] = lambda: armctl.Dynamics(model.reduced(rotors=False))
    if model.has_motors and model.has_friction:
        out["pinocchio_rigid"] = lambda: armctl.Dynamics(model.reduced(rotors=False, friction=False))
    out["lagrange_vm_nc"] = lambda: armctl.Dynamics(model, backend="lagrange", rotor_coupling=False)
    out["lagrange_vm"] = lambda: armctl.Dynamics(model, backend="lagrange", rotor_coupling=True)
    if compiled:
        out["lagrange_compiled"] = lambda: armctl.Dynamics(model, backend="lagrange", rotor_coupling=True, compile=True)
    return out


def relative_rms(tau: FloatArray, ref: FloatArray) -> float:
    """√(Σ‖τ − τ*‖²) / √(Σ‖τ*‖²) over all rows (dimensionless)."""
    return float(np.sqrt(((tau - ref) ** 2).sum() / (ref**2).sum()))


def measure_arm(
    name: str, compiled: bool, states: int = 200, number: int = 200, rounds: int = 5, seed: int = 0
) -> dict[str, Any]:
    """Every candidate on arm ``name``: relative RMS error against the coupled Lagrange reference and median
    seconds per inverse-dynamics call."""
    import armctl
    from armctl.bench.timing import interleaved

    model = arm_model(name)
    q, qd, qdd = random_states(model, states, seed)
    exact = armctl.Dynamics(model, backend="lagrange", rotor_coupling=True)
    ref = np.array([exact.inverse_dynamics(*row) for row in zip(q, qd, qdd, strict=True)])
    dyns: dict[str, Any] = {}
    build: dict[str, float] = {}
    for key, make in candidates(model, compiled).items():
        t0 = time.perf_counter()
        dyns[key] = make()
        build[key] = time.perf_counter() - t0
    taus = {k: np.array([d.inverse_dynamics(*row) for row in zip(q, qd, qdd, strict=True)]) for k, d in dyns.items()}
    rows = list(zip(q, qd, qdd, strict=True))

    def cycling(d: Dynamics) -> Callable[[], FloatArray]:
        it = [0]

        def call() -> FloatArray:
            i = it[0]
            it[0] = (i + 1) % len(rows)
            return d.inverse_dynamics(*rows[i])

        return call

    times = interleaved({k: cycling(d) for k, d in dyns.items()}, number=number, rounds=rounds)
    coupling = (
        relative_rms(taus["lagrange_vm_nc"], ref) if model.has_motors else 0.0
    )  # the rotor-coupling term's own share of τ
    cands = {
        k: {
            "label": LABELS[k],
            "backend": dyns[k].backend,
            "error": relative_rms(taus[k], ref),
            "cost_s": times[k],
            "build_s": build[k],
        }
        for k in dyns
    }
    return {
        "arm": name,
        "n": model.n,
        "has_motors": bool(model.has_motors),
        "has_friction": bool(model.has_friction),
        "states": states,
        "rotor_coupling_share": coupling,
        "tau_rms": float(np.sqrt((ref**2).sum(axis=1).mean())),
        "candidates": cands,
    }


def run(quick: bool = False) -> dict[str, Any]:
    """Measure every arm; returns every number behind the chart (errors dimensionless, costs in seconds)."""
    number, rounds, states = (100, 15, 100) if quick else (200, 31, 300)
    from armctl.bench.progress import steps

    arms = {
        name: measure_arm(name, name in COMPILED_ARMS[quick], states, number, rounds)
        for name in steps(ARMS[quick], "backends: arms")
    }
    return {
        "reference": "lagrange backend, rotor_coupling=True, full model (friction included)",
        "error": "relative RMS of inverse_dynamics over random states",
        "cost": "median seconds per inverse_dynamics call, interleaved rounds",
        "number": number,
        "rounds": rounds,
        "arms": arms,
    }


def summary(data: dict[str, Any]) -> str:
    """One line per arm and candidate: per-call cost [µs] and relative error."""
    lines = [f"dynamics backends: cost vs accuracy of inverse dynamics (reference: {data['reference']})"]
    for name, arm in data["arms"].items():
        lines.append(f"  {name} ({arm['n']} joints; rotor coupling {arm['rotor_coupling_share']:.1e} of τ):")
        for k, c in sorted(arm["candidates"].items(), key=lambda kv: kv[1]["cost_s"]):
            lines.append(f"    {k:22s} {c['cost_s'] * 1e6:8.2f} µs/call   error {c['error']:.1e}")
    return "\n".join(lines)


def plot(data: dict[str, Any], path: Path) -> None:
    """Log-log chart, one panel per arm: per-call cost [s] against relative RMS error, labelled points (a zero
    error drawn at :data:`ZERO_ERROR_PLOT`); writes a PNG to ``path``."""
    plt = pyplot()

    arms = data["arms"]
    cols = min(2, len(arms))  # two panels a row: readable at a page's width
    rows = -(-len(arms) // cols)
    fig, grid = plt.subplots(rows, cols, figsize=(6.0 * cols, 4.6 * rows), squeeze=False)
    axes = grid.flat[: len(arms)]
    for ax in grid.flat[len(arms) :]:
        ax.set_visible(False)
    colors = {k: f"C{i}" for i, k in enumerate(LABELS)}
    for ax, (name, arm) in zip(axes, arms.items(), strict=True):
        ranked = sorted(arm["candidates"].items(), key=lambda kv: kv[1]["cost_s"])
        for i, (k, c) in enumerate(ranked):
            e = max(c["error"], ZERO_ERROR_PLOT)
            ax.scatter([e], [c["cost_s"]], color=colors[k], label=c["label"], zorder=3)
            ax.annotate(
                k,
                (e, c["cost_s"]),
                textcoords="offset points",
                xytext=(4, 3 if i % 2 else -11),
                fontsize=9,
                ha="right" if e > 1e-6 else "left",
            )
        ax.set_xlim(ZERO_ERROR_PLOT / 10, 10.0)
        ax.margins(y=0.2)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(f"{name} ({arm['n']} joints{', motors' if arm['has_motors'] else ''})", fontsize=11)
        ax.set_xlabel("relative RMS error of τ vs exact Lagrange")
        ax.set_ylabel("median time per inverse_dynamics call [s]")
        ax.grid(True, which="both", alpha=0.3)
    handles: dict[str, Any] = {}
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(lab, h)
    spare = list(grid.flat[len(arms) :])
    if spare:  # the key in the empty panel
        spare[0].set_visible(True)
        spare[0].axis("off")
        spare[0].legend(list(handles.values()), list(handles), loc="center", fontsize=10, title="backend")
    else:
        fig.legend(list(handles.values()), list(handles), loc="lower center", ncol=3, fontsize=10)
    fig.suptitle(
        f"Dynamics backends: cost vs accuracy (points: backends, colour in the key; zero error drawn at "
        f"{ZERO_ERROR_PLOT:g})",
        fontsize=12,
    )
    save_figure(fig, path, rect=(0, 0.0 if spare else 0.12 / rows, 1, 0.96))


def main() -> None:
    section_main(run, summary, plot, "backends.png")


if __name__ == "__main__":
    main()
