"""The QPs solved in their generated code past the minimum without active rows: the q̈-only QP on the rows that
its unconstrained minimum breaks, the contact QP by active-set iterations from the rows its optimum on the
contact rows breaks. Where that gives the optimum the step takes it (checked in the code), where it does not the
solver chain takes over; either way τ is the optimum of an independent solver (quadprog) and that of the NumPy
path."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.controllers.osc import (
    AccelerationLimit,
    Contact,
    ContactForceTask,
    FramePoseTask,
    OperationalSpaceQP,
    PostureTask,
    TorqueLimit,
)
from tests.controllers.osc.helpers import quadprog_solvers

from .conftest import Q_HOME

qpsolvers = quadprog_solvers()
if armctl.codegen.compiler() is None:  # pragma: no cover - the machines that run the tests have one
    pytest.skip("no C compiler: no generated code", allow_module_level=True)


def _controller(dyn: armctl.Dynamics, compile: bool, accel: bool) -> OperationalSpaceQP:
    """Pose (kp 400, the ready pose's tool pose) + posture (kp 100, weight 1e-3), the URDF's torque limits and,
    with ``accel``, |q̈| ≤ 40 rad/s² (constant bounds: 14 inequality rows)."""
    pose = FramePoseTask(kp=400.0)
    pose.set_target(dyn.frame_pose(Q_HOME))
    limits = [TorqueLimit(), AccelerationLimit(40.0)] if accel else [TorqueLimit()]
    return OperationalSpaceQP(dyn, [pose, PostureTask(7, kp=100.0, weight=1e-3)], limits=limits, compile=compile)


@pytest.mark.parametrize("accel", [False, True])
def test_the_guessed_active_set_gives_the_optimum_or_hands_over(accel: bool) -> None:
    """200 states near the ready pose (q̇ large enough that the limits bind on many): τ within 1e-6 of quadprog's
    cold optimum of the public problem and within 1e-9 of the NumPy path's; the steps solved in the code (no
    solver iteration, an active row) and by the chain's solver (iterations) both occur; the check run again
    passes on every step."""
    model = armctl.models.panda()
    dyn, plain = armctl.Dynamics(model, compile=True), armctl.Dynamics(model, compile=False)
    ctrl, numpy_path = _controller(dyn, True, accel), _controller(plain, False, accel)
    ref = armctl.Reference(Q_HOME)
    rng = np.random.default_rng(11)
    in_code = by_solver = 0
    for _ in range(200):
        q, qd = Q_HOME + rng.normal(0.0, 0.1, 7), rng.normal(0.0, 0.6, 7)
        tau = ctrl(0.0, q, qd, ref)
        np.testing.assert_allclose(tau, numpy_path(0.0, q, qd, ref), atol=1e-9)
        sol = ctrl.last_solution
        assert sol is not None and sol.solutions[0] is not None
        first = sol.solutions[0]
        assert first.active is not None
        if first.iterations == 0 and first.active.any():
            in_code += 1
        elif first.iterations > 0:
            by_solver += 1
        assert ctrl.verify_last_step()
        p = ctrl.build(0.0, q, qd, ref).problem(0)
        best = np.asarray(qpsolvers.solve_problem(p.to_qpsolvers(), "quadprog").x)[p.variables["tau"]]
        rows = [i for i, name in enumerate(p.ineq_names) if name.startswith("torque_limit[")]
        np.testing.assert_allclose(tau, np.clip(best, p.l[rows], p.u[rows]), atol=1e-6)
    assert in_code >= 20 and by_solver >= 5, (in_code, by_solver)
    assert ctrl.fallback_counts.get("failed", 0) == 0


def _rows_the_minimum_breaks(p: object) -> np.ndarray:
    """+1 / −1 for each inequality row that the optimum on the equality rows alone puts above u / below l (the
    KKT system of the public problem solved with NumPy), 0 elsewhere."""
    H, g, A, b, C, lo, up = (np.asarray(getattr(p, k)) for k in ("H", "g", "A", "b", "C", "l", "u"))
    nx, me = H.shape[0], A.shape[0]
    kkt = np.block([[H, A.T], [A, np.zeros((me, me))]])
    x = np.linalg.solve(kkt, np.concatenate([-g, b]))[:nx]
    s = C @ x
    return np.where(s > up, 1, np.where(s < lo, -1, 0))


def test_the_code_solves_past_a_wrong_first_guess() -> None:
    """Where the rows that the unconstrained minimum breaks are not the optimum's active set, the code's second
    active-set step finds it on some states: the step is taken from the code (no solver iteration) with an
    active set other than that first guess, and τ is quadprog's optimum."""
    model = armctl.models.panda()
    ctrl = _controller(armctl.Dynamics(model, compile=True), True, False)
    ref = armctl.Reference(Q_HOME)
    rng = np.random.default_rng(2)
    second = 0
    for _ in range(300):
        q, qd = Q_HOME + rng.normal(0.0, 0.1, 7), rng.normal(0.0, 0.6, 7)
        tau = ctrl(0.0, q, qd, ref)
        first = ctrl.last_solution.solutions[0]  # type: ignore[union-attr]
        if first is None or first.iterations > 0 or not first.active.any():
            continue
        p = ctrl.build(0.0, q, qd, ref).problem(0)
        if np.array_equal(first.active, _rows_the_minimum_breaks(p)):
            continue
        second += 1
        best = np.asarray(qpsolvers.solve_problem(p.to_qpsolvers(), "quadprog").x)[p.variables["tau"]]
        np.testing.assert_allclose(tau, np.clip(best, p.l, p.u), atol=1e-6)
    assert second >= 3, second


