"""`armctl.bench.tails`: percentiles of per-call times, and a closed loop of a law timed call by call."""

from __future__ import annotations

import pytest

from armctl.bench import controller_speed, tails


def test_summary_takes_the_median_and_the_999th_permille() -> None:
    """Samples 1 … 1000 ns: the median is 500.5 ns and the 99.9th percentile, interpolated linearly between the
    999th and 1000th samples at rank 0.999 · 999, is 999.001 ns."""
    s = tails.summary(list(range(1, 1001)), [10 * v for v in range(1, 1001)])
    assert s["calls"] == 1000
    assert s["cpu"]["p50_s"] == pytest.approx(500.5e-9) and s["cpu"]["p999_s"] == pytest.approx(999.001e-9)
    assert s["wall"]["tail_ratio"] == pytest.approx(999.001 / 500.5)


def test_a_law_closes_a_stable_loop_and_every_call_is_timed() -> None:
    from armctl.scenes import panda_topp

    t = tails.law_tail(panda_topp().controller("passivity"), steps=200)
    assert t["calls"] == 200
    for clock in ("cpu", "wall"):
        assert 0 < t[clock]["p50_s"] <= t[clock]["p999_s"] and t[clock]["tail_ratio"] >= 1


def test_the_tails_are_reported_and_checked() -> None:
    speed = {"step_s": 2e-6, "rnea_s": 1e-6, "ratio": 2.0, "ratio_iqr": (2.0, 2.0)}
    tail = {"calls": 10, "cpu": {"p50_s": 1e-6, "p999_s": 5e-6, "tail_ratio": 5.0}}
    tail["wall"] = tail["cpu"]
    fig = {"model": "panda", "PDGravity": speed, "tails": {"PDGravity": tail}}
    assert controller_speed.beyond_targets(fig) == ["PDGravity: p99.9 / p50 5.00 > 4.0"]
    assert "p99.9 / p50 5.00" in controller_speed.report(fig)


def test_a_long_run_times_a_numpy_floor_between_the_calls() -> None:
    """Past the calibration (the law's first CALIBRATION calls, then the floor's own next CALIBRATION samples, left
    out), every call is followed by a timed floor: its samples are the rest of the run's; the report names it and
    the collections counted during the loop."""
    from armctl.scenes import panda_topp

    steps = 2 * tails.CALIBRATION + 50
    t = tails.law_tail(panda_topp().controller("pd_gravity"), steps=steps)
    assert t["calls"] == steps and t["floor"]["calls"] == 50 and t["floor"]["products"] >= 1
    assert t["gc_runs"] >= 0
    assert "NumPy floor of the same median" in tails.tail_text(t) and "garbage collections" in tails.tail_text(t)


def test_the_clock_jumps_are_counted_over_the_time_asked() -> None:
    """A short spin: a count per second, a median jump at least the threshold when there is one, and the share per
    µs of a call that follows from the count."""
    j = tails.clock_jumps(seconds=0.05, threshold_s=5e-6)
    assert j["per_s"] >= 0 and j["per_us"] == pytest.approx(j["per_s"] * 1e-6)
    assert j["median_s"] == 0.0 or j["median_s"] > 5e-6
    assert "a second" in tails.jumps_text(j)
