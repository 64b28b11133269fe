"""Benchmark section: model no more than a scene needs (term shares, cheapest sufficient controller model).

1. Term shares. Along a scene's reference (q_d, q̇_d, q̈_d sampled at :data:`SAMPLES` instants) the torque the
   arm requires is split into the terms of

       τ = M_l(q) q̈ + C_l(q, q̇) q̇ + g(q) + τ_rotor + τ_f(q̇) + Jᵀh_e

   * inertia M_l q̈ and Coriolis/centrifugal C_l q̇ of the links alone (the scene's exact model without
     rotors), gravity g;
   * rotor: the exact rigid torque (Lagrange backend with the rotors' gyroscopic coupling) minus the link-only
     terms above, i.e. k_r² I_m q̈ plus the coupling terms;
   * friction: the *plant's* friction at q̇_d (kinetic part; zero at rest);
   * contact: zero for the joint-space scenes benchmarked here (key kept for contact scenes).

   Each term's size is its RMS over the reference, √(mean_s ‖term(s)‖²) [N·m]; its share is that RMS divided
   by the sum of the terms' RMS (shares sum to 1).
2. Cheapest sufficient model. Computed torque at the scene's preset gains (``sc.gains("computed_torque")``)
   runs in closed loop with the scene's plant, integrator and rates, on candidate controller-side models:
   the scene's exact model and its reductions (no friction, no rotors, neither; a reduction identical to
   another model is skipped), each with the ``"pinocchio"`` and ``"lagrange"`` (CasADi VM, rotor coupling)
   backends — in quick mode the scene's own backend only where that leaves a reduction to compare (else both
   backends, so that the full model is never compared with itself alone), and the runs cut to
   :data:`QUICK_DURATION` seconds.
   The baseline ("the full model") is the scene's exact model on the scene's backend, the one the plant is
   simulated with: the scenes simulate their plant with the Pinocchio backend, which has no rotor coupling,
   so a controller that models the coupling is, against that plant, slightly wrong.

   The choice is the cheapest candidate whose RMS tracking error stays within :data:`FACTOR` × the
   baseline's and that did not diverge; candidates within :data:`TIE` of the cheapest one's compute time
   count as equally cheap (the difference is timing noise on a shared machine), and among those the one
   keeping fewer terms wins. Compute time is the median seconds per controller call, replaying states
   recorded in the baseline run through every candidate in interleaved rounds (the simulator's cost is not
   counted).
"""

from __future__ import annotations

import functools
import math
import operator
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from armctl._checks import FloatArray
from armctl.bench.charts import plain_log_ticks, pyplot, save_figure
from armctl.bench.standalone import section_main

if TYPE_CHECKING:
    from armctl.controllers.base import Controller
    from armctl.dynamics.base import Dynamics
    from armctl.model.robot import RobotModel
    from armctl.references import Reference

#: the joint-space scenes (computed torque is compared on them; the contact scene's controllers are
#: operational-space ones, outside this section)
SCENES: tuple[str, ...] = ("pendulum", "planar_2r", "panda_topp")
TERMS: tuple[str, ...] = ("inertia", "coriolis", "gravity", "rotor", "friction", "contact")
#: the chosen model's RMS tracking error may be at most this factor times the full model's
FACTOR = 2.0
#: reference samples for the term shares
SAMPLES = {True: 200, False: 500}
#: closed-loop runs are cut to this many seconds in quick mode
QUICK_DURATION = 2.0
#: (rotors, friction) kept by each variant of the scene's exact model
VARIANTS: dict[str, tuple[bool, bool]] = {
    "full": (True, True),
    "no_friction": (True, False),
    "no_rotors": (False, True),
    "rigid": (False, False),
}
BACKENDS: tuple[str, ...] = ("pinocchio", "lagrange")
#: relative compute-time difference below which two candidates count as equally cheap
TIE = 0.1


