"""Bad input raises an ArmctlError subclass that names the value."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.errors import ArmctlError, InvalidParameterError, NonFiniteError, ShapeError, UnknownNameError
from armctl.sim import ContactPoint, ForceSensor, HuntCrossley, KelvinVoigt, Plane, simulate
from tests.sim.helpers import zero_torque

MODEL = armctl.models.planar_2r()
REF = armctl.Reference.hold([0.1, 0.2])


def run(**kw: object) -> armctl.sim.SimResult:
    args: dict[str, object] = {"plant": MODEL, "controller": zero_torque, "reference": REF, "duration": 0.01}
    args.update(kw)
    return simulate(**args)  # type: ignore[arg-type]


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

    res = simulate(plant, meddling, REF, 0.05, integrator=integrator, friction=fric, q0=[0.3, -0.2])
    ref = simulate(plant, lambda t, q, qd, r: -q - qd, REF, 0.05, integrator=integrator, friction=fric, q0=[0.3, -0.2])
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
