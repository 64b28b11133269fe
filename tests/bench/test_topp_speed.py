"""`armctl.bench.topp_speed`: the TOPP speed benchmark runs and both of its solvers agree on the problem (no timing
is asserted)."""

from __future__ import annotations

import pytest

from armctl.bench import topp_speed


def test_benchmark_runs_and_solvers_agree(capsys: pytest.CaptureFixture[str]) -> None:
    r = topp_speed.main(["--rounds", "1", "--number", "1"])
    assert r["armctl_s"] > 0 and r["toppra_s"] > 0
    # the same path and limits: armctl's duration is within a few % of toppra's (which may exceed the
    # velocity limit between gridpoints, armctl may not)
    assert r["duration_armctl"] == pytest.approx(r["duration_toppra"], rel=0.05)
    assert "ratio" in capsys.readouterr().out