def _kind(ctrl: OperationalSpaceQP) -> str:
    """How the last step's level-0 optimum was found: "none active" (no row active, no solver), "in code" (rows
    active, no solver iteration) or "solver"."""
    sol = ctrl.last_solution
    assert sol is not None and sol.solutions[0] is not None
    first = sol.solutions[0]
    assert first.active is not None
    if first.iterations > 0:
        return "solver"
    return "in code" if first.active.any() else "none active"


def test_the_contact_qps_active_set_iterations_give_the_optimum_or_hand_over() -> None:
    """A fixed contact (μ 0.3, 4 facets) with a force target (0, 0, 10) N, pose + posture, torque limits, 300 states
    near the ready pose: τ within 1e-6 of quadprog's optimum of the public problem and 1e-9 of the NumPy path's;
    optima found in the code and by the solver both occur; the check run again passes."""
    model = armctl.models.panda()

    def make(compile: bool) -> OperationalSpaceQP:
        dyn = armctl.Dynamics(model, compile=compile)
        pose = FramePoseTask(kp=400.0)
        pose.set_target(dyn.frame_pose(Q_HOME))
        contact = Contact(mu=0.3, facets=4)
        tasks = [pose, PostureTask(7, kp=100.0, weight=1e-3), ContactForceTask(contact, (0.0, 0.0, 10.0))]
        return OperationalSpaceQP(dyn, tasks, limits=[TorqueLimit()], contacts=[contact], compile=compile)

    ctrl, numpy_path = make(True), make(False)
    ref = armctl.Reference(Q_HOME)
    rng = np.random.default_rng(5)
    kinds: dict[str, int] = {}
    for _ in range(300):
        q, qd = Q_HOME + rng.normal(0.0, 0.1, 7), rng.normal(0.0, 0.3, 7)
        tau = ctrl(0.0, q, qd, ref)
        np.testing.assert_allclose(tau, numpy_path(0.0, q, qd, ref), atol=1e-9)
        kind = _kind(ctrl)
        kinds[kind] = kinds.get(kind, 0) + 1
        assert ctrl.verify_last_step()
        if kind == "none active":
            continue
        p = ctrl.build(0.0, q, qd, ref).problem(0)
        best = np.asarray(qpsolvers.solve_problem(p.to_qpsolvers(), "quadprog").x)[p.variables["tau"]]
        rows = [i for i, name in enumerate(p.ineq_names) if name.startswith("torque_limit[")]
        np.testing.assert_allclose(tau, np.clip(best, p.l[rows], p.u[rows]), atol=1e-6)
    assert kinds.get("in code", 0) >= 10 and kinds.get("solver", 0) >= 3, kinds
