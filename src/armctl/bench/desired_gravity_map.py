"""Stability map of PD with desired gravity compensation: where the set-point is the arm's only rest point.

The pendulum (with gravity, its motor's reflected inertia, no friction) is regulated by τ = K_p (q_d − q) −
K_d q̇ + g(q_d) at set-points from hanging (q_d = 0) to upright (q_d = π), with K_p a multiple of k_g, the bound on
‖∂g/∂q‖ that :func:`~armctl.tuning.model_bounds` certifies. Each cell runs from several starts at rest and
says where they settle:

* ``"unique"``: every start settles at the set-point;
* ``"second equilibrium"``: a start settles elsewhere (at rest, at a q ≠ q_d);
* ``"unsettled"``: a start is still moving at the end.

Two borders are drawn: the textbook's, K_p = k_g (:func:`~armctl.tuning.conditions.pd_desired_gravity_condition`,
the same at every set-point), and the exact one of this one-joint arm, where a second solution of
K_p (q_d − q) = g(q) − g(q_d) appears: K_p* = sup over q ≠ q_d of (g(q) − g(q_d)) / (q_d − q), found on a fine
grid. At the upright set-point the two meet; hanging, the textbook asks for several times the gain needed.
"""

from __future__ import annotations

import functools
import math
import warnings
from concurrent.futures import Executor
from typing import Any

import numpy as np

import armctl
from armctl.controllers import PDDesiredGravity
from armctl.errors import SimulationWarning

#: starts, as offsets from the set-point [rad]
STARTS = (-4.5, -2.0, 2.0, 4.5)


def _pendulum() -> armctl.RobotModel:
    return armctl.models.pendulum().reduced(friction=False)


@functools.cache
def _constants() -> tuple[float, bool, float]:
    """(k_g, whether it is certified, the inertia J)."""
    dyn = armctl.Dynamics(_pendulum())
    bounds = armctl.tuning.model_bounds(dyn)
    return bounds.k_g, bounds.details["k_g"].certified, float(dyn.mass_matrix([0.0])[0, 0])


def exact_border(set_point: float) -> float:
    """K_p* [N·m/rad] above which q_d is the only solution of K_p (q_d − q) = g(q) − g(q_d): the sup over
    q ≠ q_d of (g(q) − g(q_d)) / (q_d − q), on a grid of 0.2 mrad over q_d ± 12π (the ratio tends to 0 beyond)."""
    from armctl.tuning.trig_poly import TrigPoly

    dyn = armctl.Dynamics(_pendulum())
    offsets = np.arange(-12 * math.pi, 12 * math.pi, 2e-4)
    offsets = offsets[np.abs(offsets) > 1e-6]
    g0 = float(dyn.gravity_torque([set_point])[0])
    # g of a revolute joint is a trigonometric polynomial of degree 1 in q, fixed by three samples
    fit = TrigPoly(dyn.gravity_torque, 1, [0], 1, np.zeros(1))
    g = fit.evaluate((set_point + offsets)[:, None])[:, 0]
    return float(np.max((g - g0) / (-offsets)))


def damping(kp: float) -> float:
    """K_d [N·m·s/rad]: critical damping of the stiffness left near the set-point, |K_p − k_g| J (at least a
    tenth of k_g J), so that every cell settles within the run."""
    kg, _, j = _constants()
    return 2.0 * math.sqrt(max(abs(kp - kg), 0.1 * kg) * j)