def model_terms(
    exact: RobotModel, plant: RobotModel, reference: Callable[[float], Reference], times: FloatArray
) -> dict[str, FloatArray]:
    """Each term of the required torque (see the module docstring) at ``times`` [s]: name → (S, n) [N·m].
    ``exact``: the controller-side full model; ``plant``: the true arm (its friction is used)."""
    import armctl

    links = armctl.Dynamics(exact.reduced(rotors=False, friction=False))
    full = (
        armctl.Dynamics(exact.reduced(friction=False), backend="lagrange", rotor_coupling=True)
        if exact.has_motors
        else None
    )
    plant_dyn = armctl.Dynamics(plant)
    out: dict[str, list[FloatArray]] = {k: [] for k in TERMS}
    for t in times:
        r = reference(float(t))
        q, qd, qdd = r.q, r.qd, r.qdd
        inertia = links.mass_matrix(q) @ qdd
        coriolis = links.coriolis_matrix(q, qd) @ qd
        gravity = links.gravity_torque(q)
        out["inertia"].append(inertia)
        out["coriolis"].append(coriolis)
        out["gravity"].append(gravity)
        rotor = (
            full.inverse_dynamics(q, qd, qdd) - (inertia + coriolis + gravity)
            if full is not None
            else np.zeros(exact.n)
        )
        out["rotor"].append(rotor)
        out["friction"].append(plant_dyn.friction_torque(qd))
        out["contact"].append(np.zeros(exact.n))
    return {k: np.array(v) for k, v in out.items()}


def term_shares(terms: dict[str, FloatArray]) -> dict[str, Any]:
    """RMS [N·m] of every term, √(mean_s ‖term(s)‖²), and its share of the sum of the terms' RMS
    (``sum_of_term_rms``; shares sum to 1); ``required_rms``: the RMS of the required torque itself, the sum of
    the terms (smaller than ``sum_of_term_rms`` where terms cancel)."""
    rms = {k: float(np.sqrt((v**2).sum(axis=1).mean())) for k, v in terms.items()}
    total = sum(rms.values())
    shares = {k: (r / total if total > 0 else 0.0) for k, r in rms.items()}
    per_joint = {k: np.sqrt((v**2).mean(axis=0)).tolist() for k, v in terms.items()}
    required = functools.reduce(operator.add, terms.values()) if terms else np.zeros((0, 0))
    return {
        "rms": rms,
        "shares": shares,
        "rms_per_joint": per_joint,
        "sum_of_term_rms": total,
        "required_rms": float(np.sqrt((required**2).sum(axis=1).mean())) if len(terms) else 0.0,
    }


def candidate_models(
    exact: RobotModel, backends: tuple[str, ...]
) -> dict[str, tuple[RobotModel, str, dict[str, bool]]]:
    """key "variant/backend" → (model, backend, terms kept) for every variant of :data:`VARIANTS` and backend
    in ``backends``; a variant identical to an earlier one (e.g. "no rotors" on an arm without motors) is
    left out."""
    seen: list[tuple[bool, bool]] = []
    out: dict[str, tuple[RobotModel, str, dict[str, bool]]] = {}
    for variant, (rotors, friction) in VARIANTS.items():
        eff = (rotors and exact.has_motors, friction and exact.has_friction)
        if eff in seen:
            continue
        seen.append(eff)
        model = exact.reduced(rotors=rotors, friction=friction)
        kept = {"rotors": eff[0], "friction": eff[1]}
        for backend in backends:
            out[f"{variant}/{backend}"] = (model, backend, kept)
    return out


def choose(
    candidates: dict[str, dict[str, Any]], baseline: str, factor: float = FACTOR, tie: float = TIE
) -> str | None:
    """The cheapest candidate (``compute_s``) with ``rms_error`` ≤ ``factor`` × the baseline's and not
    diverged; candidates within ``tie`` (relative) of the cheapest count as equally cheap and the one keeping
    fewer terms wins among them. None if the baseline itself diverged (or has no error): there is then no
    threshold to be sufficient against."""
    base = candidates[baseline]
    if base["diverged"] or not math.isfinite(base["rms_error"]):
        return None
    limit = factor * base["rms_error"]
    ok = [k for k, c in candidates.items() if not c["diverged"] and c["rms_error"] <= limit]
    cheapest = min(candidates[k]["compute_s"] for k in ok)
    tied = [k for k in ok if candidates[k]["compute_s"] <= (1.0 + tie) * cheapest]
    return min(tied, key=lambda k: (sum(candidates[k]["kept"].values()), candidates[k]["compute_s"]))


