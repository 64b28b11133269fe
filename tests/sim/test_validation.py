"""Bad input to the simulator and its results raises an ArmctlError subclass that names the value.

* ``simulate`` and its options; contact, friction and disturbance parameters at the edges: named errors instead
  of silent nonsense.
* Requests too large to carry out are refused by name before anything is allocated or evaluated: a run too long
  to record, a contact law whose coefficients overflow the forces and the stability check, and a contact point
  offset that is not numbers.
* Controller logs that are not numbers, SimResult I/O (save, load) and plots."""

from __future__ import annotations

import dataclasses
import json
import tracemalloc
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import armctl
from armctl.errors import (
    ArmctlError,
    InvalidParameterError,
    NonFiniteError,
    ShapeError,
    SimulationWarning,
    UnknownNameError,
)
from armctl.sim import ContactPoint, Forces, ForceSensor, HuntCrossley, KelvinVoigt, Plane, SimResult, simulate
from armctl.sim.friction import SmoothFriction, StickSlip
from armctl.sim.options import regroup
from tests.sim.helpers import logging_run, without_samples, zero_torque

MODEL = armctl.models.planar_2r()


REF = armctl.Reference.hold([0.1, 0.2])


def run(**kw: object) -> armctl.sim.SimResult:
    args: dict[str, object] = {"plant": MODEL, "controller": zero_torque, "reference": REF, "duration": 0.01}
    args.update(kw)
    return simulate(**regroup(args))  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kwargs", "error", "shown"),
    [
        ({"duration": -1.0}, InvalidParameterError, "-1.0"),
        ({"duration": 0.0}, InvalidParameterError, "duration"),
        ({"duration": float("nan")}, NonFiniteError, "nan"),
        ({"duration": 0.0105}, InvalidParameterError, "0.0105"),
        ({"control_dt": -1e-3}, InvalidParameterError, "-0.001"),
        ({"control_dt": "fast"}, InvalidParameterError, "fast"),
        ({"dt": 0.0}, InvalidParameterError, "dt"),
        ({"dt": 3e-4}, InvalidParameterError, "0.0003"),
        ({"dt": 2e-3}, InvalidParameterError, "0.002"),
        ({"integrator": "rk45"}, UnknownNameError, "rk45"),
        ({"q0": [0.0, 0.0, 0.0]}, ShapeError, "(3,)"),
        ({"qd0": [np.nan, 0.0]}, NonFiniteError, "nan"),
        ({"noise_q": -0.1}, InvalidParameterError, "-0.1"),
        ({"noise_qd": [0.1, 0.1, 0.1]}, ShapeError, "(3,)"),
        ({"delay": -1}, InvalidParameterError, "-1"),
        ({"delay": 1.5}, InvalidParameterError, "1.5"),
        ({"max_velocity": 0.0}, InvalidParameterError, "max_velocity"),
        ({"max_velocity": True}, InvalidParameterError, "max_velocity must be a positive number"),  # was 1 rad/s
        ({"saturate": "no"}, InvalidParameterError, "saturate must be True or False, got 'no'"),  # was truthy
        ({"energy": "no"}, InvalidParameterError, "energy must be True or False"),
        ({"reset": 0}, InvalidParameterError, "reset must be True or False, got 0"),
        ({"friction": "lugre"}, UnknownNameError, "lugre"),
        ({"environment": "wall"}, InvalidParameterError, "wall"),
        ({"environment": Plane(KelvinVoigt(1e4), points=[ContactPoint("elbow")])}, UnknownNameError, "elbow"),
        ({"sensors": [ForceSensor("wrist")]}, UnknownNameError, "wrist"),
        ({"disturbance": 3.0}, InvalidParameterError, "float"),
        ({"plant": "planar_2r"}, InvalidParameterError, "str"),
        ({"controller": None}, InvalidParameterError, "NoneType"),
        ({"reference": [0.1, 0.2]}, InvalidParameterError, "list"),
        ({"reference": armctl.Reference.hold([0.1, 0.2, 0.3])}, ShapeError, "3 joints"),
        ({"reference": lambda t: [0.0, 0.0]}, InvalidParameterError, "list"),
        ({"seed": "abc", "noise_q": 0.1}, InvalidParameterError, "abc"),
        ({"seed": 1.5, "noise_q": 0.1}, InvalidParameterError, "1.5"),
        ({"duration": True}, InvalidParameterError, "True"),
        ({"duration": 1e-12}, InvalidParameterError, "use 0.001 s (one control period)"),
        ({"q0": [3.0, 0.0], "max_position": 2.0}, InvalidParameterError, "beyond max_position = 2"),
        ({"qd0": [0.0, 5.0], "max_velocity": 2.0}, InvalidParameterError, "beyond max_velocity = 2"),
        (
            {"reference": armctl.Reference.hold([3.0, 0.0]), "max_position": 2.0},
            InvalidParameterError,
            "the reference at t = 0",
        ),
    ],
)
def test_bad_input_raises_a_named_error(kwargs: dict[str, object], error: type, shown: str) -> None:
    with pytest.raises(error) as info:
        run(**kwargs)
    assert isinstance(info.value, ArmctlError)
    assert shown in str(info.value)


