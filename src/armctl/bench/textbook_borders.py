"""The textbook's continuous-time borders on the stability maps of :mod:`armctl.bench.stability`, and the
maps' captions.

* Computed torque with M̂ = f·M on the one-joint arm: ‖I − M⁻¹M̂‖ = |1 − f|. The robust-control premise α < 1
  allows f < 2 at any gain; the small-gain condition |1 − f| γ(k) < 1 (γ the L1 norm of the error filter's
  impulse response at the gains k·(K_p⁰, K_d⁰), :mod:`armctl.tuning.inertia_estimate`) narrows it. Where the
  simulation settles at a larger f than that, the condition is conservative, by the ratio reported.
* PD + gravity on the gravity-free arm: k_g = 0, so the textbook guarantees every gain.
"""

from __future__ import annotations

from typing import Any


def computed_torque_textbook(
    ks: list[float], fs: list[float], outcome: list[list[str]], kp0: float, kd0: float
) -> dict[str, Any]:
    """The textbook borders of the computed-torque model-error map, per gain multiplier k: the premise α < 1
    (f < 2) and the small-gain interval of f, |1 − f| γ(k) < 1; and, where the simulation settles at a larger f
    than the small-gain condition guarantees, by how much (the largest stable f over the guaranteed one).
    ``kp0`` [1/s²], ``kd0`` [1/s]: the gains at k = 1."""
    from armctl.tuning.inertia_estimate import impulse_l1_norms

    gammas = [impulse_l1_norms(k * kp0, k * kd0)[1] for k in ks]
    f_max = [1.0 + 1.0 / g for g in gammas]
    stable_f = [max((f for i, f in enumerate(fs) if outcome[i][j] == "stable"), default=0.0) for j in range(len(ks))]
    return {
        "premise_f_max": 2.0,
        "small_gain_f_min": [1.0 - 1.0 / g for g in gammas],
        "small_gain_f_max": f_max,
        "largest_stable_f": stable_f,
        "conservatism": [sf / fm for sf, fm in zip(stable_f, f_max, strict=True)],
    }


def caption(key: str, data: dict[str, Any]) -> str:
    """The report's caption of the chart ``stability_<key>.png``."""
    if key == "pd_desired_gravity":
        return (
            "Stability map of PD with desired gravity compensation: gain × set-point on the pendulum with gravity "
            "(cells simulated from several starts; dashed: the textbook's K_p = k_g, solid: the exact border)"
        )
    panels = "control rate × gain" + (" and model error × gain" if "gain_error" in data.get(key, {}) else "")
    extra = ", dotted: textbook continuous-time conditions" if key in ("computed_torque", "pd_gravity") else ""
    name = key.replace("_", " ")
    return f"Stability map of {name}: {panels} (cells simulated, dashed line: sampled-data theory{extra})"


def draw_textbook(ax: Any, controller: str, kind: str, m: dict[str, Any], ks: list[float]) -> None:
    """The textbook's continuous-time borders on a panel, where there are some."""
    if controller == "computed_torque" and "textbook" in m:
        tb = m["textbook"]
        ax.axhline(tb["premise_f_max"], color="#555555", ls=":", label="textbook premise ‖I − M⁻¹M̂‖ < 1 (f < 2)")
        ax.plot(ks, tb["small_gain_f_max"], color="#1d3557", ls=":", marker=".", label="textbook small gain: f below")
        worst = max(tb["conservatism"], default=0.0)
        if worst > 1.0:
            _note(ax, f"simulated stable up to {worst:.2g}× the largest f the small-gain condition guarantees")
    elif controller == "pd_gravity" and kind == "rate_gain":
        _note(ax, "textbook (continuous time, k_g = 0): stable at every gain")


def _note(ax: Any, text: str) -> None:
    """A second line under the panel's title."""
    ax.set_title(f"{ax.get_title()}\n{text}", fontsize=9)