def run_cell(factor: float, set_point: float, duration: float = 20.0, control_dt: float = 2e-3) -> str:
    """Simulate the cell (K_p = factor · k_g at ``set_point``) from every start in :data:`STARTS`."""
    from armctl.sim import simulate

    kg, _, _ = _constants()
    kp = factor * kg
    model = _pendulum()
    dyn = armctl.Dynamics(model)
    outcome = "unique"
    for start in STARTS:
        with warnings.catch_warnings():  # a cell's outcome is its result; a velocity overrun on the way is not
            warnings.simplefilter("ignore", SimulationWarning)
            res = simulate(
                model,
                PDDesiredGravity(dyn, kp, damping(kp)),
                armctl.Reference([set_point]),
                duration,
                q0=[set_point + start],
                control_dt=control_dt,
                saturate=False,
            )
        if res.diverged or abs(res.qd[-1, 0]) > 1e-2:
            outcome = "unsettled"
        elif abs(res.q[-1, 0] - set_point) > 0.05:
            return "second equilibrium"
    return outcome


def desired_gravity_map(quick: bool = False, executor: Executor | str | None = None) -> dict[str, Any]:
    """Every cell simulated, the textbook border (K_p = k_g) and the exact one per set-point."""
    from armctl.sim import sweep

    factors = [0.15, 0.5, 0.9, 1.1] if quick else [0.1, 0.15, 0.25, 0.4, 0.6, 0.8, 0.95, 1.05, 1.3]
    set_points = [0.0, math.pi / 2, math.pi] if quick else [0.0, math.pi / 4, math.pi / 2, 3 * math.pi / 4, math.pi]
    duration = 15.0 if quick else 20.0
    cases = [{"factor": f, "set_point": s, "duration": duration} for s in set_points for f in factors]
    outcomes = sweep(cases, run=run_cell, executor=executor, progress=True)
    kg, certified, _ = _constants()
    exact = [exact_border(s) / kg for s in set_points]
    return {
        "k_g": kg,
        "k_g_certified": certified,
        "gain_factors": factors,
        "set_points": set_points,
        "starts": list(STARTS),
        "duration": duration,
        "outcome": [[outcomes[i * len(factors) + j] for j in range(len(factors))] for i in range(len(set_points))],
        "textbook_border": 1.0,
        "exact_border": exact,
        # how many times the gain the textbook asks for exceeds what uniqueness needs, per set-point
        "conservatism": [1.0 / e if e > 0 else math.inf for e in exact],
    }


def plot(data: dict[str, Any], path: Any) -> None:
    """The map: cells, the textbook border and the exact one, and the textbook's excess gain per set-point."""
    import matplotlib
    import matplotlib.ticker

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colour = {"unique": "#2a9d4a", "second equilibrium": "#d62828", "unsettled": "#e9c46a"}
    fig, ax = plt.subplots(figsize=(6.5, 4.8))
    ys = np.degrees(data["set_points"])
    for i, y in enumerate(ys):
        for j, f in enumerate(data["gain_factors"]):
            ax.scatter(f, y, s=160, marker="s", color=colour[data["outcome"][i][j]])
        ax.annotate(
            f"×{data['conservatism'][i]:.2g}",
            (data["textbook_border"], y),
            textcoords="offset points",
            xytext=(-8, 9),
            ha="right",
            fontsize=8,
        )
    kind = "certified" if data["k_g_certified"] else "estimated"
    ax.axvline(data["textbook_border"], color="k", ls="--", label=f"textbook: K_p = k_g ({kind} k_g)")
    ax.plot(data["exact_border"], ys, "k-", marker="|", label="exact: a second equilibrium appears")
    ax.set_xscale("log")
    ax.xaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_xticks(data["gain_factors"])
    ax.set_yticks(ys)
    ax.set(
        ylim=(ys.min() - 15, ys.max() + 15),
        xlabel="K_p / k_g",
        ylabel="set-point q_d [deg] (0: hanging, 180: upright)",
        title="PD + g(q_d): where q_d is the only rest point\n(×: how many times the needed gain the textbook asks)",
    )
    keys = [plt.Line2D([], [], ls="", marker="s", ms=8, color=c, label=o) for o, c in colour.items()]
    lines = ax.get_legend_handles_labels()[0]
    ax.legend(handles=[*keys, *lines], loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2, fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