def test_errors_carry_the_offending_value() -> None:
    with pytest.raises(InvalidParameterError) as info:
        run(dt=3e-4)
    assert info.value.value == 3e-4
    with pytest.raises(UnknownNameError) as info2:
        run(integrator="verlet")
    assert "rk4" in str(info2.value) and info2.value.valid


def test_controller_returning_a_wrong_shape_is_named() -> None:
    with pytest.raises(ShapeError, match=r"\(3,\)"):
        run(controller=lambda t, q, qd, ref: np.zeros(3))


def test_disturbance_returning_a_wrong_shape_is_named() -> None:
    with pytest.raises(ShapeError, match=r"\(3,\)"):
        run(disturbance=lambda t: np.zeros(3))


def test_controller_for_another_arm_is_refused() -> None:
    from tests.sim.helpers import PDGravity

    ctrl = PDGravity(armctl.Dynamics(armctl.models.pendulum()), 1.0, 1.0)
    with pytest.raises(ShapeError, match="1 joints"):
        run(controller=ctrl)


@pytest.mark.parametrize(
    ("make", "error"),
    [
        (lambda: KelvinVoigt(-1.0), InvalidParameterError),
        (lambda: KelvinVoigt(1e4, damping=-2.0), InvalidParameterError),
        (lambda: HuntCrossley(1e4, exponent=0.5), InvalidParameterError),
        (lambda: Plane(KelvinVoigt(1e4), normal=(0.0, 0.0, 0.0)), InvalidParameterError),
        (lambda: Plane(KelvinVoigt(1e4), point=(0.0, 1.0)), InvalidParameterError),
        (lambda: Plane("stiff"), InvalidParameterError),  # type: ignore[arg-type]
        (lambda: Plane(KelvinVoigt(1e4), friction=-0.1), InvalidParameterError),
        (lambda: Plane(KelvinVoigt(1e4), points=[]), InvalidParameterError),
        (lambda: ContactPoint(None, (0.0, 1.0)), InvalidParameterError),
    ],
)
def test_bad_environment_parameters(make: object, error: type) -> None:
    with pytest.raises(error):
        make()  # type: ignore[operator]


def test_caller_arrays_are_not_modified() -> None:
    q0 = np.array([0.1, 0.2])
    qd0 = np.array([0.5, -0.5])
    res = run(q0=q0, qd0=qd0, duration=0.1)
    assert q0.flags.writeable and qd0.flags.writeable
    np.testing.assert_array_equal(q0, [0.1, 0.2])
    np.testing.assert_array_equal(qd0, [0.5, -0.5])
    with pytest.raises(ValueError):
        res.q[0, 0] = 1.0  # results are read-only


