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
