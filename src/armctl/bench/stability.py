"""Stability maps: where each controller stays stable, as a function of gain and control rate, and of gain
and model error — simulated cell by cell, with the border theory predicts drawn over them.

The scenario is the geared pendulum turned into a horizontal plane (one joint, inertia J, no gravity: scaling
the controller's inertial parameters by f then scales its M̂ exactly, with no gravity offset to confuse the
outcome) regulating a set-point from a small offset, with one control period of measurement delay.
Linearised, every law here is a PD on a double integrator with
equivalent gains (K_p, K_d) [1/s², 1/s], so the discrete-time analysis of :mod:`armctl.tuning.sampled`
(zero-order hold + delay) gives the border:

* computed torque with gains k·(K_p⁰, K_d⁰) and an inertia estimate M̂ = f·M: (K_p, K_d) = k f (K_p⁰, K_d⁰);
* PD + gravity with gains k·(K_p⁰, K_d⁰) [N·m/rad, N·m·s/rad]: k (K_p⁰, K_d⁰)/J;
* passivity-based with K_D = k K_D⁰, Λ: (k K_D⁰ Λ/J, fΛ + k K_D⁰/J).

The adaptive law runs with the adaptation gain Γ of the pendulum scene's preset (no projection), starting
from the wrong model's θ̂; its border is drawn for θ̂ frozen (the passivity-based one), so cells where
adaptation itself destabilises the loop fall inside it (with Γ → 0 the map would be the passivity map).

A cell is *stable* when the error shrinks below a tenth of the initial offset, *unstable* when the run
diverges or the error ends larger than it started, *marginal* otherwise.

Beside the sampled-data border the maps draw the textbook's continuous-time conditions
(:mod:`armctl.tuning.conditions`, drawn by :mod:`armctl.bench.textbook_borders`), and say where they are
conservative:

* computed torque with M̂ = f·M: the premise ‖I − M⁻¹M̂‖ = |1 − f| < 1 of the robust-control chapters (f < 2),
  and the small-gain condition |1 − f| γ(k) < 1 (γ the L1 norm of the error filter's impulse response at the
  gains k·(K_p⁰, K_d⁰)), from which the largest f each gain is guaranteed for; the cells show how far beyond it
  the loop still settles, and that at high gains sampling, which neither condition sees, fails first;
* PD + gravity on this gravity-free arm: k_g = 0, so the textbook guarantees every gain; only sampling limits it;
* PD with desired gravity compensation, on the pendulum with gravity (:mod:`armctl.bench.desired_gravity_map`):
  K_p > k_g against the exact border of a second equilibrium, set-point by set-point.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from concurrent.futures import Executor
from typing import Any

import numpy as np

import armctl
from armctl.bench.textbook_borders import caption as caption  # the report's captions, re-exported
from armctl.bench.textbook_borders import computed_torque_textbook, draw_textbook
from armctl.controllers import Adaptive, ComputedTorque, PassivityBased, PDGravity
from armctl.tuning.sampled import spectral_radius

SET_POINT, OFFSET = 0.3, 0.05
KP0, KD0 = 100.0, 20.0  # computed torque [1/s², 1/s]
LAMBDA0 = 10.0  # passivity-based Λ [1/s]


def _pendulum() -> armctl.RobotModel:
    from dataclasses import replace

    return replace(armctl.models.pendulum().reduced(friction=False), gravity=np.zeros(3))


def _inertia() -> float:
    return float(armctl.Dynamics(_pendulum()).mass_matrix([SET_POINT])[0, 0])


def equivalent_gains(controller: str, k: float, f: float) -> tuple[float, float]:
    """(K_p, K_d) of the linearised loop for gain multiplier k and inertia-estimate factor f."""
    j = _inertia()
    if controller == "computed_torque":
        return k * f * KP0, k * f * KD0
    if controller == "pd_gravity":  # gains k·(K_p⁰, K_d⁰)·J act on the true inertia J: per unit inertia
        return k * KP0, k * KD0
    kd = k * LAMBDA0 * j  # K_D⁰ = Λ J: the pole of ṡ at Λ
    return kd * LAMBDA0 / j, f * LAMBDA0 + kd / j


def critical_multiplier(controller: str, f: float, period: float, delay: int = 1) -> float:
    """The k at which the equivalent sampled loop's spectral radius reaches 1 (bisection on log k; at f = 1 for
    computed torque this is the gain margin python-control reports, see :class:`SampledDataAnalysis`); 0 if
    the loop is unstable already at k = 1e-3, inf if it is stable up to k = 1e4."""

    def radius(k: float) -> float:
        return spectral_radius(*equivalent_gains(controller, k, f), period, delay)

    lo, hi = 1e-3, 1e4
    if radius(hi) < 1:
        return math.inf
    if radius(lo) >= 1:  # unstable already at the smallest multiplier tried: no stable range to bound
        return 0.0
    for _ in range(50):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if radius(mid) < 1 else (lo, mid)
    return lo


def make_controller(controller: str, k: float, f: float) -> Any:
    """The controller with gain multiplier k, on a model whose inertias are f times the truth."""
    truth = _pendulum()
    dyn = armctl.Dynamics(truth if f == 1.0 else truth.perturbed(mass=f, inertia=f, rotor=f))
    j = _inertia()
    if controller == "computed_torque":
        return ComputedTorque(dyn, k * KP0, k * KD0)
    if controller == "pd_gravity":  # gains scaled by the true inertia so k means the same closed-loop pole
        return PDGravity(dyn, k * KP0 * j, k * KD0 * j)
    if controller == "passivity":
        return PassivityBased(dyn, LAMBDA0, k * LAMBDA0 * j)
    if controller == "adaptive":
        return Adaptive(dyn, LAMBDA0, k * LAMBDA0 * j, gamma=_adaptive_gamma())
    raise KeyError(controller)


@functools.cache
def _adaptive_gamma() -> Any:
    """Γ of the pendulum scene's adaptive preset (the arm of this scenario, with gravity)."""
    from armctl.tuning.presets import load_preset

    return np.array(load_preset("pendulum", "adaptive")["gains"]["gamma"], dtype=float)