def _dynamics(model: RobotModel, backend: str) -> Dynamics:
    import armctl

    if backend == "lagrange":
        return armctl.Dynamics(model, backend="lagrange", rotor_coupling=True)
    return armctl.Dynamics(model)


def closed_loop(name: str, quick: bool, rounds: int = 5, timing_states: int = 100) -> dict[str, Any]:
    """Every candidate model of scene ``name`` under computed torque: RMS and max tracking error [rad],
    divergence, median compute time per controller call [s]; and the choice."""
    import warnings

    from armctl.bench.timing import interleaved
    from armctl.controllers import ComputedTorque
    from armctl.errors import SimulationWarning
    from armctl.scenes import scene
    from armctl.scenes.base import diverged_errors
    from armctl.sim import simulate
    from armctl.sim.options import regroup

    sc = scene(name)
    baseline = f"full/{sc.backend}"
    backends = (sc.backend,) if quick and len(candidate_models(sc.exact, (sc.backend,))) > 1 else BACKENDS
    gains = sc.gains("computed_torque")
    duration = min(sc.duration, QUICK_DURATION) if quick else sc.duration
    plant = sc.dynamics("plant")
    options = {"control_dt": sc.control_dt, "dt": sc.dt, "integrator": sc.integrator, "q0": sc.q0, **sc.sim_options}
    controllers: dict[str, Controller] = {}
    results: dict[str, Any] = {}
    recorded: Any = None
    for key, (model, backend, kept) in candidate_models(sc.exact, backends).items():
        ctrl = ComputedTorque(_dynamics(model, backend), gains["kp"], gains["kd"], gains.get("ki"))
        with warnings.catch_warnings():  # a limit overrun is recorded in the candidate's "status" instead
            warnings.simplefilter("ignore", SimulationWarning)
            res = simulate(plant, ctrl, sc.reference, duration, **regroup(options))
        want = np.array([sc.reference(float(t)).q for t in res.t])
        err = np.abs(res.q - want)
        controllers[key] = ctrl
        results[key] = diverged_errors(
            {
                "variant": key.split("/")[0],
                "backend": backend,
                "kept": kept,
                "rms_error": float(np.sqrt((err**2).mean())),
                "max_error": float(err.max()),
                "diverged": bool(res.diverged),
                "diverged_at": res.diverged_at,
                "status": res.status,
                "sim_wall_s": float(res.info["wall_time"]),
            }
        )
        if key == baseline:
            recorded = res
    idx = np.linspace(0, len(recorded.t) - 1, min(timing_states, len(recorded.t))).astype(int)
    states = [
        (float(recorded.t[k]), recorded.q_measured[k], recorded.qd_measured[k], sc.reference(float(recorded.t[k])))
        for k in idx
    ]

    def replay(ctrl: Controller) -> Callable[[], FloatArray]:
        pos = [0]

        def call() -> FloatArray:
            i = pos[0]
            pos[0] = (i + 1) % len(states)
            return ctrl(*states[i])

        return call

    times = interleaved({k: replay(c) for k, c in controllers.items()}, number=len(states), rounds=rounds)
    for k, t in times.items():
        results[k]["compute_s"] = t
    choice = choose(results, baseline)
    return {
        "duration": duration,
        "gains": {k: _plain(v) for k, v in gains.items()},
        "baseline": baseline,
        "threshold": FACTOR * results[baseline]["rms_error"],
        "tie": TIE,
        "candidates": results,
        "choice": choice,
        "choice_kept": results[choice]["kept"] if choice else None,
        "choice_backend": results[choice]["backend"] if choice else None,
    }


def _plain(x: Any) -> Any:
    """A gain as JSON (float or nested list)."""
    a = np.asarray(x, dtype=float)
    return float(a) if a.ndim == 0 else a.tolist()


