"""Results as tables: a run's DataFrame (long and wide) and Dataset hold the run's own arrays under the joints'
names, with units; a sweep's DataFrame has one row per case with its settings, outcome and metrics; without
pandas or xarray the methods say how to install them; ``import armctl`` imports neither."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import armctl
from armctl.errors import ArmctlError, InvalidParameterError, OptionalDependencyError
from armctl.references import Quintic
from armctl.sim import SimResult, StopRules, simulate, sweep
from tests.sim.helpers import PDGravity, failing_cases, failing_job, slider

pytestmark = pytest.mark.one_step  # conversions of what a run recorded: not a choice of step

pd = pytest.importorskip("pandas")


@pytest.fixture(scope="module")
def run() -> SimResult:
    model = armctl.models.planar_2r()
    q0 = np.array([0.0, 0.0])
    ref = Quintic(q0, [0.3, -0.2], duration=0.1)
    return simulate(model, PDGravity(armctl.Dynamics(model), 400.0, 40.0), ref, 0.1, q0=q0)


def test_a_long_table_holds_each_sample_of_each_joint(run: SimResult) -> None:
    df = run.to_dataframe()
    names = list(run.joint_names)
    assert names == ["joint1", "joint2"] and len(df) == len(run.t) * 2
    assert list(df.columns) == [
        "t", "joint", "q", "qd", "qdd", "tau", "tau_applied", "q_ref", "qd_ref", "qdd_ref", "error"
    ]  # fmt: skip
    for j, name in enumerate(names):
        rows = df[df["joint"] == name]
        assert np.array_equal(rows["t"], run.t) and np.array_equal(rows["q"], run.q[:, j])
        assert np.array_equal(rows["tau"], run.tau[:, j]) and np.array_equal(rows["q_ref"], run.reference.q[:, j])
        # the error column is the reference minus the position, as a user would compute it from the two
        assert np.allclose(rows["error"], rows["q_ref"] - rows["q"], rtol=0, atol=1e-15)
    assert np.abs(df["error"]).max() > 1e-4  # the run tracks a moving reference: a table of zeros would pass


def test_a_wide_table_has_one_column_per_quantity_and_joint(run: SimResult) -> None:
    df = run.to_dataframe(layout="wide")
    assert df.index.name == "t" and np.array_equal(df.index, run.t)
    assert list(df["q"].columns) == ["joint1", "joint2"]
    assert np.array_equal(df["qd"]["joint2"], run.qd[:, 1])
    assert np.array_equal(df[("tau_applied", "joint1")], run.tau_applied[:, 0])
    with pytest.raises(InvalidParameterError, match=r"layout must be 'long' or 'wide', got 'tall'"):
        run.to_dataframe(layout="tall")


def test_a_dataset_has_time_and_joint_coordinates_and_units(run: SimResult) -> None:
    pytest.importorskip("xarray")
    ds = run.to_xarray()
    assert list(ds["joint"].values) == ["joint1", "joint2"] and np.array_equal(ds["time"], run.t)
    assert ds["q"].dims == ("time", "joint") and np.array_equal(ds["q"].sel(joint="joint2"), run.q[:, 1])
    assert ds["q"].attrs["units"] == "rad" and ds["tau"].attrs["units"] == "N·m" and ds["time"].attrs["units"] == "s"
    assert np.array_equal(ds["error"], run.error) and ds["wrench"].dims == ("time", "wrench_axis")
    assert ds.attrs["status"] == "ok" and ds.attrs["integrator"] == run.info["integrator"]


def test_a_prismatic_joint_is_in_metres_and_newtons() -> None:
    pytest.importorskip("xarray")
    model = slider()
    res = simulate(model, PDGravity(armctl.Dynamics(model), 100.0, 20.0), armctl.Reference.hold([0.1]), 0.01)
    ds = res.to_xarray()
    assert ds["q"].attrs["units"] == "m" and ds["qd"].attrs["units"] == "m/s" and ds["tau"].attrs["units"] == "N"
    assert list(ds["joint_type"].values) == ["prismatic"]


def final_error(res: SimResult) -> dict[str, object]:
    return {"status": res.status, "final_error": float(np.abs(res.error[-1]).max()), "q_end": res.q[-1]}


def test_a_sweep_table_has_one_row_per_case(tmp_path: Path) -> None:
    model = armctl.models.planar_2r()
    gains = [100.0, 400.0, 1600.0]
    cases = [
        {
            "plant": model,
            "controller": PDGravity(armctl.Dynamics(model), kp, 2 * kp**0.5),
            "reference": armctl.Reference.hold([0.3, -0.2]),
            "duration": 0.05,
            "q0": np.array([0.0, 0.0]),
        }
        for kp in gains
    ]
    out = sweep(cases, summary=final_error, executor="serial", progress=False)
    df = out.to_dataframe()
    assert list(df.index) == [0, 1, 2] and df.index.name == "case"
    assert list(df["plant"]) == ["planar_2r"] * 3  # an object by its name
    assert list(df["duration"]) == [0.05] * 3 and list(df["q0"]) == ["[0.0, 0.0]"] * 3
    assert list(df["outcome"]) == ["ok"] * 3 and df["error_type"].isna().all()
    assert list(df["final_error"]) == [o["final_error"] for o in out] and "q_end" not in df  # scalars only
    assert df["final_error"].is_monotonic_decreasing  # stiffer gain, smaller error


@pytest.mark.filterwarnings("ignore::armctl.errors.SweepWarning")
def test_a_sweep_table_names_the_failures(tmp_path: Path) -> None:
    out = sweep(failing_cases(tmp_path / "log", {1: "raise"}, n=3), run=failing_job, executor="serial", progress=False)
    df = out.to_dataframe()
    assert list(df["outcome"]) == ["ok", "raised", "ok"] and list(df["x"]) == [0, 1, 2]
    assert df.loc[1, "error_type"] == "ValueError" and df.loc[1, "message"] == "x = 1 is not allowed"
    assert df.loc[2, "summary"] == 4 and np.isnan(df.loc[1, "summary"])


@pytest.mark.filterwarnings("ignore::armctl.errors.SimulationWarning")  # the stiff case, saturated, diverges
def test_full_results_give_their_status_and_error() -> None:
    model = armctl.models.planar_2r()
    cases = [
        {"plant": model, "controller": PDGravity(armctl.Dynamics(model), kp, 0.1 * kp),
         "reference": armctl.Reference.hold([0.3, -0.2]), "duration": 0.2, "q0": [0.0, 0.0],
         "stop": StopRules(max_velocity=20.0), "saturate": False}
        for kp in (2e3, 3e7)
    ]  # fmt: skip
    out = sweep(cases, executor="serial", progress=False)
    df = out.to_dataframe()
    assert list(df["status"]) == ["ok", "diverged"] and list(df["diverged"]) == [False, True]
    assert df.loc[0, "error_max"] == pytest.approx(np.abs(out[0].error).max())
    assert df.loc[1, "diverged_at"] == pytest.approx(out[1].diverged_at)


@pytest.mark.parametrize("module", ["pandas", "xarray"])
def test_without_the_data_extra_the_methods_say_how_to_install_it(
    run: SimResult, module: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, module, None)  # an import of it raises ImportError
    call = run.to_xarray if module == "xarray" else run.to_dataframe
    with pytest.raises(OptionalDependencyError, match=r"needs " + module + r'.*pip install "armctl\[data\]"') as info:
        call()
    assert isinstance(info.value, ArmctlError) and isinstance(info.value, ImportError)
    if module == "pandas":
        with pytest.raises(OptionalDependencyError, match=r"SweepResult.to_dataframe needs pandas"):
            sweep([{"x": 1, "log": "/dev/null"}], run=failing_job, executor="serial", progress=False).to_dataframe()


def test_import_armctl_imports_no_table_library() -> None:
    code = (
        "import sys, armctl, armctl.sim\nprint(sorted(m for m in ('pandas', 'xarray', 'pyarrow') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
