"""The generated Cartesian impedance law runs on unchecked q and q̇ (only τ is checked after it): a NaN or inf in
any entry, or a non-finite t, still raises a NonFiniteError naming it, and leaves nothing behind — no held pose,
no log, no trajectory called. The constant target is a copy of what was given, and a new target replaces it.
Force control with a sensor does the same, and keeps neither its integral nor its clock from a refused call; a
measurement given as float arrays is still checked. The generated default damping keeps its ζ through a pickle."""

from __future__ import annotations

import math
import pickle
from typing import Any

import numpy as np
import pytest

import armctl
from armctl.controllers import CartesianImpedance, ForceControl, Measurement, ParallelForcePosition
from armctl.errors import NonFiniteError, ShapeError

Q_READY = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
K = [800.0, 600.0, 700.0, 50.0, 40.0, 30.0]
D = [60.0, 50.0, 55.0, 5.0, 4.0, 3.0]

# the generated variants: damping given, damping from Λ(q), null-space stiffness, three axes
VARIANTS = {
    "given damping": {"stiffness": K, "damping": D},
    "damping from Λ": {"stiffness": K},
    "null space": {"stiffness": K, "damping": D, "nullspace_stiffness": 10.0},
    "three axes": {"stiffness": K[:3], "damping": D[:3]},
}


@pytest.fixture(scope="module")
def panda() -> armctl.Dynamics:
    return armctl.Dynamics(armctl.models.panda())


def pair(panda: armctl.Dynamics, variant: str) -> tuple[CartesianImpedance, CartesianImpedance]:
    kwargs: dict[str, Any] = VARIANTS[variant]
    fast = CartesianImpedance(panda, compile=True, **kwargs)
    slow = CartesianImpedance(panda, compile=False, **kwargs)  # its inputs are checked before the law
    assert fast._generated is not None and slow._generated is None
    return fast, slow


