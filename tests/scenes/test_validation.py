"""Bad input to the scenes raises a named ArmctlError: an unknown simulate option or scene model, gains the
method does not have, a press-and-slide of bad parameters; and what a scene computes from a run of no samples."""

from __future__ import annotations

import dataclasses
import math
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import armctl
from armctl.errors import InvalidParameterError, NonFiniteError, SimulationWarning, UnknownNameError
from armctl.scenes import PressAndSlide, scene
from armctl.sim import SimResult
from armctl.sim.result import _ARRAYS
from armctl.tuning.presets import load_preset, write_preset
from tests.sim.helpers import logging_run, without_samples


@pytest.fixture(scope="module")
def numeric() -> SimResult:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SimulationWarning)
        return logging_run()


@pytest.fixture(scope="module")
def pendulum_run() -> tuple[Any, SimResult]:
    sc = scene("pendulum")
    return sc, sc.run("pd_gravity", duration=0.02)


def test_run_lets_the_duration_override_win(pendulum_run: tuple[Any, SimResult]) -> None:
    _, res = pendulum_run
    assert len(res.t) == 21 and math.isclose(res.t[-1], 0.02)


def test_run_refuses_an_unknown_option(pendulum_run: tuple[Any, SimResult]) -> None:
    sc, _ = pendulum_run
    with pytest.raises(UnknownNameError, match=r"unknown simulate option 'durration'.*'duration'"):
        sc.run("pd_gravity", durration=0.02)
    with pytest.raises(UnknownNameError, match=r"unknown simulate option 'reference'"):
        sc.run("pd_gravity", reference=armctl.Reference.hold([0.0]))


@pytest.mark.parametrize("samples", [0, -1, 2.5, True])
def test_metrics_needs_at_least_one_timing_sample(pendulum_run: tuple[Any, SimResult], samples: Any) -> None:
    sc, res = pendulum_run
    with pytest.raises(InvalidParameterError, match=rf"timing_samples must be a whole number >= 1, got {samples!r}"):
        sc.metrics(res, "pd_gravity", timing_samples=samples)


def test_metrics_of_a_valid_run_and_of_no_samples(pendulum_run: tuple[Any, SimResult]) -> None:
    sc, res = pendulum_run
    m = sc.metrics(res, "pd_gravity", timing_samples=5)
    assert m["compute_s"] > 0 and math.isfinite(m["rms_error"]) and m["limit_violation_share"] == 0.0
    empty = sc.metrics(without_samples(res), "pd_gravity")
    assert all(
        math.isnan(empty[k]) for k in ("compute_s", "rms_error", "max_error", "torque_rms", "limit_violation_share")
    )


def test_scene_gains_are_checked(pendulum_run: tuple[Any, SimResult]) -> None:
    sc, _ = pendulum_run
    with pytest.raises(
        UnknownNameError,
        match=r"unknown pd_gravity gain 'bogus'; valid pd_gravity gains: 'kp', "
        r"'kd', 'ki'",
    ):
        sc.controller("pd_gravity", gains={"kp": 1.0, "kd": 1.0, "bogus": 1})
    with pytest.raises(InvalidParameterError, match=r"gains of 'pd_gravity' lack 'kd'; give kp, kd \(optional: ki\)"):
        sc.controller("pd_gravity", gains={"kp": 1.0})
    with pytest.raises(InvalidParameterError, match=r"gains of 'passivity' must be a dict"):
        sc.controller("passivity", gains=[1.0, 2.0])  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match=r"gains\['projection'\] must be True or False, got 'no'"):
        sc.controller("adaptive", gains={**sc.gains("adaptive"), "projection": "no"})
    assert sc.controller("adaptive", gains={**sc.gains("adaptive"), "projection": True}).projection is True
    assert sc.controller("adaptive").projection is False  # the preset: the textbook law (V non-increasing)


def test_limit_violations_of_each_kind(pendulum_run: tuple[Any, SimResult]) -> None:
    """Shares of samples beyond the effort limit, the velocity limit by more than 1 %, and the position range,
    counted here from the plant's limits on a run doctored sample by sample."""
    sc, res = pendulum_run
    joint = sc.plant.joints[0]  # the pendulum has no position range: give its plant one
    limits = dataclasses.replace(joint.limits, lower=-1.0, upper=1.0)
    sc = dataclasses.replace(
        sc, plant=dataclasses.replace(sc.plant, joints=(dataclasses.replace(joint, limits=limits),))
    )
    p = sc.plant
    n = len(res.t)
    tau, qd, q = res.tau.copy(), res.qd.copy(), res.q.copy()
    tau[:3] = 2.0 * p.effort_limit  # 3 samples over the effort limit
    qd[3:8] = 1.02 * p.velocity_limit  # 5 over the velocity limit by 2 %
    qd[8:10] = 1.005 * p.velocity_limit  # 2 within the 1 % tolerance
    q[9:11] = p.upper + 1e-3  # 2 outside the position range (one shared with the velocity rows)
    doctored = dataclasses.replace(res, tau=tau, qd=qd, q=q)
    got = sc.limit_violations(doctored)
    assert got["torque_violation_share"] == pytest.approx(3 / n)
    assert got["velocity_violation_share"] == pytest.approx(5 / n)
    assert got["position_violation_share"] == pytest.approx(2 / n)
    assert got["limit_violation_share"] == pytest.approx(10 / n)  # rows 0–7 and 9–10
    m = sc.metrics(doctored, "pd_gravity", timing_samples=3, timing_rounds=2)
    assert {k: m[k] for k in got} == got


