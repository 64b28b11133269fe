"""Gains are set all at once, and what a law derives from them is recomputed directly: construction never calls into
an object whose gains are half set, a reassigned gain takes effect at the next call (checked against the textbook
law), and a bad gain leaves the others as they were. Input checking is what a class declares (``result_check``),
kept by a subclass that keeps its ``compute`` and reset by one that writes its own."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.controllers import ComputedTorque, PassivityBased, PDGravity
from armctl.controllers.base import Controller
from armctl.errors import InvalidParameterError, NonFiniteError, UnknownNameError


def _dyn() -> armctl.Dynamics:
    return armctl.Dynamics(armctl.models.planar_2r())


def test_construction_derives_once_with_every_gain_set() -> None:
    seen: list[tuple[bool, bool, bool]] = []

    class Watching(PDGravity):
        def _derive(self) -> None:
            seen.append((self._kp_matrix is not None, self._kd_matrix is not None, self._ki_matrix is None))
            super()._derive()

    ctrl = Watching(_dyn(), 100.0, 20.0)
    assert seen == [(True, True, True)]
    ctrl.kp = 50.0
    assert len(seen) == 2


def test_a_reassigned_gain_takes_effect_against_the_textbook_law() -> None:
    dyn = _dyn()
    q, qd = np.array([0.2, -0.1]), np.array([0.3, 0.4])
    ref = armctl.Reference(np.array([0.5, 0.1]), np.array([0.0, 0.2]))
    ctrl = PDGravity(dyn, 100.0, 20.0)
    ctrl.kp = np.diag([30.0, 70.0])
    ctrl.set_gains(kd=[5.0, 9.0])
    expected = np.diag([30.0, 70.0]) @ (ref.q - q) + np.diag([5.0, 9.0]) @ (ref.qd - qd) + dyn.gravity_torque(q)
    np.testing.assert_allclose(ctrl(0.0, q, qd, ref), expected, rtol=1e-12)
    assert not ctrl.kp.flags.writeable


def test_a_bad_gain_changes_nothing_and_an_unknown_name_is_refused() -> None:
    ctrl = ComputedTorque(_dyn(), 100.0, 20.0)
    before = ctrl.kp
    with pytest.raises(InvalidParameterError, match="kd must be positive definite"):
        ctrl.set_gains(kp=10.0, kd=-1.0)
    assert ctrl.kp is before
    with pytest.raises(UnknownNameError):
        ctrl.set_gains(kq=1.0)


def test_an_integral_term_switches_the_result_only_check_off_and_back() -> None:
    ctrl = PDGravity(_dyn(), 100.0, 20.0)
    assert ctrl._checks_result
    ctrl.ki = 5.0
    assert not ctrl._checks_result
    ctrl.ki = None
    assert ctrl._checks_result


def test_checking_is_what_the_class_declares() -> None:
    """A subclass that writes its own compute gets its inputs checked first unless it declares otherwise; one that
    declares result_check keeps the fast check; a subclass without a compute of its own keeps its parent's."""

    class Own(PassivityBased):
        def compute(self, t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
            return super().compute(t, q, qd, ref)

    class Declared(PassivityBased):
        result_check = True

        def compute(self, t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
            return super().compute(t, q, qd, ref)

    class Same(PassivityBased):
        pass

    class User(Controller):
        def compute(self, t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
            return -qd

    dyn = _dyn()
    assert PassivityBased.result_check and not Own.result_check and Declared.result_check and Same.result_check
    assert not User.result_check
    assert [c(dyn, 5.0, 20.0)._checks_result for c in (Own, Declared, Same)] == [False, True, True]
    assert not User(n=2)._checks_result
    bad = np.array([0.0, np.nan])
    for c in (Own(dyn, 5.0, 20.0), Declared(dyn, 5.0, 20.0), User(n=2)):
        with pytest.raises(NonFiniteError, match=r"^qd"):
            c(0.0, np.zeros(2), bad, armctl.Reference(np.zeros(2)))
