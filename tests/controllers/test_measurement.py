"""A controller's measurement: declared signals reach ``compute``; missing or malformed ones raise named errors;
controllers that read nothing are called as before."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
import pytest

import armctl
from armctl.controllers import ComputedTorque, Controller, Measurement
from armctl.errors import InvalidParameterError, NonFiniteError, ShapeError


class WrenchEcho(Controller):
    """τ = Jᵀ h: reads the wrench."""

    reads: ClassVar[frozenset[str]] = frozenset({"wrench"})

    def compute(self, t, q, qd, ref):
        assert self.dynamics is not None
        return self.dynamics.jacobian(q).T @ self.measured("wrench")


@pytest.fixture(scope="module")
def dyn() -> armctl.Dynamics:
    return armctl.Dynamics(armctl.models.planar_2r())


def test_a_declared_signal_reaches_compute(dyn: armctl.Dynamics) -> None:
    ctrl = WrenchEcho(dyn)
    q = np.array([0.3, -0.5])
    h = np.array([1.0, 2.0, 0.0, 0.0, 0.0, 0.5])
    tau = ctrl(0.0, q, np.zeros(2), armctl.Reference(q), measurement=Measurement(wrench=h))
    np.testing.assert_allclose(tau, dyn.jacobian(q).T @ h, rtol=0, atol=1e-12)
    assert ctrl.measurement is not None and ctrl.measurement.available() == {"wrench"}


def test_a_missing_signal_is_named(dyn: armctl.Dynamics) -> None:
    ctrl = WrenchEcho(dyn)
    q = np.zeros(2)
    with pytest.raises(InvalidParameterError, match="wrench"):
        ctrl(0.0, q, q, armctl.Reference(q))
    with pytest.raises(InvalidParameterError, match="wrench"):
        ctrl(0.0, q, q, armctl.Reference(q), measurement=Measurement(tau_applied=np.zeros(2)))
    with pytest.raises(InvalidParameterError, match="Measurement"):
        ctrl(0.0, q, q, armctl.Reference(q), measurement={"wrench": np.zeros(6)})  # type: ignore[arg-type]


def test_malformed_signals_are_refused() -> None:
    with pytest.raises(ShapeError, match="wrench"):
        Measurement(wrench=np.zeros(3))
    with pytest.raises(NonFiniteError, match="tau_applied"):
        Measurement(tau_applied=[0.0, np.nan])
    with pytest.raises(ShapeError, match="tau_measured"):
        Measurement(tau_measured=np.zeros((2, 2)))


def test_a_controller_that_reads_nothing_ignores_the_measurement(dyn: armctl.Dynamics) -> None:
    ctrl = ComputedTorque(dyn, kp=100.0, kd=20.0)
    q = np.array([0.1, 0.2])
    ref = armctl.Reference(np.zeros(2))
    plain = ctrl(0.0, q, np.zeros(2), ref)
    with_m = ctrl(0.0, q, np.zeros(2), ref, measurement=Measurement(wrench=np.ones(6)))
    np.testing.assert_array_equal(plain, with_m)


def test_tau_applied_of_another_size_is_refused(dyn: armctl.Dynamics) -> None:
    ctrl = ComputedTorque(dyn, kp=100.0, kd=20.0)
    q = np.zeros(2)
    with pytest.raises(ShapeError, match="tau_applied"):
        ctrl(0.0, q, q, armctl.Reference(q), measurement=Measurement(tau_applied=np.zeros(3)))
