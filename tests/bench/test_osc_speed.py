"""`armctl.bench.osc_speed`: its figures on both sets of states, its checks, and a report without targets."""

from __future__ import annotations

import math

from armctl import codegen
from armctl.bench import osc_speed


def test_osc_speed_figures_checks_and_report() -> None:
    fig = osc_speed.run(count=40, rounds=3, tail_steps=300)
    for f, name in [(fig[k], k) for k in ("circle", "random")] + [(fig["numpy"][k], k) for k in ("circle", "random")]:
        for key in ("step_s", "rnea_s", "bare_solve_s", "check_s", "ratio_rnea", "ratio_bare", "check_share"):
            assert math.isfinite(f[key]) and f[key] > 0, (name, key)
        assert f["step_s"] > f["rnea_s"] and f["ratio_rnea"] > 1  # a step holds model terms, QP and check
        assert f["ratio_rnea_iqr"][0] <= f["ratio_rnea"] <= f["ratio_rnea_iqr"][1]
        assert 0 < f["check_share"] < 1
        assert sum(f["stages"].values()) >= 40 and f["stages"].get("failed", 0) == 0
        assert f["wrong"] == 0  # every torque quadprog's optimum of the same QP (quadprog: the test extra)
    assert "closed_form_s" in fig["circle"] and "closed_form_s" not in fig["random"]
    for f in (fig["contact"], fig["contact"]["numpy"], fig["scene"]):  # with an active contact
        assert f["step_s"] > f["rnea_s"] > 0 and f["ratio_rnea"] > 1
        assert f["ratio_rnea_iqr"][0] <= f["ratio_rnea"] <= f["ratio_rnea_iqr"][1]
    assert fig["contact"]["wrong"] == 0 and fig["contact"]["stages"].get("failed", 0) == 0
    tail = fig["scene"]["tail"]
    assert tail["calls"] == 300 and all(0 < tail[c]["p50_s"] <= tail[c]["p999_s"] for c in ("cpu", "wall"))
    verdicts = osc_speed.checks(fig)
    assert fig["generated"] == (codegen.compiler() is not None)  # the default takes generated code where it can
    assert set(verdicts) == {
        "circle: step / RNEA <= 15",
        "random: step / RNEA <= 15",
        "circle: every torque the optimum",
        "random: every torque the optimum",
        "circle (compile=False): every torque the optimum",
        "random (compile=False): every torque the optimum",
        "contact: step / RNEA <= 12",
        "contact: every torque the optimum",
        "contact (compile=False): every torque the optimum",
        "panda_contact: step / RNEA <= 25",
        "panda_contact: p99.9 / p50 <= 4",
    }
    assert all(ok for name, ok in verdicts.items() if name.endswith("every torque the optimum"))
    text = osc_speed.report(fig)
    assert "x RNEA" in text and "x bare solve" in text and "optimality check" in text and "compile=False" in text
    assert "fixed contact" in text and "panda_contact" in text and "p99.9 / p50" in text
    assert "target" not in text.lower()  # the benchmark's own checks are not printed
    assert "missed" not in text.lower()
