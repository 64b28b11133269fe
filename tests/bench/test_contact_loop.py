"""`armctl.bench.contact_loop`: the whole panda_contact loop and MuJoCo's with the same controller, on a short run."""

from __future__ import annotations

import math

import pytest

from armctl.bench import contact_loop

pytest.importorskip("mujoco")


def test_both_loops_run_the_scene_and_the_figures_follow_from_their_times() -> None:
    """0.3 s, one round (the tool touches the table near 0.24 s in both): positive times, the ratios those of the
    times (one round: the ratio of the medians), and a report that says them."""
    f = contact_loop.figures(rounds=1, duration=0.3)
    assert f["periods"] == 300 and f["substeps"] == 5 and f["compiled"]
    for key in ("us_per_period", "mujoco_us_per_period", "controller_us_per_period"):
        assert math.isfinite(f[key]) and f[key] > 0, key
    assert f["ratio_to_mujoco"] == pytest.approx(f["us_per_period"] / f["mujoco_us_per_period"])
    assert f["controller_bound"] == pytest.approx(f["controller_us_per_period"] / f["mujoco_us_per_period"])
    assert 0.2 < f["touched_s"] < 0.3 and 0.2 < f["mujoco_touched_s"] < 0.3
    text = contact_loop.report(f)
    assert f"{f['ratio_to_mujoco']:.2f}×" in text and "the controller alone" in text