def run(quick: bool = False) -> dict[str, Any]:
    """Term shares and the cheapest sufficient model for every scene of :data:`SCENES`; every number behind
    the chart (torques in N·m, errors in rad, times in s)."""
    from armctl.scenes import scene

    data: dict[str, Any] = {
        "factor": FACTOR,
        "terms": list(TERMS),
        "baseline": "full/<scene backend>",
        "controller": "computed_torque at the scene's preset gains",
        "scenes": {},
    }
    from armctl.bench.progress import steps

    for name in steps(SCENES, "fidelity: scenes"):
        sc = scene(name)
        times = np.linspace(0.0, sc.duration, SAMPLES[quick])
        shares = term_shares(model_terms(sc.exact, sc.plant, sc.reference, times))
        cl = closed_loop(name, quick, rounds=21 if quick else 31)
        data["scenes"][name] = {
            "plant": sc.plant.name,
            "joints": sc.plant.n,
            "samples": len(times),
            **shares,
            "closed_loop": cl,
        }
    return data


def summary(data: dict[str, Any]) -> str:
    """Per scene: the term shares and the chosen model."""
    lines = [
        f"model fidelity: each term's RMS torque as a share of the sum of the terms' RMS; cheapest model "
        f"within {data['factor']:g}× the full model's tracking error (computed torque)"
    ]
    for name, s in data["scenes"].items():
        shares = ", ".join(f"{k} {v:.0%}" for k, v in s["shares"].items() if v >= 0.005)
        cl = s["closed_loop"]
        b = cl["candidates"][cl["baseline"]]
        lines.append(f"  {name:11s} {shares}")
        if cl["choice"] is None:
            lines.append(
                f"  {'':11s} no choice: the full model {cl['baseline']} diverged at "
                f"{b['diverged_at']:.2f} s, so no model is sufficient against it (runs of "
                f"{cl['duration']:g} s)"
            )
            continue
        c = cl["candidates"][cl["choice"]]
        others = ", ".join(
            f"{k} {v['rms_error']:.2e} rad"
            for k, v in cl["candidates"].items()
            if k not in (cl["choice"], cl["baseline"]) and not v["diverged"]
        )
        if cl["choice"] == cl["baseline"]:
            within = [
                k
                for k, v in cl["candidates"].items()
                if k != cl["baseline"] and not v["diverged"] and v["rms_error"] <= cl["threshold"]
            ]
            verdict = (
                f"no reduction stays within {data['factor']:g}× its error"
                if not within
                else f"the cheapest of the models within {data['factor']:g}× its error"
            )
            lines.append(
                f"  {'':11s} {len(cl['candidates'])} models, runs of {cl['duration']:g} s: the full model "
                f"{cl['baseline']} ({b['compute_s'] * 1e6:.1f} µs/step, RMS error {b['rms_error']:.2e} rad) is "
                f"needed, {verdict}; the others: {others or 'none'}"
            )
        else:
            lines.append(
                f"  {'':11s} {len(cl['candidates'])} models, runs of {cl['duration']:g} s: choice {cl['choice']} "
                f"({c['compute_s'] * 1e6:.1f} µs/step, RMS error {c['rms_error']:.2e} rad) against the full model "
                f"{cl['baseline']} ({b['compute_s'] * 1e6:.1f} µs/step, {b['rms_error']:.2e} rad); the others: "
                f"{others or 'none'}"
            )
        diverged = [k for k, v in cl["candidates"].items() if v["diverged"]]
        if diverged:
            lines.append(
                f"  {'':11s} diverged: "
                + ", ".join(f"{k} at {cl['candidates'][k]['diverged_at']:.2f} s" for k in diverged)
            )
    return "\n".join(lines)


