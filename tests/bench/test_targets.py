"""The benchmark's own speed targets: checked here, never printed by the bench. Each ``beyond_targets`` function is
tested on figures at and beyond its targets. The live checks measure the figures on this machine (once more on
a miss: a shared machine's load can swing one measurement); they run where ``ARMCTL_SPEED_TARGETS=1`` is set,
on a quiet machine — a loaded one (CI shares two cores) measures the load as much as the code."""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

import pytest

from armctl.bench import controller_speed, dynamics_speed, osc_speed, sim_speed


def _speed(ratio: float) -> dict[str, Any]:
    return {"step_s": ratio * 1e-6, "rnea_s": 1e-6, "ratio": ratio, "ratio_iqr": (ratio, ratio)}


def test_controller_targets() -> None:
    at = {"model": "panda", **{k: _speed(v) for k, v in controller_speed.TARGETS.items()}}
    assert controller_speed.beyond_targets(at) == []
    over = {**at, "compiled": {"ComputedTorque": _speed(controller_speed.TARGETS["ComputedTorque"] + 0.1)}}
    assert controller_speed.beyond_targets(over) == ["ComputedTorque (compile=True): ratio 4.10 > 4.0"]
    for text in (controller_speed.report(at), controller_speed.report(over)):
        assert "target" not in text.lower()


def _dynamics_fig(scale: float) -> dict[str, Any]:
    fig: dict[str, Any] = {"model": "panda", "n": 7, "lagrange_compile_or_load_seconds": None}
    for name in ("mass_matrix", "inverse_dynamics", "regressor", "passivity_regressor"):
        r = scale * dynamics_speed.TARGETS[name]
        fig[name] = {"api_s": r * 1e-6, "raw_s": 1e-6, "ratio": r, "ratio_iqr": (r, r)}
    fig["lagrange_compiled_inverse_dynamics"] = None
    fig["lagrange_build_seconds"] = scale * dynamics_speed.TARGETS["lagrange_build_seconds"]
    return fig


def test_dynamics_targets() -> None:
    assert dynamics_speed.beyond_targets(_dynamics_fig(1.0)) == []
    assert len(dynamics_speed.beyond_targets(_dynamics_fig(1.1))) == 5
    for scale in (1.0, 1.1):
        text = dynamics_speed.report(_dynamics_fig(scale))
        assert "target" not in text.lower()


def test_osc_target() -> None:
    limit = osc_speed.TARGETS["ratio_rnea"]
    fig: dict[str, Any] = {name: {"ratio_rnea": limit, "wrong": 0} for name in ("circle", "random")}
    fig["numpy"] = {name: {"ratio_rnea": 2 * limit, "wrong": 0} for name in ("circle", "random")}
    assert osc_speed.beyond_targets(fig) == []  # the target is the default step's
    fig["random"] = {"ratio_rnea": limit + 0.5, "wrong": 1}
    fig["numpy"]["circle"]["wrong"] = 2
    assert osc_speed.beyond_targets(fig) == [
        "circle (compile=False): every torque the optimum",
        "random: step / RNEA <= 15",
        "random: every torque the optimum",
    ]


def _sim_fig(scale: float) -> dict[str, Any]:
    """Figures of :mod:`armctl.bench.sim_speed` at its targets (scale 1), or beyond them (scale > 1)."""
    t = sim_speed.TARGETS
    ratio = {"us_per_step": 10.0, "rms_error_rad": 0.1, "compiled": True}
    return {
        "panda": {
            "duration_s": 1.0,
            "modes": {"default": {**ratio, "ratio_to_mujoco": scale * t["panda_ratio"], "loop_ratio_to_mujoco": 0.9}},
            "semi_implicit_over_rk4": scale * t["semi_implicit_over_rk4"],
        },
        "chains": {
            str(n): {
                "us_per_step": 10.0,
                "mujoco_us_per_step": 5.0,
                "ratio_to_mujoco": (scale if n == 20 else 1.0) * t["chain_ratio"],
                "stick_events": 3,
                "breakaway_events": 2,
            }
            for n in (2, 20)
        },
        "sticking_chains": {
            str(n): {
                "us_per_step": 10.0,
                "mujoco_us_per_step": 5.0,
                "ratio_to_mujoco": (scale if n == 20 else 1.0) * t["sticking_chain_ratio"],
                "stick_events": 30,
                "breakaway_events": 20,
                "stuck_fraction": 0.15,
                "most_stuck": 12,
            }
            for n in (2, 20)
        },
        "contact": {
            "dt": 2e-4,
            "steps": 100,
            "us_per_step": 5.0,
            "mujoco_us_per_step": 5.0,
            "ratio_to_mujoco": scale * t["contact_plant_ratio"],
            "python_ratio_to_mujoco": 20.0,
        },
        "contact_loop": {
            "periods": 100,
            "substeps": 5,
            "dt": 2e-4,
            "us_per_period": 100.0,
            "mujoco_us_per_period": 100.0,
            "controller_us_per_period": 50.0,
            "ratio_to_mujoco": scale * t["contact_loop_ratio"],
            "controller_bound": 0.5,
            "touched_s": 0.24,
            "mujoco_touched_s": None,
        },
        "sweep": {
            "runs": 4,
            "duration_s": 1.0,
            "workers": 2,
            "serial_s": 2.0,
            "pool_s": 1.0,
            "dask_s": 1.0,
            "pool_speedup": t["pool_speedup"] / scale,
            "dask_speedup": t["dask_speedup"] / scale,
            "ceiling": {"ceiling": 1.8},
            "load_average_1min": [0.5, 0.6],
        },
    }


def test_sim_speed_targets() -> None:
    assert sim_speed.beyond_targets(_sim_fig(1.0)) == []
    beyond = sim_speed.beyond_targets(_sim_fig(1.1))
    assert len(beyond) == 8 and "chain N = 20 / MuJoCo <= 2.0" in beyond and "chain N = 2 / MuJoCo <= 2.0" not in beyond
    assert "sticking chain N = 20 / MuJoCo <= 1.5" in beyond and "sticking chain N = 2 / MuJoCo <= 1.5" not in beyond
    for scale in (1.0, 1.1):
        text = sim_speed.report(_sim_fig(scale))
        assert "target" not in text.lower()


live = pytest.mark.skipif(
    os.environ.get("ARMCTL_SPEED_TARGETS") != "1", reason="speed targets: set ARMCTL_SPEED_TARGETS=1 on a quiet machine"
)


def _live(measure: Callable[[], dict[str, Any]], beyond: Callable[[dict[str, Any]], list[str]]) -> None:
    first = beyond(measure())
    if first:
        assert beyond(measure()) == [], first


@live
@pytest.mark.slow
def test_controller_steps_meet_their_targets() -> None:
    _live(lambda: controller_speed.run(number=100, rounds=15), controller_speed.beyond_targets)


@live
@pytest.mark.slow
def test_dynamics_calls_meet_their_targets() -> None:
    _live(lambda: dynamics_speed.run(number=100, rounds=15, compile_if_needed=False), dynamics_speed.beyond_targets)


@live
@pytest.mark.slow
def test_osc_step_meets_its_target() -> None:
    _live(lambda: osc_speed.run(quick=True), osc_speed.beyond_targets)


@live
@pytest.mark.slow
def test_the_closed_loop_meets_its_targets() -> None:
    _live(sim_speed.run, sim_speed.beyond_targets)  # the full runs: the quick ones are too short for the targets
