"""The benchmark section "plant engines", run once in quick mode: finite numbers, the checks it states, the
orderings theory predicts, a written chart."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest

pytestmark = pytest.mark.mujoco


@pytest.fixture(scope="module")
def data() -> dict[str, Any]:
    pytest.importorskip("mujoco")
    from armctl.bench import engines

    return engines.run(quick=True)


# its run goes beyond a velocity limit on the way, as expected
@pytest.mark.filterwarnings("ignore:the run went beyond the plant's limits:armctl.errors.SimulationWarning")
def test_section_output(data: dict[str, Any], tmp_path: Path) -> None:
    from armctl.bench import engines

    text = json.dumps(data, allow_nan=False)  # JSON, no NaN or inf
    assert "null" not in text  # nothing diverged
    assert engines.summary(data).count("\n") >= len(data["series"])
    png = tmp_path / "engines.png"
    engines.plot(data, png)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
    assert {"native rk4", "native euler", "native rk4 compiled", "mujoco rk4", "mujoco euler"} <= set(data["series"])
    for series in data["series"].values():
        for scene in ("frictionless", "stiction"):
            for case in series.get(scene, []):
                assert case["cost"] > 0 and case["error"] >= 0 and case["runs"] >= 3


def test_checks_hold(data: dict[str, Any]) -> None:
    """Same scheme, same equations: the same error in both engines (RK4 within 1e-3 relative, where the error is
    well above the reference's own); armctl's stick–slip holds exactly, MuJoCo's frictionless creeps."""
    assert all(check["ok"] for check in data["checks"].values()), data["checks"]
    assert data["frictionless"]["reference_error"] < 1e-12


@pytest.mark.parametrize("name", ["native rk4", "mujoco rk4"])
def test_rk4_is_fourth_order_in_both_engines(data: dict[str, Any], name: str) -> None:
    cases = data["series"][name]["frictionless"]
    assert cases[0]["error"] / cases[1]["error"] > 100.0  # h / 4: 4⁴ = 256 in the asymptotic range


def test_noslip_reduces_the_creep(data: dict[str, Any]) -> None:
    plain = [c["error"] for c in data["series"]["mujoco implicitfast"]["stiction"]]
    noslip = [c["error"] for c in data["series"]["mujoco implicitfast noslip"]["stiction"]]
    assert all(0 < b < a for a, b in zip(plain, noslip, strict=True))
    assert all(math.isfinite(e) for e in plain + noslip)