def test_a_run_stopped_before_its_first_sample_has_an_empty_energy_balance() -> None:
    def nan_torque(t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        return np.full(2, np.nan)

    res = run(controller=nan_torque)
    assert res.diverged and res.diverged_at == 0.0 and len(res.t) == 0
    assert res.energy_balance().shape == (0,)


@pytest.mark.parametrize("integrator", ["rk4", "implicit-euler"])
@pytest.mark.parametrize("friction", ["stick-slip", None])
def test_a_controller_cannot_change_the_state_in_place(integrator: str, friction: str | None) -> None:
    """The state handed to the controller is read-only: writing into it raises, and the run it was given is
    the same as with a controller that only reads it."""
    plant = MODEL.with_friction(viscous=0.5, coulomb=0.2) if friction else MODEL
    fric = friction or "smooth"

    def meddling(t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        try:
            q += 1.0
        except ValueError:
            pass
        else:
            raise AssertionError("the controller changed q in place")
        with pytest.raises(ValueError):
            qd[0] = 0.0
        return -q - qd

    res = simulate(plant, meddling, REF, 0.05, integrator=integrator, q0=[0.3, -0.2], forces=Forces(friction=fric))
    ref = simulate(
        plant,
        lambda t, q, qd, r: -q - qd,
        REF,
        0.05,
        integrator=integrator,
        q0=[0.3, -0.2],
        forces=Forces(friction=fric),
    )
    np.testing.assert_array_equal(res.q, ref.q)
    assert abs(res.q[-1] - res.q[0]).max() > 1e-4  # the arm moved: the runs are not trivially equal


@pytest.mark.parametrize("returned", [np.array([1j, 0.0]), ["a", "b"], {"a": 1.0}])
def test_a_torque_that_is_not_real_numbers_is_named(returned: object) -> None:
    """Complex torques are refused, not cut to their real part (NumPy would only warn); text and dicts too."""
    with pytest.raises(InvalidParameterError, match=r"^the controller's torque at t = 0 s must hold real numbers"):
        run(controller=lambda t, q, qd, r: returned)


@pytest.mark.parametrize("returned", [[1.0, -2.0], np.array([1, -2]), np.array([1.0, -2.0], dtype=">f4")])
def test_lists_integers_and_other_float_types_are_taken_as_torques(returned: object) -> None:
    res = run(controller=lambda t, q, qd, r: returned)
    np.testing.assert_array_equal(res.tau, np.tile([1.0, -2.0], (len(res.t), 1)))
    assert res.tau.dtype == np.float64


@pytest.mark.parametrize(
    ("kind", "times"),
    [
        ("float32", {"control_dt": 1e-3, "dt": 1e-4}),
        ("float32", {"duration": 0.01}),
        ("float16", {"duration": 0.1}),
        ("array32", {"control_dt": 1e-3}),
    ],
)
def test_times_given_in_a_lower_precision_are_the_decimals_they_print_as(kind: str, times: dict) -> None:
    # float32(1e-3) is 0.0010000000475 s: 1 s was "not a whole number of control periods (1000); use … 1 s"
    def make(v: float) -> object:
        return np.array(v, dtype=np.float32) if kind == "array32" else getattr(np, kind)(v)

    args = {"duration": 1.0, **{k: make(v) for k, v in times.items()}}
    duration = args.pop("duration")
    res = simulate(MODEL, zero_torque, REF, duration, **args)
    control_dt = float(times.get("control_dt", 1e-3))
    assert len(res.t) == round(float(times.get("duration", 1.0)) / control_dt) + 1
    assert res.info["dt"] == times.get("dt", 1e-3) and res.info["control_dt"] == control_dt


def test_a_huge_plane_normal_is_normalised_not_lost() -> None:
    """The norm of (1e300, 0, 0) overflows; dividing by it would give the normal (0, 0, 0) and no force at all."""
    np.testing.assert_array_equal(Plane(KelvinVoigt(1e4), normal=(1e300, 0.0, 0.0)).normal, [1.0, 0.0, 0.0])
    np.testing.assert_allclose(Plane(KelvinVoigt(1e4), normal=(3e-300, 4e-300, 0.0)).normal, [0.6, 0.8, 0.0])


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: Plane(KelvinVoigt(1e4), normal="abc"), "plane normal must hold real numbers"),
        (lambda: Plane(KelvinVoigt(1e4), point=["a", "b", "c"]), "plane point must hold real numbers"),
        (lambda: Plane(KelvinVoigt(1e4), points=5), "points must be a non-empty sequence of ContactPoint"),
        (lambda: HuntCrossley.from_restitution(1e4, 2.0, 1.0), r"restitution must be in \[0, 1\].*got 2"),
        (lambda: KelvinVoigt(1e3).depth_at(-5.0), "force must be >= 0, got -5"),
        (lambda: HuntCrossley(1e3, exponent=1.5).depth_at(-5.0), "force must be >= 0, got -5"),
        (lambda: ForceSensor(world_axes="no"), "world_axes must be True or False, got 'no'"),
        (lambda: StickSlip(armctl.models.pendulum(), stribeck="no"), "stribeck must be True or False, got 'no'"),
    ],
)
def test_bad_environment_values_are_named(make: object, message: str) -> None:
    with pytest.raises(InvalidParameterError, match=message):
        make()  # type: ignore[operator]