def plot(data: dict[str, Any], path: Path) -> None:
    """Stacked bars of the term shares per scene, and per scene a log-log scatter of RMS tracking error
    against compute time per step for the candidate models, the threshold drawn and the choice ringed;
    writes a PNG to ``path``."""
    plt = pyplot()
    scenes = data["scenes"]
    cols = 2  # two panels a row: readable at a page's width
    rows = -(-(1 + len(scenes)) // cols)
    fig, grid = plt.subplots(rows, cols, figsize=(6.2 * cols, 4.9 * rows), squeeze=False)
    for extra in grid.flat[1 + len(scenes) :]:
        extra.set_visible(False)
    ax = grid.flat[0]
    names = list(scenes)
    bottom = np.zeros(len(names))
    for i, term in enumerate(data["terms"]):
        vals = np.array([scenes[n]["shares"][term] for n in names])
        ax.bar(names, vals, bottom=bottom, label=term, color=f"C{i}")
        bottom += vals
    ax.set_ylim(0, 1)
    ax.set_ylabel("share of Σ term RMS torques")
    ax.set_title("Model terms along each reference", fontsize=10)
    ax.legend(fontsize=9, loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=3)
    ax.tick_params(axis="x", labelsize=8)
    markers = {"pinocchio": "o", "lagrange": "s"}
    for ax, name in zip(grid.flat[1 : 1 + len(names)], names, strict=True):
        cl = scenes[name]["closed_loop"]
        for key, c in cl["candidates"].items():
            us = c["compute_s"] * 1e6
            if c["diverged"]:  # no error to plot: a cross at the top of the panel, at its compute time
                ax.plot(us, 0.97, "x", color="C3", ms=9, mew=2, transform=ax.get_xaxis_transform(), zorder=4)
                ax.annotate(
                    f"{key}: diverged at {c['diverged_at']:.2f} s",
                    (us, 0.97),
                    xycoords=ax.get_xaxis_transform(),
                    textcoords="offset points",
                    xytext=(5, -10),
                    fontsize=9,
                    color="C3",
                )
                continue
            ax.scatter([us], [c["rms_error"]], marker=markers[c["backend"]], color="C0", zorder=3)
            left = c["backend"] == "pinocchio"  # usually the cheaper: its label goes left, Lagrange's right
            ax.annotate(
                c["variant"],
                (us, c["rms_error"]),
                textcoords="offset points",
                xytext=(-5 if left else 5, 3),
                ha="right" if left else "left",
                fontsize=9,
            )
        if cl["choice"] is not None:
            ch = cl["candidates"][cl["choice"]]
            ax.scatter(
                [ch["compute_s"] * 1e6],
                [ch["rms_error"]],
                s=220,
                facecolors="none",
                edgecolors="C2",
                linewidths=2,
                zorder=4,
                label=f"choice: {cl['choice']}",
            )
            ax.axhline(cl["threshold"], color="C2", ls="--", lw=1, label=f"{data['factor']:g}× full model's error")
        else:
            ax.text(0.02, 0.02, "no choice: the full model diverged", transform=ax.transAxes, fontsize=9, color="C3")
        costs = [c["compute_s"] * 1e6 for c in cl["candidates"].values()]
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(min(costs) / 4.0, max(costs) * 4.0)
        plain_log_ticks(ax)
        ax.margins(y=0.2)
        ax.set_xlabel("controller compute time per step [µs]")
        ax.set_ylabel("RMS tracking error [rad]")
        arm = scenes[name]
        who = f"{arm['plant']} ({arm['joints']} joints)" if "plant" in arm else name
        ax.set_title(f"{name}: {who}\ncomputed torque on candidate models, {cl['duration']:g} s runs", fontsize=11)
        ax.grid(True, which="both", alpha=0.3)
        if cl["choice"] is not None:
            ax.legend(fontsize=9, loc="best")
    shown = dict.fromkeys(c["backend"] for s in scenes.values() for c in s["closed_loop"]["candidates"].values())
    symbols = {"pinocchio": "○ Pinocchio", "lagrange": "□ Lagrange VM"}
    fig.suptitle(f"Model no more than a scene needs ({', '.join(symbols[b] for b in shown)})", fontsize=11)
    save_figure(fig, path)


def main() -> None:
    section_main(run, summary, plot, "fidelity.png")


if __name__ == "__main__":
    main()
