"""The generated Cartesian impedance law runs on unchecked q and q̇ (only τ is checked after it): a NaN or inf in
any entry, or a non-finite t, still raises a NonFiniteError naming it, and leaves nothing behind — no held pose,
no log, no trajectory called. The constant target is a copy of what was given, and a new target replaces it."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

import armctl
from armctl.controllers import CartesianImpedance
from armctl.errors import NonFiniteError

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
