"""A run whose controller, reference or disturbance raises keeps what it simulated: the exception propagates
unchanged, carrying the samples before it as ``exc.result`` (before, every sample was lost)."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.controllers import PDGravity
from armctl.sim import Forces, Sensing, StopRules, simulate


class _Breaks(PDGravity):
    """PD + gravity that raises at t >= ``at``."""

    def __init__(self, dyn: armctl.Dynamics, at: float) -> None:
        super().__init__(dyn, 50.0, 10.0)
        self.at = at

    def compute(self, t, q, qd, ref):  # type: ignore[no-untyped-def]
        if t >= self.at:
            raise ZeroDivisionError("the law divided by zero")
        return super().compute(t, q, qd, ref)


def _setup() -> tuple[armctl.Dynamics, armctl.Reference]:
    model = armctl.models.planar_2r()
    return armctl.Dynamics(model), armctl.Reference.hold([0.5, -0.3])


def test_a_controller_that_raises_keeps_the_samples_before_it() -> None:
    dyn, ref = _setup()
    whole = simulate(dyn, PDGravity(dyn, 50.0, 10.0), ref, 0.2, q0=[0.0, 0.0])
    with pytest.raises(ZeroDivisionError, match="the law divided by zero") as info:
        simulate(dyn, _Breaks(dyn, 0.1), ref, 0.2, q0=[0.0, 0.0])
    part = info.value.result
    assert len(part.t) == 100 and part.t[-1] == pytest.approx(0.099)  # samples t = 0 … 0.099 s
    np.testing.assert_array_equal(part.q, whole.q[:100])  # the same run up to the failure
    np.testing.assert_array_equal(part.tau, whole.tau[:100])
    assert part.info["failure"] == "ZeroDivisionError: the law divided by zero"
    assert any("raised at t = 0.1 s" in note for note in info.value.__notes__)


def test_a_reference_that_raises_keeps_the_samples_before_it() -> None:
    dyn, _ = _setup()

    def ref(t: float) -> armctl.Reference:
        if t > 0.05:
            raise RuntimeError("no reference beyond 50 ms")
        return armctl.Reference.hold([0.5, -0.3])

    with pytest.raises(RuntimeError, match="no reference beyond") as info:
        simulate(dyn, PDGravity(dyn, 50.0, 10.0), ref, 0.2, q0=[0.0, 0.0])
    assert len(info.value.result.t) == 51


def test_the_option_groups_equal_their_keywords() -> None:
    dyn, ref = _setup()
    ctrl = PDGravity(dyn, 50.0, 10.0)
    flat = simulate(dyn, ctrl, ref, 0.1, q0=[0, 0], noise_q=0.01, seed=4, delay=2, friction="smooth", max_velocity=50)
    grouped = simulate(
        dyn,
        ctrl,
        ref,
        0.1,
        q0=[0, 0],
        sensing=Sensing(noise_q=0.01, seed=4, delay=2),
        forces=Forces(friction="smooth"),
        stop=StopRules(max_velocity=50),
    )
    np.testing.assert_array_equal(flat.q, grouped.q)
    np.testing.assert_array_equal(flat.q_measured, grouped.q_measured)


def test_an_option_given_twice_or_a_wrong_group_is_named() -> None:
    dyn, ref = _setup()
    ctrl = PDGravity(dyn, 50.0, 10.0)
    with pytest.raises(armctl.errors.InvalidParameterError, match="noise_q given both as keyword"):
        simulate(dyn, ctrl, ref, 0.1, noise_q=0.01, sensing=Sensing(seed=1))
    with pytest.raises(armctl.errors.InvalidParameterError, match=r"sensing must be an armctl\.sim\.Sensing"):
        simulate(dyn, ctrl, ref, 0.1, sensing={"noise_q": 0.01})  # type: ignore[arg-type]
