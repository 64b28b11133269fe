"""Bad input to the references (Reference, Quintic, Sinusoid, WaypointSpline) raises an ArmctlError naming it."""

from __future__ import annotations

import pickle
import re
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

import armctl
from armctl.errors import ArmctlError, InvalidParameterError, NonFiniteError, ShapeError, UnknownNameError
from armctl.references import Quintic, Reference, Sinusoid, WaypointSpline

REFERENCES: dict[str, Callable[[], Any]] = {
    "Quintic": lambda: Quintic([0.0, 0.5], [1.0, -1.0], 2.0),
    "Sinusoid": lambda: Sinusoid([0.0, 0.0], 0.1, 1.0),
    "WaypointSpline": lambda: WaypointSpline([0.0, 1.0, 2.0], [[0.0, 0.0], [1.0, 2.0], [0.0, 1.0]]),
}


BAD_TIMES = [
    (np.array([0.1, 0.2]), InvalidParameterError, r"^t must be a real number, got array\(\[0\.1, 0\.2\]\)"),
    (float("nan"), NonFiniteError, r"^t must be finite, got nan"),
    (np.float64("nan"), NonFiniteError, r"^t must be finite, got nan"),
    (float("inf"), NonFiniteError, r"^t must be finite, got inf"),
    (-float("inf"), NonFiniteError, r"^t must be finite, got -inf"),
    ("a", InvalidParameterError, r"^t must be a real number, got 'a'"),
    ("0.5", InvalidParameterError, r"^t must be a real number, got '0\.5'"),
    (None, InvalidParameterError, r"^t must be a real number, got None"),
    (0.5j, InvalidParameterError, r"^t must be a real number, got 0\.5j"),
]


@pytest.mark.parametrize("kind", sorted(REFERENCES))
@pytest.mark.parametrize(("t", "error", "match"), BAD_TIMES)
def test_time_must_be_a_real_finite_scalar(kind: str, t: Any, error: type[ArmctlError], match: str) -> None:
    # an array t used to evaluate each joint at a different time (Sinusoid) or fail deep inside (the others)
    ref = REFERENCES[kind]()
    with pytest.raises(error, match=match):
        ref(t)


@pytest.mark.parametrize("kind", sorted(REFERENCES))
def test_any_real_scalar_time_gives_the_same_reference(kind: str) -> None:
    ref = REFERENCES[kind]()
    want = ref(1.0)
    for t in (1, np.float64(1.0), np.int64(1), np.array(1.0), np.float32(1.0)):
        got = ref(t)
        for name in ("q", "qd", "qdd"):
            assert np.array_equal(getattr(got, name), getattr(want, name)), (t, name)


def test_hold_refuses_what_is_not_a_number() -> None:
    with pytest.raises(InvalidParameterError, match=r"^Reference q must hold real numbers, got \['a', 'b'\]"):
        Reference.hold(["a", "b"])
    with pytest.raises(InvalidParameterError, match=r"^Reference q must hold real numbers .*got None"):
        Reference.hold(None)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match=r"q is required"):
        Reference(None)  # type: ignore[arg-type]
    assert Reference.hold([0.1, 0.2]).q.tolist() == [0.1, 0.2]
    assert Reference.hold(np.array([1, 2])).qd.tolist() == [0.0, 0.0]


@pytest.mark.parametrize(
    ("build", "match"),
    [
        (lambda: Reference([]), r"^Reference q must hold at least one joint position, got \[\]"),
        (lambda: Reference(np.zeros(0)), r"^Reference q must hold at least one joint position, got array\(\[\]"),
        (lambda: Reference.hold([]), r"^Reference q must hold at least one joint position, got \[\]"),
        (lambda: Quintic([], [], 1.0), r"^q0 must be a vector of at least one joint value, got shape \(0,\)"),
        (lambda: Sinusoid([], 0.1, 1.0), r"^center must be a vector of at least one joint value, got shape \(0,\)"),
        (lambda: WaypointSpline([0.0, 1.0], np.zeros((2, 0))), r"n >= 1 joints, got shape \(2, 0\)"),
    ],
)
def test_a_reference_of_no_joint_is_refused(build: Callable[[], Any], match: str) -> None:
    with pytest.raises(ShapeError, match=match):
        build()