def test_compute_time_is_a_median_of_replays(
    pendulum_run: tuple[Any, SimResult], monkeypatch: pytest.MonkeyPatch
) -> None:
    import armctl.scenes.base as base

    sc, res = pendulum_run
    window = sc.replay_window(res, 7)
    assert len(window["t"]) == 7 and window["t"][0] == pytest.approx(float(res.t[7]))  # the middle of 21
    calls: list[int] = []
    monkeypatch.setattr(
        base, "replay_times", lambda ctrl, w, passes: calls.append(passes) or [100.0, 3.0, 1.0, 2.0, 50.0, 4.0][:passes]
    )
    assert sc.compute_time("pd_gravity", window, rounds=5) == 3.0  # median of the five after the warm-up
    assert calls == [6]
    assert math.isnan(sc.compute_time("pd_gravity", {"t": [], "q": [], "qd": [], "ref": []}))
    assert math.isnan(sc.metrics(res, "pd_gravity", timing_rounds=0)["compute_s"]) and calls == [6]  # not timed


def test_dynamics_of_an_unknown_model_is_a_named_error(pendulum_run: tuple[Any, SimResult]) -> None:
    sc, _ = pendulum_run
    with pytest.raises(
        UnknownNameError,
        match=r"unknown scene model 'foo'; valid scene models: 'plant', 'exact', "
        r"'reduced'",
    ):
        sc.dynamics("foo")


@pytest.fixture(scope="module")
def contact() -> Any:
    return scene("panda_contact")


@pytest.mark.parametrize(
    ("kw", "error", "match"),
    [
        ({"slide_time": 0}, InvalidParameterError, r"slide_time must be > 0, got 0"),
        ({"force": float("nan")}, NonFiniteError, r"force must be finite"),
        ({"force": -1.0}, InvalidParameterError, r"force must be >= 0"),
        ({"slide": "0.1"}, InvalidParameterError, r"slide must be a real number, got '0.1'"),
    ],
)
def test_press_and_slide_checks_its_parameters(contact: Any, kw: dict[str, Any], error: type, match: str) -> None:
    with pytest.raises(error, match=match):
        PressAndSlide(contact.dynamics("exact"), contact.z_table, contact.mu, **kw)


def test_contact_scene_gains_are_checked_and_applied(contact: Any) -> None:
    with pytest.raises(UnknownNameError, match=r"unknown osc_qp gain 'bogus'; valid osc_qp gains: 'kp', 'kd'"):
        contact.controller("osc_qp", gains={"kd": 1e9, "bogus": 1})
    ctrl = contact.controller("osc_qp", gains={"kp": 100.0, "kd": 30.0})
    np.testing.assert_array_equal(np.diag(ctrl.pose.kp), 100.0)
    np.testing.assert_array_equal(np.diag(ctrl.pose.kd), 30.0)


@pytest.mark.parametrize("method", ["osc_qp", "osc_closed_form"])
def test_contact_scene_reads_its_presets(
    contact: Any, method: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    shipped = load_preset("panda_contact", method)
    assert shipped["written_by"] == "examples/tune_gains.py" and "ω_n = 20" in shipped["how"]
    ctrl = contact.controller(method)
    np.testing.assert_array_equal(np.diag(ctrl.pose.kp), shipped["gains"]["kp"])
    np.testing.assert_array_equal(np.diag(ctrl.pose.kd), shipped["gains"]["kd"])
    write_preset("panda_contact", method, {"kp": 121.0, "kd": 22.0}, "test", "test", tmp_path)
    monkeypatch.setenv("ARMCTL_PRESETS", str(tmp_path))  # another folder's preset is the one read
    ctrl = contact.controller(method)
    np.testing.assert_array_equal(np.diag(ctrl.pose.kp), 121.0)
    np.testing.assert_array_equal(np.diag(ctrl.pose.kd), 22.0)


def test_contact_metrics_of_a_run_without_samples(contact: Any, numeric: SimResult) -> None:
    def rows(name: str) -> tuple[int, ...]:
        a = getattr(numeric, name)
        return (
            (0, *a.shape[1:]) if a.ndim == 1 or name in ("wrench", "contact_force_on_environment", "sensor") else (0, 7)
        )

    empty = SimResult(**{name: np.zeros(rows(name)) for name in _ARRAYS})
    m = contact.metrics(empty, "osc_qp")
    assert math.isnan(m["rms_error"]) and math.isnan(m["force_rms_error"]) and math.isnan(m["compute_s"])
    assert m["contact_lost"] is False