def run_cell(controller: str, k: float, f: float, period: float, duration: float = 2.0, dt_max: float = 1e-3) -> str:
    """Simulate one cell (``duration`` [s], integration step ≤ ``dt_max``) and classify it (an unstable cell
    overruns the pendulum's limits by design: the run's warnings about it are not printed)."""
    import warnings

    from armctl.errors import SimulationWarning
    from armctl.sim import Forces, Sensing, StopRules, simulate

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SimulationWarning)
        res = simulate(
            _pendulum(),
            make_controller(controller, k, f),
            armctl.Reference([SET_POINT]),
            duration,
            q0=[SET_POINT + OFFSET],
            control_dt=period,
            dt=_step(period, dt_max),
            sensing=Sensing(delay=1),
            forces=Forces(friction="smooth"),
            stop=StopRules(max_velocity=1e3),
            saturate=False,
        )
    if res.diverged:
        return "unstable"
    err = abs(res.q[-1, 0] - SET_POINT)
    if err < 0.1 * OFFSET:
        return "stable"
    return "unstable" if err > OFFSET else "marginal"


def _step(period: float, dt_max: float) -> float:
    """The largest step ≤ dt_max that divides the control period."""
    return period / math.ceil(period / dt_max - 1e-9)


def maps(
    quick: bool = False,
    executor: Executor | str | None = None,
    controllers: tuple[str, ...] = ("computed_torque", "pd_gravity", "passivity", "adaptive"),
) -> dict[str, Any]:
    """For each controller a "rate_gain" map (control period × k, exact model) and a "gain_error" map
    (k × f at 100 Hz), each with its theory border; every cell simulated."""
    from armctl.sim import sweep

    rates = [100.0, 1000.0] if quick else [100.0, 200.0, 500.0, 1000.0, 2000.0]
    ks = list(np.geomspace(0.5, 64.0, 5 if quick else 9))
    fs = [0.5, 1.0, 2.0] if quick else [0.5, 0.75, 1.0, 1.5, 2.0, 3.0]
    duration, dt_max = (1.5, 2e-3) if quick else (2.0, 1e-3)
    base_period = 0.01
    out: dict[str, Any] = {
        "set_point": SET_POINT,
        "offset": OFFSET,
        "duration": duration,
        "delay_periods": 1,
        "k": ks,
        "rates_hz": rates,
        "inertia_factors": fs,
    }
    cases: list[dict[str, Any]] = []
    index: list[tuple[str, str, int, int]] = []
    for c in controllers:
        for i, r in enumerate(rates):
            for j, k in enumerate(ks):
                cases.append(
                    {
                        "controller": c,
                        "k": float(k),
                        "f": 1.0,
                        "period": 1.0 / r,
                        "duration": duration,
                        "dt_max": dt_max,
                    }
                )
                index.append((c, "rate_gain", i, j))
        if c == "pd_gravity":
            continue  # PD + gravity's loop gain does not depend on an inertia estimate
        for i, f in enumerate(fs):
            for j, k in enumerate(ks):
                cases.append(
                    {
                        "controller": c,
                        "k": float(k),
                        "f": float(f),
                        "period": base_period,
                        "duration": duration,
                        "dt_max": dt_max,
                    }
                )
                index.append((c, "gain_error", i, j))
    outcomes = sweep(cases, run=run_cell, executor=executor, progress=True, on_error="raise")
    for c in controllers:
        out[c] = {
            "rate_gain": {
                "outcome": [[""] * len(ks) for _ in rates],
                "border_k": [critical_multiplier(c, 1.0, 1.0 / r) for r in rates],
            }
        }
        if c != "pd_gravity":
            out[c]["gain_error"] = {
                "outcome": [[""] * len(ks) for _ in fs],
                "border_k": [critical_multiplier(c, f, base_period) for f in fs],
            }
    for (c, kind, i, j), o in zip(index, outcomes, strict=True):
        out[c][kind]["outcome"][i][j] = o
    if "computed_torque" in controllers:
        out["computed_torque"]["gain_error"]["textbook"] = computed_torque_textbook(
            ks, fs, out["computed_torque"]["gain_error"]["outcome"], KP0, KD0
        )
    if "pd_gravity" in controllers:
        from armctl.bench.desired_gravity_map import desired_gravity_map

        out["pd_desired_gravity"] = desired_gravity_map(quick=quick, executor=executor)
    return out