def test_one_contact_point_need_not_be_in_a_list() -> None:
    point = ContactPoint(offset=(0.0, 0.0, 0.1))
    assert Plane(KelvinVoigt(1e4), points=point).points == (point,)


def test_a_tiny_stribeck_velocity_gives_a_finite_friction_slope() -> None:
    """exp(−(q̇/v_s)²) underflows to 0 where q̇/v_s overflows: the slope is then the viscous one, not 0·inf =
    NaN (implicit Euler, which uses it, reported such a run as diverged at t = 0); elsewhere it is the
    derivative of the torque (central differences)."""
    tiny = armctl.models.pendulum().with_friction(viscous=0.05, coulomb=0.3, static=0.45, stribeck_velocity=1e-200)
    sliding = (np.array([0.5]), np.array([1.0]))
    np.testing.assert_array_equal(StickSlip(tiny).slope(*sliding), [0.05])
    np.testing.assert_array_equal(SmoothFriction(tiny).slope(sliding[0]), [0.05])
    res = simulate(
        tiny, lambda t, q, qd, r: np.array([2.0]), armctl.Reference.hold([0.0]), 0.2, integrator="implicit-euler"
    )
    ref = simulate(tiny, lambda t, q, qd, r: np.array([2.0]), armctl.Reference.hold([0.0]), 0.2, integrator="rk4")
    assert not res.diverged and abs(res.q[-1, 0] - ref.q[-1, 0]) < 5e-3  # first order against fourth
    normal = armctl.models.pendulum().with_friction(viscous=0.05, coulomb=0.3, static=0.45, stribeck_velocity=0.1)
    for model in (StickSlip(normal), SmoothFriction(normal)):
        for v in (0.0, 0.03, 0.1, 0.4, -0.2):
            x, d, h = np.array([v]), np.array([1.0 if v >= 0 else -1.0]), 1e-7
            fd = (model.torque(x + h, d) - model.torque(x - h, d)) / (2 * h)
            np.testing.assert_allclose(model.slope(x, d), fd, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("returned", ["abc", {"a": 1.0}, ["1"] * 6, np.array([1j, 0, 0, 0, 0, 0])])
def test_a_disturbance_that_is_not_real_numbers_is_named(returned: object) -> None:
    with pytest.raises(InvalidParameterError, match=r"^disturbance\(t\) at t = 0 s must hold real numbers"):
        simulate(
            armctl.models.planar_2r(),
            lambda t, q, qd, r: np.zeros(2),
            armctl.Reference.hold([0.1, 0.2]),
            0.01,
            forces=Forces(disturbance=lambda t: returned),
        )


def _pd(model: armctl.RobotModel) -> armctl.controllers.PDGravity:
    return armctl.controllers.PDGravity(armctl.Dynamics(model), 100.0, 20.0)


def test_a_run_too_long_to_record_is_refused() -> None:
    """simulate(..., duration=1e7) ended in MemoryError: 1e10 samples need more than a terabyte."""
    m = armctl.models.pendulum()
    with pytest.raises(
        InvalidParameterError,
        match=r"^duration = 1e\+07 s at control_dt = 0\.001 s is 1e\+10 control periods; recording them for a "
        r"1-joint arm needs at least 1\.\d+ TB of memory, more than the .* this machine has: shorten the run or "
        r"raise control_dt",
    ) as info:
        simulate(m, _pd(m), armctl.Reference.hold([0.0]), 1e7)
    assert info.value.value == 1e7


def test_the_memory_named_is_a_lower_bound_of_what_a_run_records() -> None:
    """What a run allocates, measured (tracemalloc sees NumPy's arrays), is at least the estimate per sample."""
    from armctl.sim.setup import RECORD_BYTES, RECORD_BYTES_PER_JOINT

    m = armctl.models.planar_2r()
    ref = armctl.Reference.hold([0.1, 0.2])
    simulate(m, _pd(m), ref, 0.01)  # imports and caches first
    tracemalloc.start()
    try:
        res = simulate(m, _pd(m), ref, 2.0)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert len(res.t) * (RECORD_BYTES + RECORD_BYTES_PER_JOINT * m.n) <= peak


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: KelvinVoigt(1e308), r"^contact stiffness = 1e\+308 N/m is beyond what a simulation can represent"),
        (lambda: KelvinVoigt(1e4, 1e200), r"^contact damping = 1e\+200 N·s/m is beyond"),
        (lambda: HuntCrossley(1e308), r"^contact stiffness = 1e\+308 N/mᵖ is beyond"),
        (lambda: HuntCrossley(1e4, 1e300), r"^contact dissipation = 1e\+300 s/m is beyond"),
        (lambda: HuntCrossley.from_restitution(1e4, 0.5, 1e-300), r"^contact dissipation = 7\.5e\+299 s/m is beyond"),
    ],
)
def test_contact_coefficients_that_overflow_are_refused(make: object, match: str) -> None:
    """Plane(KelvinVoigt(1e308)) is refused when made, not left for simulate to die in NumPy's LinAlgError (the
    stability check's step matrix would hold inf)."""
    with pytest.raises(InvalidParameterError, match=match):
        make()  # type: ignore[operator]


