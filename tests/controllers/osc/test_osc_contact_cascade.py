"""Two priority levels with a sliding contact and the default limits: where no inequality row is active, both
levels' optimum comes from their equality rows alone (generated code, or NumPy on ``compile=False``), checked
against a cascade of full KKT solves of the public problem that keeps level 0's task rows themselves (no basis),
and against each other; where a row binds, the solver chain takes over on both paths."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.controllers.osc import (
    Contact,
    ContactForceTask,
    FramePoseTask,
    FramePositionTask,
    OperationalSpaceQP,
    PostureTask,
    TorqueLimit,
    default_limits,
)
from armctl.controllers.osc.hierarchy import extend_basis
from armctl.controllers.osc.limits.base import Limit
from armctl.controllers.osc.optimality import residuals

from .helpers import Q_HOME, panda_dynamics


def _sliding(
    limits: list[Limit] | None = None,
    compile: bool | str = "auto",
    active: bool = True,
) -> OperationalSpaceQP:
    """The pose task with its normal direction off and a normal force target in level 0, the posture in level 1;
    ``active=False``: the contact (and its force task) off, the levels on q̈ alone."""
    dyn = panda_dynamics(friction=True)
    pose = FramePoseTask(kp=400.0, weight=[1, 1, 0, 1, 1, 1])
    target = dyn.frame_pose(Q_HOME)
    target[0, 3] += 0.02
    pose.set_target(target)
    contact = Contact(mode="sliding", mu=0.3, kd=100.0, active=active)
    tasks = [pose, ContactForceTask(contact, 8.0, weight=1.0), PostureTask(7, kp=25.0, priority=1)]
    lims = default_limits() if limits is None else limits
    return OperationalSpaceQP(dyn, tasks, limits=lims, contacts=[contact], compile=compile)


def _states(count: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(seed)
    return [(Q_HOME + rng.normal(0.0, 0.1, 7), rng.normal(0.0, 0.3, 7)) for _ in range(count)]


def _kkt(H: np.ndarray, g: np.ndarray, A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The minimum of ½xᵀHx + gᵀx on A x = b by one least-squares solve of the full KKT system."""
    n, k = g.shape[0], b.shape[0]
    K = np.zeros((n + k, n + k))
    K[:n, :n], K[:n, n:], K[n:, :n] = H, A.T, A
    return np.linalg.lstsq(K, np.concatenate((-g, b)), rcond=None)[0][:n]


@pytest.mark.parametrize("active", [True, False])
def test_without_an_active_row_both_levels_are_the_kkt_cascade_on_both_paths(active: bool) -> None:
    """With the contact on and off: the generated code is used, and no solver runs (both levels' optimum from
    their equality rows); τ is the cascade of full KKT solves of the public problem with level 0's weighted task
    rows kept as they are, to 1e-7 N·m; the NumPy path's τ equals the generated path's to 1e-9 N·m, its bounds
    the limits' own; level 1's frozen rows are extend_basis's basis, and each level's reported solution
    satisfies its public problem's KKT conditions to 1e-8."""
    ref = armctl.Reference(Q_HOME)
    ctrl = _sliding(active=active)
    assert ctrl.uses_generated_code
    numpy_ctrl = _sliding(compile=False, active=active)
    taken = 0
    for q, qd in _states(10, seed=21):
        tau = ctrl(0.0, q, qd, ref)
        np.testing.assert_allclose(tau, numpy_ctrl(0.0, q, qd, ref), atol=1e-9, rtol=0)
        sol, np_sol = ctrl.last_solution, numpy_ctrl.last_solution
        assert sol is not None and sol.level_status == ("solved", "solved") and np_sol is not None
        for mine, theirs in ((sol.problem(0).l, np_sol.problem(0).l), (sol.problem(0).u, np_sol.problem(0).u)):
            np.testing.assert_allclose(mine, theirs, rtol=1e-12, atol=1e-12)  # the limits' bounds, as NumPy has them
        if any(s is None or s.solver != "active set" for s in sol.solutions):
            continue  # a row binds: the chain's step (the next test)
        taken += 1
        p0, p1 = sol.problem(0), sol.problem(1)
        x0 = _kkt(p0.H, p0.g, p0.A, p0.b)
        s0 = p0.C.dot(x0)
        assert (s0 >= p0.l - 1e-9).all() and (s0 <= p0.u + 1e-9).all()  # indeed no row active at level 0
        T0 = sol.step.levels[0].T
        T0 = T0[np.linalg.norm(T0, axis=1) > 0]  # rows of zero weight keep nothing
        n_eq = p0.b.shape[0]
        x1 = _kkt(p1.H, p1.g, np.vstack((p1.A[:n_eq], T0)), np.concatenate((p1.b[:n_eq], T0.dot(x0))))
        np.testing.assert_allclose(tau, x1[p1.variables["tau"]], atol=1e-7, rtol=0)
        F = p1.A[n_eq:]
        np.testing.assert_allclose(F, extend_basis(np.zeros((0, T0.shape[1])), T0), atol=1e-12)
        for k, p in enumerate((p0, p1)):
            s = sol.solutions[k]
            assert s is not None and residuals(p.arrays, s.x, s.y, s.z).ok(1e-8, 1e-8)
    assert taken >= 5


