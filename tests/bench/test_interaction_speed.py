"""The interaction-control speed benchmark: its rows run and report, and rows beyond their target are named."""

from __future__ import annotations

from armctl.bench import interaction_speed


def test_rows_beyond_their_target_are_named() -> None:
    row = {"step_s": 1e-5, "rnea_s": 1e-6, "ratio": 2.0, "ratio_iqr": (1.9, 2.1)}
    fig = {"model": "panda", "CartesianImpedance": row, "ForceControl (inner CT)": {**row, "ratio": 4.5}}
    assert interaction_speed.beyond_targets(fig) == ["ForceControl (inner CT): ratio 4.50 > 4.0"]
    assert "ForceControl (inner CT)" in interaction_speed.report(fig)


def test_every_row_runs() -> None:
    fig = interaction_speed.run(number=5, rounds=3)
    rows = [k for k, v in fig.items() if isinstance(v, dict)]
    assert set(interaction_speed.TARGETS) <= set(rows) and len(rows) == 9  # 7 laws and 2 observers
    assert all(fig[r]["ratio"] > 0 for r in rows)