@pytest.mark.parametrize(
    ("build", "match"),
    [
        (lambda m: Reference(m), r"^Reference q has masked entries: fill them first"),
        (lambda m: Reference([0.0, 0.0], m), r"^Reference qd has masked entries: fill them first"),
        (lambda m: Reference.hold(m), r"^Reference q has masked entries: fill them first"),
        (lambda m: Quintic(m, [0.0, 0.0], 1.0), r"^q0 has masked entries: fill them first"),
        (lambda m: Sinusoid([0.0, 0.0], m, 1.0), r"^amplitude has masked entries: fill them first"),
    ],
)
def test_a_masked_array_is_refused(build: Callable[[Any], Any], match: str) -> None:
    # NumPy drops the mask: the data under it (2.0 here) would have been used
    masked = np.ma.masked_array([1.0, 2.0], mask=[False, True])
    with pytest.raises(InvalidParameterError, match=match):
        build(masked)


def test_waypoint_spline_bc_type_is_a_known_name() -> None:
    times, w = [0.0, 1.0, 2.0], [[0.0, 0.0], [1.0, 2.0], [0.0, 1.0]]
    valid = "'clamped', 'natural', 'not-a-knot', 'periodic'"
    for bad in ("nope", 3, None):
        match = rf"^unknown bc_type {re.escape(repr(bad))}; valid bc_types: {valid}"
        with pytest.raises(UnknownNameError, match=match):
            WaypointSpline(times, w, bc_type=bad)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match=r"^bc_type='periodic' does not fit these waypoints: .*identical"):
        WaypointSpline(times, w, bc_type="periodic")
    with pytest.raises(InvalidParameterError, match=r"^bc_type=\(\(1, 0\.0\),\) does not fit"):
        WaypointSpline(times, w, bc_type=((1, 0.0),))  # type: ignore[arg-type]
    # the valid ones, named or explicit, still work
    for bc in ("clamped", "natural", "not-a-knot"):
        assert np.allclose(WaypointSpline(times, w, bc_type=bc)(1.0).q, [1.0, 2.0])
    assert np.allclose(WaypointSpline(times, [[0.0, 0.0], [1.0, 2.0], [0.0, 0.0]], bc_type="periodic")(2.0).q, 0.0)
    explicit = WaypointSpline(times, w, bc_type=((1, [0.0, 0.0]), (2, [0.0, 0.0])))  # type: ignore[arg-type]
    assert np.allclose(explicit(0.0).qd, 0.0)


def test_reference_parameters_are_checked_by_name() -> None:
    with pytest.raises(InvalidParameterError, match=r"^t0 must be a real number, got 'a'"):
        Quintic([0.0], [1.0], 1.0, t0="a")  # type: ignore[arg-type]
    with pytest.raises(NonFiniteError, match=r"^t0 must be finite, got nan"):
        Quintic([0.0], [1.0], 1.0, t0=float("nan"))
    with pytest.raises(ShapeError, match=r"^amplitude must have shape \(2,\), got shape \(3,\)"):
        Sinusoid([0.0, 0.0], [0.1, 0.2, 0.3], 1.0)
    with pytest.raises(InvalidParameterError, match=r"^frequency must hold real numbers, got \['a', 'b'\]"):
        Sinusoid([0.0, 0.0], 0.1, ["a", "b"])
    with pytest.raises(InvalidParameterError, match=r"^q1 must hold real numbers, got 'x'"):
        Quintic([0.0], "x", 1.0)  # type: ignore[arg-type]
    with pytest.raises(NonFiniteError, match=r"^center holds NaN or inf: array\(\[ 0., nan\]\)"):
        Sinusoid([0.0, float("nan")], 0.1, 1.0)
    with pytest.raises(NonFiniteError, match=r"^waypoints must be finite; waypoint 1 joint 0 is inf"):
        WaypointSpline([0.0, 1.0], [[0.0, 0.0], [float("inf"), 0.0]])
    with pytest.raises(InvalidParameterError, match=r"^waypoints must hold real numbers, got \[\['a'\], \['b'\]\]"):
        WaypointSpline([0.0, 1.0], [["a"], ["b"]])


def test_valid_references_keep_their_values() -> None:
    # scalars: one joint (Quintic), or every joint (Sinusoid's amplitude, frequency, phase; a one-entry list too)
    assert Quintic(0.0, 1.0, 2.0)(1.0).q.tolist() == [0.5]
    sine = Sinusoid([0.0, 0.0], [0.2], 1.0, phase=0.0)
    assert sine.amplitude.tolist() == [0.2, 0.2] and sine.frequency.tolist() == [1.0, 1.0]
    assert np.allclose(sine(0.25).q, [0.2, 0.2])
    with pytest.raises(ShapeError, match=r"^q1 must have shape \(2,\), got shape \(\)"):
        Quintic([0.0, 0.0], 1.0, 1.0)  # a scalar end for two joints stays refused (ambiguous)
    spline = WaypointSpline([0.0, 1.0, 3.0], [[0.0, 0.0], [1.0, 2.0], [0.0, 1.0]])
    assert np.allclose(spline(5.0).q, [0.0, 1.0]) and np.allclose(spline(5.0).qd, 0.0)