def test_a_binding_torque_limit_takes_the_solver_chain_on_both_paths() -> None:
    """Joint 2's torque limit at a third of what the free optimum asks for: the verdict refuses the optimum on
    the equality rows, the chain's solver finds the bound (τ₂ on it), and both paths give the same τ to 1e-9."""
    ref = armctl.Reference(Q_HOME)
    (q, qd), *_ = _states(1, seed=22)
    tau_free = _sliding()(0.0, q, qd, ref)
    limit = np.array([87.0, abs(tau_free[1]) / 3.0, 87.0, 87.0, 12.0, 12.0, 12.0])
    lims = [TorqueLimit(limit), *default_limits()[1:]]
    ctrl, numpy_ctrl = _sliding(lims), _sliding(lims, compile=False)
    tau = ctrl(0.0, q, qd, ref)
    assert abs(tau[1]) == pytest.approx(limit[1], abs=1e-9)
    sol = ctrl.last_solution
    assert sol is not None and sol.solutions[0] is not None and sol.solutions[0].solver != "active set"
    np.testing.assert_allclose(tau, numpy_ctrl(0.0, q, qd, ref), atol=1e-9, rtol=0)


def test_a_two_level_controller_pickles_with_its_generated_code() -> None:
    """A two-level controller with the contact off (its first layout made with it) and on crosses a pickle (as a
    sweep's worker receives it) and gives the same τ, on the generated code (to 1e-6 N·m where a limit binds: the
    copy's solver chain starts cold, and a verified optimum is one to the check's tolerances)."""
    import pickle

    ref = armctl.Reference(Q_HOME)
    states = _states(3, seed=23)
    for active in (False, True):
        ctrl = _sliding(active=active)
        copy = pickle.loads(pickle.dumps(ctrl))
        assert copy.uses_generated_code
        for q, qd in states:
            np.testing.assert_allclose(copy(0.0, q, qd, ref), ctrl(0.0, q, qd, ref), atol=1e-6, rtol=0)
        copy = pickle.loads(pickle.dumps(ctrl))  # after steps too
        for q, qd in states:
            np.testing.assert_allclose(copy(0.0, q, qd, ref), ctrl(0.0, q, qd, ref), atol=1e-6, rtol=0)


def test_dependent_rows_in_level_0_take_the_svd_basis_on_both_paths() -> None:
    """Level 0 with the tool's position asked twice (its rows dependent: T₀T₀ᵀ singular), the posture below: the
    generated code refuses its basis, the step takes extend_basis's SVD basis as the NumPy path does, and both give
    the same τ to 1e-9 N·m with both levels solved; the frozen rows are orthonormal, as many as the rank (3)."""
    dyn = panda_dynamics(friction=True)
    ref = armctl.Reference(Q_HOME)

    def make(compile: bool | str) -> OperationalSpaceQP:
        target = dyn.frame_pose(Q_HOME)[:3, 3] + [0.02, 0.0, -0.01]
        first = FramePositionTask(kp=400.0)
        second = FramePositionTask(kp=400.0, weight=2.0, name="again")
        first.set_target(target)
        second.set_target(target)
        return OperationalSpaceQP(dyn, [first, second, PostureTask(7, kp=25.0, priority=1)], compile=compile)

    ctrl, numpy_ctrl = make("auto"), make(False)
    assert ctrl.uses_generated_code
    for q, qd in _states(4, seed=24):
        np.testing.assert_allclose(ctrl(0.0, q, qd, ref), numpy_ctrl(0.0, q, qd, ref), atol=1e-9, rtol=0)
        sol = ctrl.last_solution
        assert sol is not None and sol.level_status == ("solved", "solved")
        F = sol.problem(1).A[sol.problem(0).b.shape[0] :]
        assert F.shape[0] == 3
        np.testing.assert_allclose(F @ F.T, np.eye(3), atol=1e-12)
