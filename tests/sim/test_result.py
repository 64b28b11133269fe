"""SimResult: npz round trip, read-only arrays, plots as matplotlib Figures, matplotlib loaded lazily."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import armctl
from armctl.sim import Forces, KelvinVoigt, Plane, Sensing, SimResult, simulate
from tests.sim.helpers import ComputedTorque, ForceControl


@pytest.fixture(scope="module")
def result() -> SimResult:
    dyn = armctl.Dynamics(armctl.models.planar_2r().with_friction(viscous=2.0, coulomb=5.0))
    return simulate(
        dyn,
        ComputedTorque(dyn, 100.0, 20.0),
        armctl.Reference.hold([0.3, 0.2]),
        0.3,
        sensing=Sensing(noise_q=1e-4, seed=3, delay=1),
    )


def test_save_and_load_round_trip(result: SimResult, tmp_path: Path) -> None:
    path = result.save(tmp_path / "run")
    assert path.suffix == ".npz"
    back = SimResult.load(path)
    for name in (
        "t",
        "q",
        "qd",
        "qdd",
        "tau",
        "tau_applied",
        "tau_friction",
        "tau_ext",
        "wrench",
        "contact_force_on_environment",
        "sensor",
        "q_measured",
        "qd_measured",
        "stuck",
        "energy",
        "work_actuator",
        "work_friction",
        "work_external",
    ):
        np.testing.assert_array_equal(getattr(back, name), getattr(result, name), err_msg=name)
    np.testing.assert_array_equal(back.logs["error_norm"], result.logs["error_norm"])
    assert back.info == result.info and back.diverged is False and back.diverged_at is None


def test_a_diverged_result_round_trips(tmp_path: Path) -> None:
    res = simulate(
        armctl.models.pendulum(),
        lambda t, q, qd, ref: np.array([np.nan]) if t > 0.01 else np.zeros(1),
        armctl.Reference.hold([0.0]),
        0.05,
    )
    back = SimResult.load(res.save(tmp_path / "bad.npz"))
    assert back.diverged and back.diverged_at == res.diverged_at and back.divergence == res.divergence
    np.testing.assert_array_equal(back.diverged_q, res.diverged_q)


def test_loading_something_else_is_a_named_error(tmp_path: Path) -> None:
    np.savez(tmp_path / "x.npz", a=np.zeros(3))
    with pytest.raises(armctl.errors.InvalidParameterError, match=r"x\.npz"):
        SimResult.load(tmp_path / "x.npz")


def test_arrays_are_read_only(result: SimResult) -> None:
    with pytest.raises(ValueError):
        result.q[0, 0] = 1.0
    with pytest.raises(ValueError):
        result.logs["error_norm"][0] = 1.0


def test_plots_are_figures(result: SimResult) -> None:
    from matplotlib.figure import Figure

    dyn = armctl.Dynamics(armctl.models.planar_2r())
    wall = Plane(KelvinVoigt(1e5, 1e3), normal=(-1.0, 0.0, 0.0), point=(1.7, 0.0, 0.0))
    touching = simulate(
        dyn,
        ForceControl(dyn, [100.0, 0.0, 0.0], kd=300.0),
        armctl.Reference.hold([0.6, -1.2]),
        0.2,
        forces=Forces(environment=wall),
    )
    for fig in (
        result.plot(),
        result.plot(("qdd", "tau_friction"), joints=[1]),
        result.plot_energy(),
        touching.plot_wrench(),
    ):
        assert isinstance(fig, Figure) and fig.axes
    with pytest.raises(armctl.errors.UnknownNameError):
        result.plot(("torque",))


def test_importing_the_simulator_does_not_import_matplotlib() -> None:
    code = "import sys, armctl.sim; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"


def test_a_reference_that_varies_is_stacked_when_read_and_travels_with_the_result() -> None:
    """A reference given as a function of time: res.reference holds, row by row, what the function returned at
    each sample (its vectors, read-only), whether it is first read before or after the result is pickled."""
    import pickle

    def ref(t: float) -> armctl.Reference:
        return armctl.Reference([0.3 * t, -t], [0.3, -1.0], [0.0, t * t])

    dyn = armctl.Dynamics(armctl.models.planar_2r())
    res = simulate(dyn, ComputedTorque(dyn, 100.0, 20.0), ref, 0.05)
    copy = pickle.loads(pickle.dumps(res))
    for r in (res, copy):
        expected = [ref(t) for t in r.t]
        np.testing.assert_array_equal(r.reference.q, [e.q for e in expected])
        np.testing.assert_array_equal(r.reference.qd, [e.qd for e in expected])
        np.testing.assert_array_equal(r.reference.qdd, [e.qdd for e in expected])
        assert not r.reference.q.flags.writeable and not r.reference.qdd.flags.writeable
        np.testing.assert_array_equal(r.error, r.reference.q - r.q)
    with pytest.raises(AttributeError, match="no attribute 'x'"):
        _ = res.reference.x
