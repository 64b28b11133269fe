"""`armctl bench --quick`: the main job's output, and sweeps on a Dask cluster."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from armctl.cli import main
from tests.helpers.browser import chromium, keep_screenshot, open_page


def _finite(x: object) -> bool:
    if isinstance(x, dict):
        return all(_finite(v) for v in x.values())
    if isinstance(x, list):
        return all(_finite(v) for v in x)
    return not isinstance(x, float) or math.isfinite(x)


@pytest.mark.slow
def test_bench_quick_writes_every_scene_and_controller(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from armctl.bench.suite import SECTION_TITLES
    from armctl.scenes import SCENES, scene

    assert main(["bench", "--quick", "--out", str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    # every section's results as it finished, and no internal speed target among them
    assert all(f"== {title} (" in printed for title in SECTION_TITLES.values())
    assert "target" not in printed.lower()
    fig = json.loads((tmp_path / "figures.json").read_text())
    rows = {(r["scene"], r["method"]): r for r in fig["scenes"]}
    for name in SCENES:
        for method in scene(name).methods:
            assert (name, method) in rows
    for r in rows.values():
        assert _finite([r["rms_error"], r["max_error"], r["compute_s"], r["torque_rms"]])
        # timed in the main process after the runs, as a median of interleaved replays
        assert r["compute_timing"].startswith("median of 5 interleaved replays")
        assert r["compute_s_iqr"][0] <= r["compute_s"] <= r["compute_s_iqr"][1]
        assert {"torque_violation_share", "velocity_violation_share", "position_violation_share"} <= set(r)
        assert "window" not in r  # the replayed states stay out of figures.json
    for name in SCENES:
        if (name, "computed_torque_reduced") in rows:
            assert rows[(name, "computed_torque")]["rms_error"] < rows[(name, "computed_torque_reduced")]["rms_error"]
    maps = fig["stability_maps"]
    for controller, kinds in maps.items():
        if not isinstance(kinds, dict) or "rate_gain" not in kinds:
            continue
        for kind, data in kinds.items():
            outcomes = [o for row in data["outcome"] for o in row]
            assert "stable" in outcomes and "unstable" in outcomes, (controller, kind)
            # cells clearly inside the theoretical border are stable, clearly outside unstable
            for row, border in zip(data["outcome"], data["border_k"], strict=True):
                for k, o in zip(maps["k"], row, strict=True):
                    if k < 0.7 * border:
                        assert o == "stable", (controller, kind, k, border)
                    if k > 1.4 * border:
                        assert o == "unstable", (controller, kind, k, border)
    osc = fig["osc_speed"]  # a step holds the model terms, the QP and its check: it costs more than one RNEA
    for name in ("circle", "random"):
        assert _finite(osc[name]) and osc[name]["step_s"] > osc[name]["rnea_s"] > 0 and osc[name]["ratio_rnea"] > 1
    for name in fig["charts"]:
        assert (tmp_path / name).stat().st_size > 1000
    page = (tmp_path / "report.html").read_text()
    assert "<img" in page and page.count("<table class='sortable'>") >= len(SECTION_TITLES)
    for name in SCENES:  # each scene's playback, written and embedded
        assert (tmp_path / f"playback_{name}.html").stat().st_size > 100_000
        assert f"<iframe src='playback_{name}.html'" in page
    if chromium() is not None:
        report = open_page(tmp_path / "report.html", "document.querySelectorAll('table').length", settle=3.0)
        keep_screenshot(report.screenshot, "armctl-bench-report.png")
        assert report.errors == [] and report.value >= len(SECTION_TITLES)
        assert all(u.startswith(("file:", "data:")) for u in report.requests), report.requests


def test_sweep_on_a_dask_local_cluster() -> None:
    """The same sweep code on a Dask cluster (here a local one) as on the default process pool."""
    import distributed  # in the test extra: missing, the test fails rather than skips

    from armctl.bench.stability import run_cell
    from armctl.sim import sweep

    cases = [
        {"controller": "computed_torque", "k": k, "f": 1.0, "period": 0.01, "duration": 1.0, "dt_max": 2e-3}
        for k in (1.0, 20.0)
    ]
    with (
        distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cl,
        distributed.Client(cl) as client,
    ):
        out = sweep(cases, run=run_cell, executor=client.get_executor(), progress=False)
    assert out == ["stable", "unstable"]  # k* = 4.87 at 100 Hz with one period of delay
    assert np.array_equal(out, sweep(cases, run=run_cell, executor="serial", progress=False))
