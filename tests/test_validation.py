"""The checks shared by every package (:mod:`armctl._checks`) and the command line refuse bad input by name.

* Where numbers are meant, the shared input checks take numbers only: dates and durations (``datetime64``,
  ``timedelta64``), booleans hidden among numbers and masked scalars raise an InvalidParameterError naming the
  argument, rather than being converted (a date to days since 1970, ``True`` to 1.0, a masked entry to NaN).
* Counts given to the API (a delay in periods, a seed, a priority level, pyramid facets, filter orders) are
  checked alike everywhere: an int, a NumPy integer or an integral float is taken; a bool, a fraction, NaN/inf
  or text raises an InvalidParameterError naming the value.
* ``armctl bench --out`` names a folder it can write, or the command stops before running with one error line."""

from __future__ import annotations

import datetime
import math
import re
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import armctl
from armctl._checks import gain_matrix, nonnegative_vector, per_joint, real_array, scalar, vector, whole_number
from armctl.controllers.osc import Contact, FramePositionTask
from armctl.errors import InvalidParameterError
from armctl.references import Quintic
from armctl.sim import Sensing, simulate
from armctl.tuning.sampled import sampled_pd_loop

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
    """None of these is a number, though NumPy converts a date to its count of days and a boolean to 1.0."""
    with pytest.raises(InvalidParameterError, match=r"^x must (hold real numbers|be real numbers|be a real number)"):
        check(value)


def test_dates_get_a_message_that_says_how_to_convert_them() -> None:
    with pytest.raises(InvalidParameterError, match=r"^t must hold real numbers, not dates or durations \(datetime64"):
        real_array(DATES, "t")
    with pytest.raises(InvalidParameterError, match=r"not dates or durations \(timedelta64\[s\]\).*np\.timedelta64"):
        vector(DURATIONS, 2, "t")


@pytest.mark.parametrize("value", [np.ma.masked, np.ma.masked_array(2.0, mask=True)])
def test_a_masked_scalar_is_refused_by_name(value: Any) -> None:
    """float(np.ma.masked) is NaN (with a warning): the error names the mask, not a non-finite value."""
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
    """No Dynamics method takes a datetime64 array as numbers (days since 1970)."""
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
    a = simulate(*args, q0=[0.0], sensing=Sensing(delay=2, seed=4, noise_q=1e-3))
    b = simulate(*args, q0=[0.0], sensing=Sensing(delay=2.0, seed=np.int64(4), noise_q=1e-3))
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
            armctl.models.pendulum(),
            lambda t, q, qd, r: -q,
            armctl.Reference.hold([0.0]),
            0.01,
            sensing=Sensing(delay=True),
        ),
        lambda: simulate(
            armctl.models.pendulum(),
            lambda t, q, qd, r: -q,
            armctl.Reference.hold([0.0]),
            0.01,
            sensing=Sensing(seed=1.5),
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


@pytest.fixture
def no_bench(monkeypatch: pytest.MonkeyPatch) -> list[Path]:
    """Replace the suite so a test never runs it; records the folders it was given."""
    import armctl.bench.suite

    calls: list[Path] = []

    def fake(quick: bool, out: Path, **parts: object) -> dict:
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


@pytest.mark.parametrize("shape", [(3,), (7, 7), (2, 300)])
@pytest.mark.parametrize("bad", [None, np.inf, -np.inf, np.nan, "inf-inf"])
def test_all_finite_agrees_with_isfinite_and_warns_nothing(shape: tuple[int, ...], bad: object) -> None:
    # a matrix holding inf was multiplied by zeros, and NumPy warned "invalid value encountered in dot"
    from armctl._checks import all_finite

    a = np.linspace(-1.0, 1.0, int(np.prod(shape))).reshape(shape)
    if bad == "inf-inf":
        a.flat[0], a.flat[-1] = np.inf, -np.inf
    elif bad is not None:
        a.flat[a.size // 2] = bad
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert all_finite(a) == bool(np.isfinite(a).all())
        assert all_finite(np.asfortranarray(a)) == bool(np.isfinite(a).all())


def test_readonly_fields_copies_each_named_field_as_a_read_only_float_array() -> None:
    from dataclasses import dataclass

    from armctl._checks import readonly_fields

    @dataclass(frozen=True)
    class Record:
        a: Any
        b: Any
        c: Any

        def __post_init__(self) -> None:
            readonly_fields(self, ("a", "b"))

    given = np.arange(3)
    rec = Record(given, [[1, 2], [3, 4]], given)
    assert rec.a.dtype == np.float64 and rec.b.dtype == np.float64 and rec.b.shape == (2, 2)
    assert not rec.a.flags.writeable and not rec.b.flags.writeable
    assert rec.c is given  # a field not named is left alone
    given[0] = 7  # the caller's array is not shared
    assert rec.a[0] == 0.0
    with pytest.raises(ValueError, match="read-only"):
        rec.a[0] = 1.0