def test_a_stiff_but_representable_contact_still_runs() -> None:
    """The bound is far above real contacts: 1e12 N/m builds and a run reports its instability, not an error."""
    m = armctl.models.pendulum()
    with pytest.warns(armctl.errors.SimulationWarning):
        res = simulate(
            m, _pd(m), armctl.Reference.hold([0.1]), 0.01, forces=Forces(environment=Plane(KelvinVoigt(1e12)))
        )
    assert len(res.t) >= 1


@pytest.mark.parametrize("offset", [["a", "b", "c"], [0.0, None, 0.0], [True, False, True], "0 0 1"])
def test_a_contact_point_offset_must_be_numbers(offset: object) -> None:
    """ContactPoint(None, ["a", "b", "c"]) raised NumPy's bare ValueError."""
    with pytest.raises(InvalidParameterError, match=r"^contact point offset must (hold|be) real numbers"):
        ContactPoint(None, offset)  # type: ignore[arg-type]
    np.testing.assert_array_equal(ContactPoint(None, [0, 0, 1]).offset, [0.0, 0.0, 1.0])


@pytest.fixture(scope="module")
def numeric() -> SimResult:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SimulationWarning)
        return logging_run()


# ------------------------------------------------------------------------------ controller logs
def test_logs_that_are_not_numbers_are_left_out_with_a_warning_naming_them() -> None:
    with pytest.warns(
        SimulationWarning,
        match=r"'none' \(not numbers: NoneType\).*'info' \(not numbers: dict\)"
        r".*'ragged' \(entries of different shapes\)",
    ):
        res = logging_run()
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


# ------------------------------------------------------------------------------ result files
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


# ------------------------------------------------------------------------------ plots
def test_plot_energy_of_a_run_without_samples_is_a_named_error(numeric: SimResult) -> None:
    with pytest.raises(InvalidParameterError, match=r"the result has no samples"):
        without_samples(numeric).plot_energy()


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
    with pytest.raises(UnknownNameError, match=r"unknown quantity 'torque'; valid quantities: 'q'"):
        numeric.plot(quantities=("q", "torque"))
    fig = numeric.plot("qd", joints=np.array([0]))
    # the joint is labelled with the plant's name for it; the legend stands beside the panel, off the curves
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert len(fig.axes) == 1 and labels == [armctl.models.pendulum().joint_names[0], "reference (dashed)"]