@pytest.mark.parametrize("field", ["q", "qd", "qdd"])
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_the_fast_path_still_refuses_non_finite_entries(field: str, bad: float) -> None:
    """Three float64 vectors take a cheaper check (the sum of their entries); every non-finite entry is still
    named, finite entries whose sum overflows are still accepted, and the arrays are copies, read-only."""
    arrays = {k: np.linspace(-1.0, 1.0, 7) for k in ("q", "qd", "qdd")}
    arrays[field][3] = bad
    with pytest.raises(NonFiniteError, match=f"Reference {field} holds NaN or inf"):
        Reference(**arrays)
    huge = np.full(7, 1e308)
    ref = Reference(huge, huge, -huge)  # finite: the sum overflows, the entries do not
    assert np.array_equal(ref.q, huge) and ref.q is not huge and not ref.q.flags.writeable
    src = np.zeros(7)
    ref = Reference(src, src, src)
    src[0] = 5.0  # the caller's buffer changes: the reference does not
    assert ref.q[0] == 0.0 and not (ref.qd.flags.writeable or ref.qdd.flags.writeable)


def test_sinusoid_is_the_formula() -> None:
    """q = c + a sin(2π f t + φ) and its two derivatives, written out here, at several times and joints."""
    c, a, f, ph = np.linspace(-1, 1, 4), np.array([0.1, 0.2, 0.0, 0.4]), np.array([0.5, 1.0, 2.0, 0.25]), 0.3
    ref_fn = Sinusoid(c, a, f, ph)
    for t in (0.0, 0.37, 2.5):
        r = ref_fn(t)
        w = 2 * np.pi * f
        np.testing.assert_allclose(r.q, c + a * np.sin(w * t + ph), rtol=1e-15, atol=1e-15)
        np.testing.assert_allclose(r.qd, a * w * np.cos(w * t + ph), rtol=1e-14, atol=1e-15)
        np.testing.assert_allclose(r.qdd, -a * w**2 * np.sin(w * t + ph), rtol=1e-14, atol=1e-14)


def test_sinusoid_keeps_copies_and_pickles() -> None:
    """The caller's arrays changing afterwards changes nothing (q̇ stays the derivative of q), and a pickled
    Sinusoid gives the same reference."""

    c, a, f = np.zeros(2), np.array([0.3, 0.1]), np.array([0.5, 1.0])
    ref_fn = Sinusoid(c, a, f)
    before = ref_fn(0.2)
    a *= 2.0
    f *= 3.0
    after = ref_fn(0.2)
    assert np.array_equal(before.q, after.q) and np.array_equal(before.qd, after.qd)
    assert not ref_fn.amplitude.flags.writeable
    h = 1e-6
    np.testing.assert_allclose((ref_fn(0.2 + h).q - ref_fn(0.2 - h).q) / (2 * h), after.qd, rtol=1e-7)
    copy = pickle.loads(pickle.dumps(ref_fn))(0.2)
    for name in ("q", "qd", "qdd"):
        assert np.array_equal(getattr(copy, name), getattr(after, name)), name


def test_a_reference_of_three_empty_arrays_is_refused() -> None:
    """Three empty float64 vectors (the form the cheap check of Reference takes) hold no joint: refused with
    the ShapeError an empty q alone gets, not a reference of n = 0."""
    with pytest.raises(ShapeError, match="at least one joint position"):
        armctl.Reference(np.zeros(0), np.zeros(0), np.zeros(0))


@pytest.mark.parametrize("kind", sorted(REFERENCES))
def test_unpickled_references_take_the_fast_path(kind: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """A reference sent to a sweep's worker is unpickled there: its arrays' float64 dtype is then a distinct
    (equal) object. Its references must still be built on the fast path, not checked entry by entry (the slow
    path, Reference._checked): counted over 200 calls, and the values are the original's."""
    import pickle

    calls = []
    checked = Reference._checked

    def counting(self: Reference, *args: Any) -> None:
        calls.append(1)
        checked(self, *args)

    original = REFERENCES[kind]()
    copy = pickle.loads(pickle.dumps(original))
    monkeypatch.setattr(Reference, "_checked", counting)
    for t in np.linspace(0.0, 2.5, 200):
        got, want = copy(float(t)), original(float(t))
        np.testing.assert_array_equal(got.q, want.q)
        np.testing.assert_array_equal(got.qdd, want.qdd)
    again = pickle.loads(pickle.dumps(original(1.0)))
    Reference(again.q, again.qd, again.qdd)  # a Reference from an unpickled one's arrays
    assert calls == []
    Reference([1.0, 2.0])  # (the slow path is what a list takes: the count sees it)
    assert calls == [1]
