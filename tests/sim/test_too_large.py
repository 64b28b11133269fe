"""Requests too large to carry out are refused by name before anything is allocated or evaluated: a run too
long to record, a contact law whose coefficients overflow the forces and the stability check, and a contact
point offset that is not numbers."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

import armctl
from armctl.errors import InvalidParameterError
from armctl.sim import simulate
from armctl.sim.contact import ContactPoint, Plane
from armctl.sim.normal_force import HuntCrossley, KelvinVoigt


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
    """Plane(KelvinVoigt(1e308)) used to build, and simulate then died in NumPy's LinAlgError (the stability
    check's step matrix held inf)."""
    with pytest.raises(InvalidParameterError, match=match):
        make()  # type: ignore[operator]


def test_a_stiff_but_representable_contact_still_runs() -> None:
    """The bound is far above real contacts: 1e12 N/m builds and a run reports its instability, not an error."""
    m = armctl.models.pendulum()
    with pytest.warns(armctl.errors.SimulationWarning):
        res = simulate(m, _pd(m), armctl.Reference.hold([0.1]), 0.01, environment=Plane(KelvinVoigt(1e12)))
    assert len(res.t) >= 1


@pytest.mark.parametrize("offset", [["a", "b", "c"], [0.0, None, 0.0], [True, False, True], "0 0 1"])
def test_a_contact_point_offset_must_be_numbers(offset: object) -> None:
    """ContactPoint(None, ["a", "b", "c"]) raised NumPy's bare ValueError."""
    with pytest.raises(InvalidParameterError, match=r"^contact point offset must (hold|be) real numbers"):
        ContactPoint(None, offset)  # type: ignore[arg-type]
    np.testing.assert_array_equal(ContactPoint(None, [0, 0, 1]).offset, [0.0, 0.0, 1.0])
