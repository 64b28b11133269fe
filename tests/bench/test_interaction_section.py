"""The bench section ``interaction`` in quick mode: finite JSON, a written chart and tables, simulated stability
borders within 15 % of the sampled-data predictions, and the observer's trade-off as its closed forms say."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from armctl.bench import interaction, tables
from tests.bench.test_sections import _finite_numbers


@pytest.fixture(scope="module")
def data() -> dict[str, Any]:
    return interaction.run(quick=True)


@pytest.mark.slow
def test_section_writes_finite_figures_a_chart_and_tables(data: dict[str, Any], tmp_path: Path) -> None:
    json.dumps(data, allow_nan=False)
    assert _finite_numbers(data) == []
    assert "panda_collision" in interaction.summary(data)
    interaction.plot(data, tmp_path / "interaction.png")
    assert (tmp_path / "interaction.png").stat().st_size > 30_000
    assert [len(t.rows) for t in tables.interaction(data)][:4] == [4, 3, 2, 4]


@pytest.mark.slow
def test_borders_predicted_and_simulated_agree(data: dict[str, Any]) -> None:
    for r in data["force_border"]["rows"]:
        assert 0.85 < r["ratio"] < 1.15, r
    for r in data["impedance_map"]["rows"]:
        assert 0.85 < r["ratio"] < 1.15, r
    for c in data["impedance_map"]["cells"]:
        assert c["outcome"] == ("stable" if c["factor"] < 1.0 else "chatter"), c


@pytest.mark.slow
def test_force_tracking_and_observer_tradeoff(data: dict[str, Any]) -> None:
    tracking = data["force_tracking"]
    for rows, forms in ((tracking["controllers"]["CartesianImpedance"], "impedance"),
                        (tracking["controllers"]["ForceControl (P)"], "force_p")):  # fmt: skip
        got = [r["error"] for r in rows]
        want = [c[forms] for c in tracking["closed_forms"]]
        np.testing.assert_allclose(got, want, rtol=0.05)
    stiff = tracking["controllers"]["ParallelForcePosition (PI)"][-1]
    assert stiff["outcome"] == "stable" and stiff["error"] < 0.01  # integral action: no error at rest
    rows = data["observer"]["rows"]
    delays = [r["delay"] for r in rows if r["delay"] is not None]
    assert delays == sorted(delays, reverse=True)  # a higher gain detects sooner ...
    noise = [r["noise"] for r in rows]
    assert noise == sorted(noise)  # ... and is noisier, as the discrete lag's closed form says
    np.testing.assert_allclose(noise, [r["noise_predicted"] for r in rows], rtol=0.05)
