"""The interaction scenes show what their methods are for, against closed forms: on ``panda_press`` (a table
lower than believed) impedance and admittance press with the series-spring force of the depth they actually
reach, k_e k_d/(k_e + k_d)(δ_c − Δz), and parallel force/position control with exactly the desired force; on
``panda_wipe`` (a sloping table with friction) force control holds the force better than impedance, and parallel
force/position control pays for the surface friction with path error."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from armctl.scenes import SCENES, normal_force, panda_press, panda_wipe, scene
from armctl.scenes.panda_press import TABLE_STIFFNESS


@pytest.fixture(scope="module")
def press() -> Any:
    return panda_press()


@pytest.fixture(scope="module")
def wipe_metrics() -> dict[str, dict[str, Any]]:
    sc = panda_wipe()
    return {m: sc.metrics(sc.run(m), m, timing_rounds=0) for m in sc.methods}


def test_the_scenes_are_listed() -> None:
    assert {"panda_press", "panda_wipe"} <= set(SCENES)
    assert scene("panda_press").name == "panda_press"


@pytest.mark.parametrize("method", ["cartesian_impedance", "admittance"])
def test_impedance_presses_with_the_force_of_the_depth_it_reaches(press: Any, method: str) -> None:
    res = press.run(method)
    kz = float(np.asarray(press.gains(method)["stiffness"])[2])
    series = TABLE_STIFFNESS * kz / (TABLE_STIFFNESS + kz)
    commanded = press.force / series  # δ_c below the believed surface: f_d were the table where believed
    offset = press.z_believed - press.z_table
    m = press.metrics(res, method, timing_rounds=0)
    assert m["force_at_rest"] == pytest.approx(series * (commanded - offset), rel=0.01)
    assert m["force_error"] < -0.4 * press.force  # the lower table: half the force wanted
    # the force trace is the simulator's sensor reading
    np.testing.assert_allclose(normal_force(res)[-1], -res.sensor[-1, 0, 2])


def test_parallel_force_position_finds_the_force_wherever_the_table_is(press: Any) -> None:
    res = press.run("parallel_force_position")
    m = press.metrics(res, "parallel_force_position", timing_rounds=0)
    assert m["force_at_rest"] == pytest.approx(press.force, abs=0.01 * press.force)
    assert not m["contact_lost"] and not m["diverged"]
    # the tool reached the true table, 1 cm below the believed one, and rests in it by f_d / k_e
    assert m["depth"] == pytest.approx(press.force / TABLE_STIFFNESS, rel=0.05)


def test_force_control_holds_the_force_on_a_sloping_table(wipe_metrics: dict[str, dict[str, Any]]) -> None:
    fc, imp = wipe_metrics["force_control"], wipe_metrics["cartesian_impedance"]
    assert not fc["contact_lost"] and not fc["diverged"]
    assert fc["rms_error"] < 0.5 * imp["rms_error"]
    assert fc["path_rms_error"] < 1e-3


def test_parallel_control_reads_surface_friction_as_force_error(wipe_metrics: dict[str, dict[str, Any]]) -> None:
    par, fc = wipe_metrics["parallel_force_position"], wipe_metrics["force_control"]
    assert par["path_rms_error"] > 5 * max(fc["path_rms_error"], 1e-4)


def test_scene_metrics_time_the_controllers_with_their_measurements(press: Any) -> None:
    res = press.run("parallel_force_position", duration=0.3)
    m = press.metrics(res, "parallel_force_position", timing_samples=20, timing_rounds=1)
    assert m["compute_s"] > 0