def plot(data: dict[str, Any], path_for: Callable[[str], Any]) -> list[str]:
    """One PNG per controller (two panels); returns the file names."""
    from armctl.bench.charts import plain_log_ticks, pyplot, save_figure

    plt = pyplot()
    colour = {"stable": "#2a9d4a", "marginal": "#e9c46a", "unstable": "#d62828"}
    names = []
    for c in ("computed_torque", "pd_gravity", "passivity", "adaptive"):
        if c not in data:
            continue
        panels = [("rate_gain", "control rate [Hz]", data["rates_hz"])]
        if "gain_error" in data[c]:
            panels.append(("gain_error", "controller inertia / true inertia", data["inertia_factors"]))
        fig, axes = plt.subplots(1, len(panels), figsize=(5.5 * len(panels), 4.8), squeeze=False)
        for ax, (kind, ylabel, ys) in zip(axes[0], panels, strict=True):
            m = data[c][kind]
            for i, y in enumerate(ys):
                for j, k in enumerate(data["k"]):
                    ax.scatter(k, y, s=160, marker="s", color=colour[m["outcome"][i][j]])
            ax.plot(
                m["border_k"],
                ys,
                "k--",
                label="theory: sampled-data border" + (" (θ̂ frozen)" if c == "adaptive" else ""),
            )
            ax.set(
                xscale="log",
                yscale="log",
                xlabel="gain multiplier k",
                ylabel=ylabel,
                title=f"{c.replace('_', ' ')}: {kind.replace('_', ' × ')}\n"
                "one-joint pendulum, horizontal plane, 1 period of delay",
            )
            draw_textbook(ax, c, kind, m, data["k"])
            plain_log_ticks(ax)
            present = {o for row in m["outcome"] for o in row}  # only the outcomes the map has
            keys = [
                plt.Line2D([], [], ls="", marker="s", ms=8, color=colour[o], label=f"{o} (simulated cell)")
                for o in colour
                if o in present
            ]
            handles = [*keys, *ax.get_legend_handles_labels()[0]]
            # below the axes: inside, the key covered cells
            ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, fontsize=8)
        name = f"stability_{c}.png"
        save_figure(fig, path_for(name))
        names.append(name)
    if "pd_desired_gravity" in data:
        from armctl.bench.desired_gravity_map import plot as plot_desired_gravity

        name = "stability_pd_desired_gravity.png"
        plot_desired_gravity(data["pd_desired_gravity"], path_for(name))
        names.append(name)
    return names
