"""Limits of a time-optimal plan are numbers: a boolean, text or a date is refused by name rather than
converted (True planned at 1 rad/s, "2.0" parsed), and a grid too large for the machine is refused, saying how
much memory it would need, before anything is allocated."""

from __future__ import annotations

import tracemalloc
from typing import Any

import numpy as np
import pytest

import armctl
from armctl.errors import InvalidParameterError
from armctl.planning import time_optimal


@pytest.fixture(scope="module")
def dyn() -> armctl.Dynamics:
    return armctl.Dynamics(armctl.models.planar_2r())


WAYPOINTS = [[0.0, 0.0], [0.4, -0.3]]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"vel_limit": True}, r"^velocity limit must be a real number, not a boolean, got True"),
        ({"vel_limit": [True, True]}, r"^velocity limit must be real numbers, not booleans"),
        ({"vel_limit": ["2.0", "2.0"]}, r"^velocity limit must hold real numbers, got \['2\.0', '2\.0'\]"),
        ({"acc_limit": np.array([1, 2], dtype="timedelta64[s]")}, r"^acceleration limit must hold real numbers, not"),
        ({"torque_limit": [[-5.0, "5"], [-5.0, 5.0]]}, r"^torque limit must hold real numbers"),
        ({"torque_limit": 500.0, "torque_margin": "0.1"}, r"^torque_margin must be a real number, got '0\.1'"),
        ({"torque_limit": 500.0, "torque_margin": True}, r"^torque_margin must be a real number, not a boolean"),
    ],
)
def test_limits_that_are_not_numbers_are_refused(dyn: armctl.Dynamics, kwargs: dict[str, Any], match: str) -> None:
    """vel_limit=True is not 1 rad/s; ["2.0"] * n and torque_margin="0.1" are text, not numbers."""
    kwargs = {"vel_limit": 1.0, **kwargs}
    with pytest.raises(InvalidParameterError, match=match):
        time_optimal(dyn, WAYPOINTS, **kwargs)


def test_numeric_limits_still_plan(dyn: armctl.Dynamics) -> None:
    a = time_optimal(dyn, WAYPOINTS, vel_limit=np.array([1, 1]), torque_limit=5000, torque_margin=np.float32(0.25))
    b = time_optimal(dyn, WAYPOINTS, vel_limit=[1.0, 1.0], torque_limit=5000.0, torque_margin=0.25)
    assert a.duration == pytest.approx(b.duration, rel=1e-12)


def test_a_grid_too_large_for_the_machine_is_refused(dyn: armctl.Dynamics) -> None:
    """grid=10**9 ended in MemoryError (or in swapping) after the gridpoints were made."""
    with pytest.raises(InvalidParameterError, match=r"^a time-optimal plan on a grid of 1e\+09 stages for 2 joints "):
        time_optimal(dyn, WAYPOINTS, vel_limit=1.0, grid=10**9)
    with pytest.raises(InvalidParameterError, match=r"TB of memory, more than the .* this machine has: use a smaller"):
        time_optimal(dyn, WAYPOINTS, vel_limit=1.0, grid=10**9)
    from armctl._checks import memory_limit

    assert memory_limit() < 1e13  # (the request above needs 9 TB)


def test_the_memory_named_is_a_lower_bound_of_what_a_plan_takes(dyn: armctl.Dynamics) -> None:
    """The estimate behind the refusal, measured: a plan on 2000 stages allocates at least as much as the
    estimate says (tracemalloc sees NumPy's arrays), so a refused request would not have fitted."""
    from armctl.planning.topp import CHECK_BYTES_PER_SAMPLE, PLAN_BYTES_PER_STAGE

    time_optimal(dyn, WAYPOINTS, vel_limit=1.0, grid=20)  # imports and caches first
    stages, oversample = 2000, 10
    tracemalloc.start()
    try:
        time_optimal(dyn, WAYPOINTS, vel_limit=1.0, grid=stages, refine=False, tol=float("inf"))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    estimate = (stages + 1) * dyn.n * (PLAN_BYTES_PER_STAGE + CHECK_BYTES_PER_SAMPLE * oversample)
    assert estimate <= peak
