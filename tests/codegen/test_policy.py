"""The compile policy reads ``compile`` the same way wherever it appears (``Dynamics``, ``simulate``, the OSC): a
NumPy boolean is its bool, anything but True, False and ``"auto"`` is refused naming the three, and ``"auto"``
without a C compiler (``$CC`` a missing program, an empty cache) runs the slower path with one PerformanceWarning
per user and cause, whose results are those of ``compile=False``."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import armctl
from armctl.codegen import COMPILE_OPTIONS, Fallback, compile_mode
from armctl.controllers.osc import OperationalSpaceQP, PostureTask
from armctl.errors import BackendError, InvalidParameterError, PerformanceWarning

Q = np.array([0.3, -0.4])


def _dynamics(compile: object) -> Any:
    return armctl.Dynamics(armctl.models.planar_2r(), compile=compile)


def _lagrange(compile: object) -> Any:
    return armctl.Dynamics(armctl.models.planar_2r(), backend="lagrange", rotor_coupling=False, compile=compile)


def _simulate(compile: object) -> Any:
    model = armctl.models.pendulum().with_friction(viscous=0.1, coulomb=1.0)
    zero = lambda t, q, qd, r: np.zeros(1)  # noqa: E731
    return armctl.sim.simulate(model, zero, armctl.Reference.hold([1.0]), 0.05, compile=compile)


def _osc(compile: object) -> Any:
    return OperationalSpaceQP(armctl.Dynamics(armctl.models.planar_2r()), [PostureTask(2, kp=50.0)], compile=compile)


USERS: dict[str, Callable[[object], Any]] = {
    "dynamics": _dynamics,
    "lagrange": _lagrange,
    "simulate": _simulate,
    "osc": _osc,
}


def test_the_three_values_and_numpy_booleans() -> None:
    assert COMPILE_OPTIONS == ("auto", True, False)
    assert [compile_mode(v) for v in (True, False, "auto", np.True_, np.False_)] == [True, False, "auto", True, False]
    assert type(compile_mode(np.bool_(True))) is bool


@pytest.mark.parametrize("user", sorted(USERS))
@pytest.mark.parametrize("value", ["yes", "False", "AUTO", 1, 0, None, 1.0])
def test_anything_else_is_refused_naming_the_valid_values(user: str, value: object) -> None:
    with pytest.raises(InvalidParameterError, match=r"compile must be True .*False .*'auto'.*got ") as err:
        USERS[user](value)
    assert err.value.value is value or err.value.value == value


@pytest.mark.parametrize("user", ["dynamics", "lagrange", "osc"])
def test_a_numpy_boolean_is_its_bool_for_every_user(user: str) -> None:
    """np.False_ is False (nothing compiled, no warning); np.True_ is True, as for simulate (tests/sim)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", PerformanceWarning)
        made = USERS[user](np.False_)
    if user == "osc":
        assert made.compile is False
    else:
        assert made.compiled is False


def test_simulate_takes_numpy_booleans() -> None:
    assert _simulate(np.False_).info["compiled"] is False


@pytest.fixture
def no_compiler(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """No C compiler and an empty cache; every user's fallback warning forgotten (a fresh process)."""
    from armctl.controllers.osc import controller as osc_controller
    from armctl.dynamics import compiled, lagrange
    from armctl.sim import compiled as sim_compiled

    monkeypatch.setenv("CC", "no-such-compiler-armctl")
    monkeypatch.setenv("ARMCTL_CACHE", str(tmp_path))
    for fallback in (compiled.FALLBACK, lagrange.FALLBACK, sim_compiled.FALLBACK, osc_controller.FALLBACK):
        fallback.reset()
    return tmp_path


@pytest.mark.parametrize("user", ["dynamics", "lagrange", "simulate"])
def test_auto_without_a_compiler_warns_once_and_gives_the_results_of_false(no_compiler: Path, user: str) -> None:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        first, second = USERS[user]("auto"), USERS[user]("auto")
    said = [str(w.message) for w in caught if issubclass(w.category, PerformanceWarning)]
    assert len(said) == 1, said
    if user != "simulate":  # it points at the line that made the object
        assert [w.filename for w in caught if issubclass(w.category, PerformanceWarning)] == [__file__]
    assert said[0].startswith("no C compiler was found ($CC = 'no-such-compiler-armctl' is not a program on the PATH)")
    assert "apt install gcc" in said[0] and "compile=False" in said[0]
    assert not list(no_compiler.rglob("*.so"))
    plain = USERS[user](False)
    if user == "simulate":
        assert first.info["compiled"] is False and second.info["compiled"] is False
        np.testing.assert_array_equal(first.q, plain.q)
    else:
        assert first.compiled is False and first.options["compile"] == "auto"
        np.testing.assert_array_equal(first.gravity_torque(Q), plain.gravity_torque(Q))
    with pytest.raises(BackendError, match=r"\$CC = 'no-such-compiler-armctl' is not a program"):
        USERS[user](True)


def test_each_user_warns_for_itself(no_compiler: Path) -> None:
    """One warning per user of generated code and cause: the dynamics' does not silence the simulator's."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        _dynamics("auto")
        _simulate("auto")
        _dynamics("auto")
    said = [str(w.message) for w in caught if issubclass(w.category, PerformanceWarning)]
    assert len(said) == 2 and "dynamics" in said[0] and "simulator" in said[1], said


def test_a_fallback_warns_once_per_cause_and_says_what_runs_instead() -> None:
    fallback = Fallback("the test's generated code", "the test's NumPy path", "slower")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for exc in (BackendError("first"), BackendError("first"), RuntimeError("second")):
            fallback.warn(exc)
    said = [str(w.message) for w in caught]
    assert len(said) == 2
    if armctl.codegen.compiler() is not None:  # with a compiler the cause is the failure itself
        assert said == [
            "the test's generated code could not be built (first); the test's NumPy path runs instead, slower",
            "the test's generated code could not be built (RuntimeError: second); the test's NumPy path runs "
            "instead, slower",
        ]
    fallback.reset()
    with pytest.warns(PerformanceWarning):
        fallback.warn(BackendError("first"))
