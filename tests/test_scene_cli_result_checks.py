"""Named errors for bad input to SimResult I/O and plots, controller logs, the scenes and ``armctl bench``."""

from __future__ import annotations

import dataclasses
import json
import math
import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import armctl
from armctl.errors import InvalidParameterError, NonFiniteError, SimulationWarning, UnknownNameError
from armctl.scenes import PressAndSlide, scene
from armctl.sim import SimResult, simulate
from armctl.sim.result import _ARRAYS
from armctl.tuning.presets import load_preset, write_preset


class Logging:
    """A controller holding zero torque whose log has numbers, None, dicts and ragged arrays."""

    def __init__(self) -> None:
        self.last_log: dict[str, Any] = {}

    def __call__(self, t: float, q: np.ndarray, qd: np.ndarray, ref: Any) -> np.ndarray:
        k = round(t / 1e-3)
        self.last_log = {"number": float(k), "none": None, "info": {"k": k}, "ragged": np.zeros(1 + k % 2)}
        return np.zeros(1)


def _run() -> SimResult:
    return simulate(armctl.models.pendulum(), Logging(), armctl.Reference.hold([0.0]), 0.01)


def _empty(res: SimResult) -> SimResult:
    """``res`` cut to no samples (a run stopped before its first one)."""
    return SimResult(**{name: getattr(res, name)[:0] for name in _ARRAYS})


@pytest.fixture(scope="module")
def numeric() -> SimResult:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SimulationWarning)
        return _run()


# ------------------------------------------------------------------------------ 1. logs
def test_logs_that_are_not_numbers_are_left_out_with_a_warning_naming_them() -> None:
    with pytest.warns(
        SimulationWarning,
        match=r"'none' \(not numbers: NoneType\).*'info' \(not numbers: dict\)"
        r".*'ragged' \(entries of different shapes\)",
    ):
        res = _run()
    assert set(res.logs) == {"number"}
    np.testing.assert_array_equal(res.logs["number"], np.arange(len(res.t)))


def test_numeric_logs_still_record_without_a_warning(tmp_path: Path) -> None:
    class Plain:
        def __init__(self) -> None:
            self.last_log: dict[str, Any] = {}

        def __call__(self, t: float, q: np.ndarray, qd: np.ndarray, ref: Any) -> np.ndarray:
            self.last_log = {"e": np.array([t, 2 * t])}
            return np.zeros(1)

    with warnings.catch_warnings():
        warnings.simplefilter("error", SimulationWarning)
        res = simulate(armctl.models.pendulum(), Plain(), armctl.Reference.hold([0.0]), 0.01)
    back = SimResult.load(res.save(tmp_path / "plain"))
    np.testing.assert_array_equal(back.logs["e"], res.logs["e"])


def test_save_refuses_a_log_of_python_objects_naming_its_key(numeric: SimResult, tmp_path: Path) -> None:
    bad = dataclasses.replace(numeric, logs={"mode": np.array([None, {"a": 1}], dtype=object)})
    with pytest.raises(InvalidParameterError, match=r"log 'mode' holds Python objects"):
        bad.save(tmp_path / "bad.npz")
    assert not (tmp_path / "bad.npz").exists()


# ------------------------------------------------------------------------------ 2. files
def test_save_to_an_unwritable_path_names_it(numeric: SimResult, tmp_path: Path) -> None:
    target = tmp_path / "no-such-folder" / "run.npz"
    with pytest.raises(InvalidParameterError, match=r"cannot write the SimResult to .*no-such-folder.*writable"):
        numeric.save(target)


def test_load_of_a_missing_file_names_it(tmp_path: Path) -> None:
    with pytest.raises(InvalidParameterError, match=r"missing\.npz' does not exist"):
        SimResult.load(tmp_path / "missing.npz")
    with pytest.raises(InvalidParameterError, match=r"is not a file"):
        SimResult.load(tmp_path)


def test_load_of_a_npy_file_is_a_named_error(tmp_path: Path) -> None:
    np.save(tmp_path / "a.npy", np.zeros(3))
    with pytest.raises(InvalidParameterError, match=r"a\.npy' is a single NumPy array"):
        SimResult.load(tmp_path / "a.npy")


def test_load_of_a_text_file_is_a_named_error(tmp_path: Path) -> None:
    (tmp_path / "t.npz").write_text("not numpy")
    with pytest.raises(InvalidParameterError, match=r"t\.npz' cannot be read as an npz file"):
        SimResult.load(tmp_path / "t.npz")


def test_load_of_a_partial_file_lists_the_missing_entries(numeric: SimResult, tmp_path: Path) -> None:
    with np.load(numeric.save(tmp_path / "full")) as data:
        kept = {k: data[k] for k in data.files if k not in ("qd", "energy")}
    np.savez(tmp_path / "part.npz", **kept)
    with pytest.raises(
        InvalidParameterError,
        match=r"part\.npz' is incomplete: it lacks the entries "
        r"\['qd', 'energy'\]",
    ):
        SimResult.load(tmp_path / "part.npz")


