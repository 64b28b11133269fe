"""Where numbers are meant, the shared input checks take numbers only: dates and durations (``datetime64``,
``timedelta64``), booleans hidden among numbers and masked scalars raise an InvalidParameterError naming the
argument, rather than being converted (a date to days since 1970, ``True`` to 1.0, a masked entry to NaN)."""

from __future__ import annotations

import datetime
import re
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

import armctl
from armctl._checks import gain_matrix, nonnegative_vector, per_joint, real_array, scalar, vector, whole_number
from armctl.errors import InvalidParameterError
from armctl.references import Quintic
from armctl.sim import simulate

DATES = np.array(["2020-01-01", "2020-01-02"], dtype="datetime64[D]")
DURATIONS = np.array([1, 2], dtype="timedelta64[s]")

NOT_NUMBERS: dict[str, Any] = {
    "datetime64 array": DATES,
    "timedelta64 array": DURATIONS,
    "datetime64 scalar": np.datetime64("2020-01-01"),
    "timedelta64 scalar": np.timedelta64(5, "s"),
    "object array of dates": np.array([np.datetime64("2020-01-01")] * 2, dtype=object),
    "Python dates": [datetime.date(2020, 1, 1)] * 2,
    "a boolean among numbers": [1.0, True],
    "a NumPy boolean among numbers": [np.bool_(False), 2.0],
    "a boolean in a nested list": [[1.0, 2.0], [False, 1.0]],
    "an object array with a boolean": np.array([1.0, True], dtype=object),
    "an object array with a masked element": np.array([1.0, np.ma.masked], dtype=object),
}


@pytest.mark.parametrize("value", NOT_NUMBERS.values(), ids=NOT_NUMBERS.keys())
@pytest.mark.parametrize(
    "check",
    [
        lambda x: real_array(x, "x"),
        lambda x: vector(x, 2, "x"),
        lambda x: per_joint(x, 2, "x"),
        lambda x: nonnegative_vector(x, 2, "x"),
        lambda x: gain_matrix(x, 2, "x"),
    ],
    ids=["real_array", "vector", "per_joint", "nonnegative_vector", "gain_matrix"],
)
def test_arrays_of_non_numbers_are_refused(check: Callable[[Any], Any], value: Any) -> None:
    """Each of these used to be taken: NumPy converts a date to its count of days, a boolean to 1.0."""
    with pytest.raises(InvalidParameterError, match=r"^x must (hold real numbers|be real numbers|be a real number)"):
        check(value)


def test_dates_get_a_message_that_says_how_to_convert_them() -> None:
    with pytest.raises(InvalidParameterError, match=r"^t must hold real numbers, not dates or durations \(datetime64"):
        real_array(DATES, "t")
    with pytest.raises(InvalidParameterError, match=r"not dates or durations \(timedelta64\[s\]\).*np\.timedelta64"):
        vector(DURATIONS, 2, "t")


@pytest.mark.parametrize("value", [np.ma.masked, np.ma.masked_array(2.0, mask=True)])
def test_a_masked_scalar_is_refused_by_name(value: Any) -> None:
    """float(np.ma.masked) is NaN (with a warning): the error used to blame a non-finite value."""
    with pytest.raises(InvalidParameterError, match=r"^kp is masked: give a number"):
        scalar(value, "kp")


def test_a_timedelta_is_not_a_whole_number() -> None:
    """np.timedelta64 derives from np.signedinteger: int(np.timedelta64(5, 's')) raised a bare TypeError."""
    with pytest.raises(InvalidParameterError, match=r"^delay must be a whole number >= 0, got np\.timedelta64\("):
        whole_number(np.timedelta64(5, "s"), "delay")


def test_numbers_still_pass() -> None:
    """The refusals are for non-numbers only: unmasked masked arrays, integers, NumPy floats and nested lists of
    numbers are taken, as before."""
    np.testing.assert_array_equal(real_array([[1, 2.0], [np.float32(3), np.int8(4)]], "x"), [[1, 2], [3, 4]])
    np.testing.assert_array_equal(vector(np.ma.masked_array([1.0, 2.0], mask=False), 2, "x"), [1, 2])
    np.testing.assert_array_equal(real_array(np.array([1, 2.5], dtype=object), "x"), [1, 2.5])
    assert scalar(np.ma.masked_array(2.0), "x") == 2.0
    assert whole_number(np.int64(5), "x") == 5


@pytest.mark.parametrize("backend", ["pinocchio", "lagrange"])
@pytest.mark.parametrize("dates", [DATES, DURATIONS], ids=["datetime64", "timedelta64"])
def test_every_dynamics_method_refuses_dates(backend: str, dates: np.ndarray) -> None:
    """Every Dynamics method used to take a datetime64 array as numbers (days since 1970)."""
    dyn = armctl.Dynamics(armctl.models.planar_2r(), backend=backend)
    z = np.zeros(2)
    calls = {
        "q": [
            lambda x: dyn.mass_matrix(x),
            lambda x: dyn.gravity_torque(x),
            lambda x: dyn.jacobian(x),
            lambda x: dyn.frame_pose(x),
            lambda x: dyn.potential_energy(x),
        ],
        "qd": [
            lambda x: dyn.coriolis_matrix(z, x),
            lambda x: dyn.friction_torque(x),
            lambda x: dyn.kinetic_energy(z, x),
        ],
        "qdd": [lambda x: dyn.inverse_dynamics(z, z, x), lambda x: dyn.regressor(z, z, x)],
        "tau": [lambda x: dyn.forward_dynamics(z, z, x)],
        "qdd_r": [lambda x: dyn.passivity_regressor(z, z, z, x)],
    }
    for name, fns in calls.items():
        for fn in fns:
            with pytest.raises(InvalidParameterError, match=f"^{name} must hold real numbers, not dates"):
                fn(dates)


@pytest.mark.parametrize(
    ("build", "name"),
    [
        (lambda x: armctl.Reference(x), "Reference q"),
        (lambda x: Quintic(x, [0.0, 0.0], 1.0), "q0"),
        (
            lambda x: simulate(
                armctl.models.planar_2r(), lambda t, q, qd, r: -q, armctl.Reference.hold([0.0, 0.0]), 0.01, q0=x
            ),
            "q0",
        ),
    ],
)
def test_entry_points_refuse_dates_by_name(build: Callable[[Any], Any], name: str) -> None:
    with pytest.raises(InvalidParameterError, match="^" + re.escape(name) + " must hold real numbers, not dates"):
        build(DATES)