@pytest.mark.parametrize("variant", sorted(VARIANTS))
@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_a_non_finite_state_is_named_and_leaves_no_held_pose(panda: armctl.Dynamics, variant: str, bad: float) -> None:
    fast, slow = pair(panda, variant)
    ref = armctl.Reference(Q_READY)
    qd = np.linspace(-0.3, 0.3, 7)
    for joint in range(7):
        for name in ("q", "qd"):
            q_bad, qd_bad = Q_READY.copy(), qd.copy()
            (q_bad if name == "q" else qd_bad)[joint] = bad
            with pytest.raises(NonFiniteError, match=rf"^{name} holds NaN or inf"):
                fast(0.0, q_bad, qd_bad, ref)
            assert fast.last_log == {}
    with pytest.raises(NonFiniteError, match="t must be finite"):
        fast(bad, Q_READY, qd, ref)
    # the first finite call holds its own pose, as the NumPy law does
    q = Q_READY + 0.05
    np.testing.assert_allclose(fast(0.0, q, qd, ref), slow(0.0, q, qd, ref), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(fast.last_log["force"], slow.last_log["force"], rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_after_a_finite_call_a_non_finite_state_is_still_named(panda: armctl.Dynamics, bad: float) -> None:
    fast, _ = pair(panda, "given damping")
    ref = armctl.Reference(Q_READY)
    fast(0.0, Q_READY, np.zeros(7), ref)
    log = fast.last_log
    for joint in range(7):
        qd = np.zeros(7)
        qd[joint] = bad
        with pytest.raises(NonFiniteError, match=r"^qd holds NaN or inf"):
            fast(1e-3, Q_READY, qd, ref)
        assert fast.last_log is log


def test_a_trajectory_is_never_called_at_a_non_finite_time(panda: armctl.Dynamics) -> None:
    fast, slow = pair(panda, "given damping")
    pose = panda.frame_pose(Q_READY)
    seen: list[float] = []

    def trajectory(t: float) -> tuple[np.ndarray, None, None]:
        seen.append(t)
        moved = pose.copy()
        moved[2, 3] += 0.1 * t
        return moved, None, None

    for c in (fast, slow):
        c.set_trajectory(trajectory)
    ref = armctl.Reference(Q_READY)
    with pytest.raises(NonFiniteError, match="t must be finite"):
        fast(math.nan, Q_READY, np.zeros(7), ref)
    assert seen == []
    for t in (0.0, 0.5, 1.0):  # a new target at every call reaches the law
        np.testing.assert_allclose(fast(t, Q_READY, np.zeros(7), ref), slow(t, Q_READY, np.zeros(7), ref), atol=1e-9)


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_the_target_is_a_copy_and_a_new_one_replaces_it(panda: armctl.Dynamics, variant: str) -> None:
    fast, slow = pair(panda, variant)
    axes = len(VARIANTS[variant]["stiffness"])
    pose = panda.frame_pose(Q_READY)
    given = pose.copy() if axes == 6 else pose[:3, 3].copy()
    twist = np.array([0.1, -0.05, 0.02, 0.3, 0.0, -0.2])[:axes]
    fast.set_target(given, twist)
    slow.set_target(given.copy(), twist.copy())
    # changing the arrays given afterwards changes neither controller's target
    (given[:3, 3] if axes == 6 else given)[...] += 0.2
    twist[0] = 5.0
    q, qd, ref = Q_READY + 0.1, np.full(7, 0.2), armctl.Reference(Q_READY)
    np.testing.assert_allclose(fast(0.0, q, qd, ref), slow(0.0, q, qd, ref), rtol=1e-9, atol=1e-9)
    for c in (fast, slow):  # a new constant target replaces the one the generated law has read
        c.set_target(given, twist, np.full(axes, 0.5))
    np.testing.assert_allclose(fast(0.0, q, qd, ref), slow(0.0, q, qd, ref), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(fast.last_log["error"], slow.last_log["error"], rtol=1e-9, atol=1e-9)


def force_pair(panda: armctl.Dynamics, cls: type, **kwargs: Any) -> tuple[Any, Any]:
    fast = cls(panda, [0.0, 0.0, -10.0], 2e-4, 1e-3, compile=True, **kwargs)
    slow = cls(panda, [0.0, 0.0, -10.0], 2e-4, 1e-3, compile=False, **kwargs)
    assert fast.inner.generated is not None and slow.inner.generated is None
    return fast, slow


@pytest.mark.parametrize("cls", [ForceControl, ParallelForcePosition])
@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_force_control_names_a_non_finite_state_and_keeps_no_state(
    panda: armctl.Dynamics, cls: type, bad: float
) -> None:
    fast, slow = force_pair(panda, cls)
    ref = armctl.Reference(Q_READY)
    sensed = Measurement(wrench=np.array([0.5, -0.2, -7.0, 0.1, 0.0, 0.05]), world_axes=True)
    in_sensor_axes = Measurement(wrench=np.array([0.5, -0.2, -7.0, 0.1, 0.0, 0.05]))
    qd = np.linspace(-0.3, 0.3, 7)
    for m in (sensed, in_sensor_axes):
        for joint in range(7):
            for name in ("q", "qd"):
                q_bad, qd_bad = Q_READY.copy(), qd.copy()
                (q_bad if name == "q" else qd_bad)[joint] = bad
                with pytest.raises(NonFiniteError, match=rf"^{name} holds NaN or inf"):
                    fast(0.0, q_bad, qd_bad, ref, measurement=m)
                assert fast.last_log == {}
    with pytest.raises(NonFiniteError, match="t must be finite"):
        fast(bad, Q_READY, qd, ref, measurement=sensed)
    # nothing was kept: the pose held, the integral and its clock start at the first finite call, as the NumPy
    # law's do
    for k, t in enumerate((0.0, 1e-3, 2e-3)):
        q = Q_READY + 0.01 * k
        np.testing.assert_allclose(
            fast(t, q, qd, ref, measurement=sensed), slow(t, q, qd, ref, measurement=sensed), rtol=1e-8, atol=1e-8
        )
        np.testing.assert_allclose(fast.last_log["offset"], slow.last_log["offset"], rtol=1e-9, atol=1e-12)


def test_force_control_after_a_refused_step_integrates_as_before(panda: armctl.Dynamics) -> None:
    fast, slow = force_pair(panda, ForceControl)
    ref = armctl.Reference(Q_READY)
    m = Measurement(wrench=np.array([0.0, 0.0, -4.0, 0.0, 0.0, 0.0]), world_axes=True)
    qd = np.zeros(7)
    for c in (fast, slow):
        c(0.0, Q_READY, qd, ref, measurement=m)
    with pytest.raises(NonFiniteError, match=r"^qd holds"):
        fast(1e-3, Q_READY, np.full(7, math.nan), ref, measurement=m)
    for c in (fast, slow):  # the refused call moved neither the integral nor its clock
        c(2e-3, Q_READY, qd, ref, measurement=m)
    np.testing.assert_allclose(fast.last_log["offset"], slow.last_log["offset"], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(fast._integral, slow._integral, rtol=1e-12, atol=0.0)
    assert fast._integral[2] == pytest.approx(-6.0 * 2e-3)  # e_f = −10 − (−4) N over Δt = 2 ms, by hand


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_a_measurement_of_float_arrays_is_still_checked(bad: float) -> None:
    h = np.zeros(6)
    h[4] = bad
    with pytest.raises(NonFiniteError, match=r"measurement\.wrench"):
        Measurement(wrench=h)
    with pytest.raises(NonFiniteError, match=r"measurement\.tau_applied"):
        Measurement(tau_applied=np.array([0.0, bad]))
    with pytest.raises(ShapeError, match=r"measurement\.wrench"):
        Measurement(wrench=np.zeros(5))
    with pytest.raises(ShapeError, match=r"measurement\.tau_measured"):
        Measurement(tau_measured=np.zeros((2, 2)))
    big = np.full(6, 1e308)  # finite, whose sum is not: taken through the full check, and accepted
    assert Measurement(wrench=big).wrench is big
    m = Measurement(wrench=np.ones(6), tau_measured=np.ones(3))
    assert m.available() == {"wrench", "tau_measured"}


@pytest.mark.parametrize("zeta", [0.4, 1.0])
def test_the_default_damping_survives_a_pickle(panda: armctl.Dynamics, zeta: float) -> None:
    fast = CartesianImpedance(panda, K, zeta=zeta, compile=True)
    slow = CartesianImpedance(panda, K, zeta=zeta, compile=False)  # D from Λ by the NumPy double diagonalisation
    assert fast._generated is not None and fast._generated.split
    copy = pickle.loads(pickle.dumps(fast))
    target = panda.frame_pose(Q_READY)
    target[:3, 3] += [0.02, -0.01, 0.03]
    for c in (copy, slow):
        c.set_target(target, [0.1, 0.0, -0.1, 0.2, 0.0, 0.1])
    q, qd, ref = Q_READY + 0.1, np.linspace(-0.5, 0.5, 7), armctl.Reference(Q_READY)
    np.testing.assert_allclose(copy(0.0, q, qd, ref), slow(0.0, q, qd, ref), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(copy.last_log["force"], slow.last_log["force"], rtol=1e-9, atol=1e-9)


def test_a_subclass_with_its_own_law_gets_its_inputs_checked_first(panda: armctl.Dynamics) -> None:
    seen: list[np.ndarray] = []

    class Recording(CartesianImpedance):
        def compute(self, t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
            seen.append(q.copy())  # state a NaN must never reach
            return super().compute(t, q, qd, ref)

    class RecordingForce(ForceControl):
        def compute(self, t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
            seen.append(q.copy())
            return super().compute(t, q, qd, ref)

    q = Q_READY.copy()
    q[3] = math.nan
    ref = armctl.Reference(Q_READY)
    with pytest.raises(NonFiniteError, match=r"^q holds NaN or inf"):
        Recording(panda, K, D, compile=True)(0.0, q, np.zeros(7), ref)
    force = RecordingForce(panda, [0.0, 0.0, -10.0], 2e-4, compile=True)
    with pytest.raises(NonFiniteError, match=r"^q holds NaN or inf"):
        force(0.0, q, np.zeros(7), ref, measurement=Measurement(wrench=np.zeros(6)))
    assert seen == []


@pytest.mark.parametrize("variant", ["given damping", "three axes"])
def test_reset_forgets_a_held_pose_and_keeps_a_set_target(panda: armctl.Dynamics, variant: str) -> None:
    fast, slow = pair(panda, variant)
    ref, qd = armctl.Reference(Q_READY), np.full(7, 0.1)
    q1, q2 = Q_READY + 0.1, Q_READY - 0.1
    for c in (fast, slow):
        c(0.0, q1, qd, ref)  # holds the pose at q1
        c.reset()
    np.testing.assert_allclose(fast(0.0, q2, qd, ref), slow(0.0, q2, qd, ref), rtol=1e-9, atol=1e-9)
    held_at_q2 = fast(0.0, q2, np.zeros(7), ref)
    np.testing.assert_allclose(fast.last_log["error"], 0.0, atol=1e-12)  # the pose at q2 is the target now
    axes = len(VARIANTS[variant]["stiffness"])
    pose = panda.frame_pose(Q_READY)
    for c in (fast, slow):
        c.set_target(pose if axes == 6 else pose[:3, 3])
        c.reset()  # a target that was set stays
    np.testing.assert_allclose(fast(0.0, q2, qd, ref), slow(0.0, q2, qd, ref), rtol=1e-9, atol=1e-9)
    assert not np.allclose(fast(0.0, q2, np.zeros(7), ref), held_at_q2)