@pytest.mark.parametrize(
    ("meta", "match"),
    [
        ("{not json", r"has an unreadable entry"),
        (json.dumps({"info": {}}), r"has a 'meta' entry without the keys"),
        (json.dumps([1, 2]), r"has a 'meta' entry without the keys"),
    ],
)
def test_load_of_bad_meta_is_a_named_error(numeric: SimResult, tmp_path: Path, meta: str, match: str) -> None:
    with np.load(numeric.save(tmp_path / "full")) as data:
        kept = {k: data[k] for k in data.files}
    kept["meta"] = np.array(meta)
    np.savez(tmp_path / "meta.npz", **kept)
    with pytest.raises(InvalidParameterError, match=r"meta\.npz' " + match):
        SimResult.load(tmp_path / "meta.npz")


def test_load_of_an_object_log_written_by_an_old_version_is_a_named_error(numeric: SimResult, tmp_path: Path) -> None:
    with np.load(numeric.save(tmp_path / "full")) as data:
        kept = {k: data[k] for k in data.files}
    kept["log:mode"] = np.array([None, None], dtype=object)
    np.savez(tmp_path / "old.npz", **kept)
    with pytest.raises(InvalidParameterError, match=r"old\.npz' has an unreadable entry"):
        SimResult.load(tmp_path / "old.npz")


# ------------------------------------------------------------------------------ 2. plots
def test_plot_energy_of_a_run_without_samples_is_a_named_error(numeric: SimResult) -> None:
    with pytest.raises(InvalidParameterError, match=r"the result has no samples"):
        _empty(numeric).plot_energy()


@pytest.mark.parametrize(
    ("joints", "match"),
    [
        ([5], r"joint index 5 is out of range: the result has 1 joints"),
        ([-1], r"joints\[0\] \(a joint index 0 … 0\) .*>= 0, got -1"),
        ([0.5], r"joints\[0\].*got 0\.5"),
        ([], r"at least one joint index"),
    ],
)
def test_plot_refuses_bad_joint_indices(numeric: SimResult, joints: Any, match: str) -> None:
    with pytest.raises(InvalidParameterError, match=match):
        numeric.plot(joints=joints)


def test_plot_refuses_no_quantities_and_takes_one_name(numeric: SimResult) -> None:
    with pytest.raises(InvalidParameterError, match=r"quantities must name at least one of q, qd"):
        numeric.plot(quantities=())
    with pytest.raises(UnknownNameError, match=r"unknown quantity 'torque'"):
        numeric.plot(quantities=("q", "torque"))
    fig = numeric.plot("qd", joints=np.array([0]))
    # the joint is labelled with the plant's name for it; the legend stands beside the panel, off the curves
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert len(fig.axes) == 1 and labels == [armctl.models.pendulum().joint_names[0], "reference (dashed)"]


# ------------------------------------------------------------------------------ 3. scenes
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
    empty = sc.metrics(_empty(res), "pd_gravity")
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
        return (0, *a.shape[1:]) if a.ndim == 1 or name in ("wrench", "contact_force", "sensor") else (0, 7)

    empty = SimResult(**{name: np.zeros(rows(name)) for name in _ARRAYS})
    m = contact.metrics(empty, "osc_qp")
    assert math.isnan(m["rms_error"]) and math.isnan(m["force_rms_error"]) and math.isnan(m["compute_s"])
    assert m["contact_lost"] is False


# ------------------------------------------------------------------------------ 4. CLI
@pytest.fixture
def no_bench(monkeypatch: pytest.MonkeyPatch) -> list[Path]:
    """Replace the suite so a test never runs it; records the folders it was given."""
    import armctl.bench.suite

    calls: list[Path] = []

    def fake(quick: bool, out: Path) -> dict:
        calls.append(out)
        (out / "figures.json").write_text("{}")  # (the CLI reports the written file's size)
        return {}

    monkeypatch.setattr(armctl.bench.suite, "run_suite", fake)
    return calls


def _out_case(tmp_path: Path, case: str) -> str:
    (tmp_path / "file.txt").write_text("x")
    return {
        "empty": "",
        "blank": "  ",
        "file": str(tmp_path / "file.txt"),
        "under_file": str(tmp_path / "file.txt" / "sub"),
    }[case]


@pytest.mark.parametrize(
    ("case", "match"),
    [
        ("empty", r"--out must name a folder, got an empty path"),
        ("blank", r"--out must name a folder, got an empty path"),
        ("file", r"file\.txt' exists and is not a folder"),
        ("under_file", r"sub' cannot be created or written to"),
    ],
)
def test_bench_refuses_a_bad_out_before_running(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], no_bench: list[Path], case: str, match: str
) -> None:
    from armctl.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["bench", "--quick", "--out", _out_case(tmp_path, case)])
    assert exc.value.code == 2 and not no_bench
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert len([line for line in err.splitlines() if "error:" in line]) == 1
    assert re.search(r"armctl bench: error: .*" + match, err), err


def test_bench_accepts_a_new_folder(tmp_path: Path, no_bench: list[Path]) -> None:
    from armctl.cli import main

    assert main(["bench", "--quick", "--out", str(tmp_path / "a" / "b")]) == 0
    assert no_bench == [tmp_path / "a" / "b"] and (tmp_path / "a" / "b").is_dir()


def test_bench_reports_the_size_of_the_file_it_wrote(
    tmp_path: Path, no_bench: list[Path], capsys: pytest.CaptureFixture[str]
) -> None:
    # it printed the size of an unindented dump, 20 % below the file on disk (written with indent=1)
    from armctl.cli import main

    assert main(["bench", "--out", str(tmp_path)]) == 0
    assert f"wrote {tmp_path / 'figures.json'} (2 bytes)" in capsys.readouterr().out
