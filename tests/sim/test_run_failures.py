"""A run whose controller, reference or disturbance raises keeps what it simulated: the exception propagates
unchanged, carrying the samples up to it as ``exc.result``, the sample it was raised at included with NaN for what
was not computed there."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.controllers import PDGravity
from armctl.sim import Forces, Sensing, StopRules, simulate
from armctl.sim.stick_slip import NotPositiveDefinite


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


def test_a_controller_that_raises_keeps_the_samples_up_to_it() -> None:
    dyn, ref = _setup()
    whole = simulate(dyn, PDGravity(dyn, 50.0, 10.0), ref, 0.2, q0=[0.0, 0.0])
    with pytest.raises(ZeroDivisionError, match="the law divided by zero") as info:
        simulate(dyn, _Breaks(dyn, 0.1), ref, 0.2, q0=[0.0, 0.0])
    part = info.value.result
    assert len(part.t) == 101 and part.t[-1] == pytest.approx(0.1)  # samples t = 0 … 0.1 s
    np.testing.assert_array_equal(part.q, whole.q[:101])  # the same run up to the failure, its state included
    np.testing.assert_array_equal(part.qd, whole.qd[:101])
    np.testing.assert_array_equal(part.tau[:100], whole.tau[:100])
    assert np.isnan(part.tau[100]).all() and np.isnan(part.tau_applied[100]).all()  # no torque at t = 0.1 s
    assert np.isnan(part.qdd[100]).all() and np.isfinite(part.qdd[:100]).all()
    np.testing.assert_array_equal(part.reference.q[100], [0.5, -0.3])  # the reference was given
    assert part.info["failure"] == "ZeroDivisionError: the law divided by zero"
    assert part.status == "failed" and "stopped at t = 0.1 s by ZeroDivisionError" in repr(part)
    assert part.limits.torque_peak.max() > 0.0 and np.isfinite(part.limits.torque_peak).all()
    assert any("raised at t = 0.1 s" in note for note in info.value.__notes__)


@pytest.mark.parametrize("error", [np.linalg.LinAlgError, NotPositiveDefinite])
def test_a_controllers_linear_algebra_error_is_its_failure_not_the_plants(error: type[Exception]) -> None:
    """A controller's factorisation failing is raised as the controller's, not reported as the plant diverging."""
    dyn, ref = _setup()

    class Singular(PDGravity):
        def compute(self, t, q, qd, ref):  # type: ignore[no-untyped-def]
            if t >= 0.05:
                raise error("the controller's matrix is singular")
            return super().compute(t, q, qd, ref)

    with pytest.raises(error, match="controller's matrix is singular") as info:
        simulate(dyn, Singular(dyn, 50.0, 10.0), ref, 0.2, q0=[0.0, 0.0])
    part = info.value.result  # type: ignore[attr-defined]
    assert not part.diverged and len(part.t) == 51


def test_a_reference_that_raises_keeps_the_samples_up_to_it() -> None:
    dyn, _ = _setup()

    def ref(t: float) -> armctl.Reference:
        if t > 0.05:
            raise RuntimeError("no reference beyond 50 ms")
        return armctl.Reference.hold([0.5, -0.3])

    with pytest.raises(RuntimeError, match="no reference beyond") as info:
        simulate(dyn, PDGravity(dyn, 50.0, 10.0), ref, 0.2, q0=[0.0, 0.0])
    part = info.value.result
    assert len(part.t) == 52  # t = 0 … 0.051 s: the state at 0.051 s, for which no reference was given
    assert np.isnan(part.reference.q[51]).all() and np.isnan(part.tau[51]).all()
    np.testing.assert_array_equal(part.reference.q[:51], np.tile([0.5, -0.3], (51, 1)))


class _Reports(PDGravity):
    """PD + gravity whose ``end_run`` raises."""

    def end_run(self) -> None:
        raise RuntimeError("the controller's report failed")


def test_end_run_raising_keeps_the_run() -> None:
    dyn, ref = _setup()
    with pytest.raises(RuntimeError, match="report failed") as info:
        simulate(dyn, _Reports(dyn, 50.0, 10.0), ref, 0.1, q0=[0.0, 0.0])
    assert len(info.value.result.t) == 101  # type: ignore[attr-defined]


def test_end_run_raising_does_not_hide_the_runs_failure() -> None:
    dyn, ref = _setup()

    class Both(_Breaks, _Reports):
        pass

    with pytest.raises(ZeroDivisionError, match="divided by zero") as info:
        simulate(dyn, Both(dyn, 0.05), ref, 0.1, q0=[0.0, 0.0])
    assert any("end_run() then raised RuntimeError" in note for note in info.value.__notes__)
    assert len(info.value.result.t) == 51  # type: ignore[attr-defined]


def test_a_log_set_after_the_first_call_is_recorded() -> None:
    """A controller that creates ``last_log`` only once it has something to log."""
    dyn, ref = _setup()

    law = PDGravity(dyn, 50.0, 10.0)

    class Lazy:
        def __call__(self, t, q, qd, ref):  # type: ignore[no-untyped-def]
            if t >= 0.05:
                self.last_log = {"phase": 1.0}
            return law.compute(t, q, qd, ref)

    res = simulate(dyn, Lazy(), ref, 0.1, q0=[0.0, 0.0])
    np.testing.assert_array_equal(res.logs["phase"], np.ones(51))  # logged at the samples t = 0.05 … 0.1 s
    np.testing.assert_array_equal(res.logs["phase:sample"], np.arange(50, 101))


def test_a_huge_finite_torque_is_finite() -> None:
    """[1e308, 1e308] is finite (its sum is not): it is saturated and the run goes on."""
    dyn, ref = _setup()

    class Huge(PDGravity):
        def compute(self, t, q, qd, ref):  # type: ignore[no-untyped-def]
            return np.array([1e308, 1e308]) if 0.05 <= t < 0.052 else super().compute(t, q, qd, ref)

    res = simulate(dyn, Huge(dyn, 50.0, 10.0), ref, 0.1, q0=[0.0, 0.0])
    assert not res.diverged and len(res.t) == 101
    np.testing.assert_array_equal(res.tau_applied[50], dyn.model.effort_limit)


# its run goes beyond a velocity limit on the way, as expected
@pytest.mark.filterwarnings("ignore:the run went beyond the plant's limits:armctl.errors.SimulationWarning")
def test_a_huge_finite_state_is_not_called_non_finite() -> None:
    """Unbounded stop rules: a state of huge finite entries is a state (its entries decide, not their sum)."""
    dyn, ref = _setup()

    def idle(t, q, qd, ref):  # type: ignore[no-untyped-def]
        return np.zeros(2)

    res = simulate(dyn, idle, ref, 0.01, qd0=[1e308, 1e308], stop=StopRules(max_velocity=np.inf))
    assert res.diverged and "not finite" in res.divergence
    assert len(res.t) >= 1 and res.diverged_at > 0.0  # the initial state was recorded and controlled
    np.testing.assert_array_equal(res.qd[0], [1e308, 1e308])


def test_the_option_groups_equal_their_keywords() -> None:
    dyn, ref = _setup()
    ctrl = PDGravity(dyn, 50.0, 10.0)
    flat = simulate(
        dyn,
        ctrl,
        ref,
        0.1,
        q0=[0, 0],
        sensing=Sensing(noise_q=0.01, seed=4, delay=2),
        forces=Forces(friction="smooth"),
        stop=StopRules(max_velocity=50),
    )
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
    with (
        pytest.warns(DeprecationWarning, match="noise_q"),
        pytest.raises(armctl.errors.InvalidParameterError, match="noise_q given both as keyword"),
    ):
        simulate(dyn, ctrl, ref, 0.1, noise_q=0.01, sensing=Sensing(seed=1))
    with pytest.raises(armctl.errors.InvalidParameterError, match=r"sensing must be an armctl\.sim\.Sensing"):
        simulate(dyn, ctrl, ref, 0.1, sensing={"noise_q": 0.01})  # type: ignore[arg-type]


def test_a_disturbance_that_raises_within_a_period_keeps_the_torque_held_there() -> None:
    """A disturbance that raises at the middle of the period from t = 0.05 s (the plant samples it at the start,
    middle and end of each step): the run keeps the samples up to t = 0.05 s, the torque of that sample computed
    and held (its applied row np.clip of it at the effort limits), and its acceleration not computed (NaN)."""
    dyn, ref = _setup()

    def push(t: float) -> np.ndarray:
        if t > 0.05 and abs(t / 1e-3 - round(t / 1e-3)) > 1e-6:
            raise RuntimeError("the disturbance's table ends here")
        return np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0])

    with pytest.raises(RuntimeError, match="table ends here") as info:
        simulate(dyn, PDGravity(dyn, 50.0, 10.0), ref, 0.2, q0=[0.0, 0.0], forces=Forces(disturbance=push))
    part = info.value.result
    assert len(part.t) == 51 and part.t[-1] == pytest.approx(0.05)
    assert np.isfinite(part.tau[50]).all()
    limit = dyn.model.effort_limit
    np.testing.assert_array_equal(part.tau_applied, np.clip(part.tau, -limit, limit))
    assert np.isnan(part.qdd[50]).all() and np.isfinite(part.qdd[:50]).all()
