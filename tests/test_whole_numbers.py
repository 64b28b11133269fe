"""Counts given to the API (a delay in periods, a seed, a priority level, pyramid facets, filter orders) are
checked alike everywhere: an int, a NumPy integer or an integral float is taken; a bool, a fraction, NaN/inf
or text raises an InvalidParameterError naming the value."""

from __future__ import annotations

import math

import numpy as np
import pytest

import armctl
from armctl._checks import whole_number
from armctl.controllers.osc import Contact, FramePositionTask
from armctl.errors import InvalidParameterError
from armctl.sim import simulate
from armctl.tuning.sampled import sampled_pd_loop


@pytest.mark.parametrize("x", [3, np.int64(3), np.uint8(3), 3.0, np.float32(3.0)])
def test_whole_numbers_are_taken(x: object) -> None:
    out = whole_number(x, "k", minimum=1)
    assert out == 3 and type(out) is int


@pytest.mark.parametrize("x", [True, np.bool_(True), 2.5, math.nan, math.inf, "3", None, [3], 1j, 0, -1.0])
def test_other_values_are_named(x: object) -> None:
    with pytest.raises(InvalidParameterError, match=r"^k must be a whole number >= 1, got "):
        whole_number(x, "k", minimum=1)


def test_every_entry_point_takes_an_integral_float_as_its_integer() -> None:
    plant = armctl.models.pendulum()
    ref = armctl.Reference.hold([0.2])

    def ctrl(t: float, q: np.ndarray, qd: np.ndarray, r: armctl.Reference) -> np.ndarray:
        return -20.0 * (q - r.q) - 2.0 * qd

    args = (plant, ctrl, ref, 0.05)
    a = simulate(*args, q0=[0.0], delay=2, seed=4, noise_q=1e-3)
    b = simulate(*args, q0=[0.0], delay=2.0, seed=np.int64(4), noise_q=1e-3)
    np.testing.assert_array_equal(a.q, b.q)
    assert b.info["delay"] == 2 and b.info["seed"] == 4
    lp, lf = sampled_pd_loop(100.0, 10.0, 1e-3, delay=1), sampled_pd_loop(100.0, 10.0, 1e-3, delay=1.0)
    assert lp.dt == lf.dt and np.allclose(np.asarray(lp.poles()), np.asarray(lf.poles()))
    assert FramePositionTask(priority=2.0).priority == 2
    assert Contact(facets=np.int32(6)).facets == 6


@pytest.mark.parametrize(
    "make",
    [
        lambda: simulate(
            armctl.models.pendulum(), lambda t, q, qd, r: -q, armctl.Reference.hold([0.0]), 0.01, delay=True
        ),
        lambda: simulate(
            armctl.models.pendulum(), lambda t, q, qd, r: -q, armctl.Reference.hold([0.0]), 0.01, seed=1.5
        ),
        lambda: sampled_pd_loop(100.0, 10.0, 1e-3, delay=0.5),
        lambda: FramePositionTask(priority=True),
        lambda: Contact(facets=2.0),
    ],
)
def test_entry_points_refuse_what_is_not_a_count(make: object) -> None:
    with pytest.raises(InvalidParameterError, match="must be a whole number >= "):
        make()  # type: ignore[operator]


@pytest.mark.parametrize(
    ("value", "error", "match"),
    [
        ([np.array(1.0), np.array([1.0, 2.0])], "ShapeError", r"different shapes \[\(\), \(2,\)\]"),
        ([[1.0, 2.0], [3.0]], "ShapeError", r"different shapes \[\(2,\), \(1,\)\]"),
        (["ab", [1.0, 2.0]], "InvalidParameterError", "must hold real numbers"),
        ([[[1.0, 2.0], [3.0]], [[1.0, 2.0], [3.0, 4.0]]], "InvalidParameterError", "must hold real numbers"),
    ],
)
def test_ragged_arrays_are_named_as_such(value: object, error: str, match: str) -> None:
    # a ragged list made NumPy raise "inhomogeneous shape", reported as "must hold real numbers"
    from armctl import errors
    from armctl._checks import real_array

    with pytest.raises(getattr(errors, error), match=match):
        real_array(value, "x")  # type: ignore[arg-type]
