"""Bad input and infeasible problems raise ArmctlError subclasses that name the value."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.controllers.osc import (
    AccelerationLimit,
    ClosedFormOSC,
    Contact,
    ContactForceTask,
    FrameOrientationTask,
    FramePoseTask,
    FramePositionTask,
    JointPositionLimit,
    JointVelocityLimit,
    OperationalSpaceQP,
    PostureTask,
    QPProblem,
    TorqueLimit,
)
from armctl.errors import (
    ArmctlError,
    InfeasibleError,
    InvalidParameterError,
    NonFiniteError,
    ShapeError,
    UnknownNameError,
)
from tests.controllers.osc.helpers import Q_HOME, quadprog_solvers, rotation_zyx


def test_unknown_frame_lists_the_valid_names(panda: armctl.Dynamics) -> None:
    with pytest.raises(UnknownNameError) as err:
        OperationalSpaceQP(panda, [FramePositionTask("panda_hand_tpc")])
    assert "panda_hand_tcp" in str(err.value) and "panda_link7" in str(err.value)
    assert "panda_hand_tcp" in err.value.valid
    with pytest.raises(UnknownNameError, match="panda_hand_tcp"):
        OperationalSpaceQP(panda, [PostureTask(7)], contacts=[Contact("gripper")])


@pytest.mark.parametrize(
    "make",
    [
        lambda: PostureTask(6),  # a 6-joint posture on a 7-joint arm: raised when given to the controller
        lambda: FramePoseTask(kp=np.ones(3)),
        lambda: FramePositionTask(kp=100.0, kd=np.ones(4)),
        lambda: FramePositionTask(weight=[1.0, 1.0]),
        lambda: PostureTask(7, kp=np.ones((7, 6))),
    ],
)
def test_tasks_of_the_wrong_size(panda: armctl.Dynamics, make) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ShapeError):
        OperationalSpaceQP(panda, [make()])


def test_targets_of_the_wrong_size(panda: armctl.Dynamics) -> None:
    task = FramePositionTask()
    with pytest.raises(ShapeError):
        task.set_target([0.1, 0.2])
    pose = FramePoseTask()
    with pytest.raises(ShapeError):
        pose.set_target(np.eye(3))
    pose.set_trajectory(lambda t: (np.eye(4), np.zeros(5), None))
    ctrl = OperationalSpaceQP(panda, [pose])
    with pytest.raises(ShapeError, match="velocity"):
        ctrl(0.0, Q_HOME, np.zeros(7), armctl.Reference(Q_HOME))
    with pytest.raises(InvalidParameterError, match="no target"):
        OperationalSpaceQP(panda, [FramePositionTask()])(0.0, Q_HOME, np.zeros(7), armctl.Reference(Q_HOME))


def test_rotation_and_pose_targets_must_be_rotations(panda: armctl.Dynamics) -> None:
    # a reflection, a scaled or a zero matrix would give a zero rotation error: the task would think it is there
    rot = rotation_zyx(0.1, 0.2, 0.3)
    orientation, pose = FrameOrientationTask(), FramePoseTask()
    for bad, why in [
        (rot @ np.diag([1.0, 1.0, -1.0]), "reflection"),
        (2.0 * rot, "not orthonormal"),
        (np.zeros((3, 3)), "not orthonormal"),
        (rot + 1e-3, "not orthonormal"),
    ]:
        with pytest.raises(InvalidParameterError, match=why):
            orientation.set_target(bad)
        pose_matrix = np.eye(4)
        pose_matrix[:3, :3] = bad
        with pytest.raises(InvalidParameterError, match=why):
            pose.set_target(pose_matrix)
    skewed = np.eye(4)
    skewed[3, 0] = 0.1
    with pytest.raises(InvalidParameterError, match="last row"):
        pose.set_target(skewed)
    # rounded in the 4th decimal: accepted
    orientation.set_target(np.array([[0.7071, -0.7071, 0.0], [0.7071, 0.7071, 0.0], [0.0, 0.0, 1.0]]))
    # checked on every call of a trajectory too
    pose.set_trajectory(lambda t: (skewed if t > 0.5 else np.eye(4), np.zeros(6), np.zeros(6)))
    ctrl = OperationalSpaceQP(panda, [pose, PostureTask(7, weight=1e-3)])
    ref = armctl.Reference(Q_HOME)
    ctrl(0.0, Q_HOME, np.zeros(7), ref)
    with pytest.raises(InvalidParameterError, match="last row"):
        ctrl(1.0, Q_HOME, np.zeros(7), ref)


def test_build_and_solve_check_their_inputs(panda: armctl.Dynamics) -> None:
    ctrl = OperationalSpaceQP(panda, [PostureTask(7)])
    ref = armctl.Reference(Q_HOME)
    for method in (ctrl.build, ctrl.solve):
        with pytest.raises(ShapeError, match="reference has 1 joints"):
            method(0.0, Q_HOME, np.zeros(7), armctl.Reference([0.1]))
        with pytest.raises(InvalidParameterError, match=r"armctl\.Reference"):
            method(0.0, Q_HOME, np.zeros(7), Q_HOME)  # type: ignore[arg-type]
        with pytest.raises(ArmctlError, match=r"^t must be"):
            method(np.nan, Q_HOME, np.zeros(7), ref)
        with pytest.raises(ShapeError, match=r"^qd"):
            method(0.0, Q_HOME, np.zeros(6), ref)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"weight": -1.0}, r"weight must be >= 0, got \[-1.0"),
        ({"weight": [1.0, -0.1, 1.0]}, r"weight must be >= 0"),
        ({"kp": -5.0}, "kp must be positive definite"),
        ({"kp": [[1.0, 2.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], "kd": 1.0}, "kp must be symmetric"),
        ({"priority": -1}, "priority must be a whole number >= 0, got -1"),
        ({"priority": 1.5}, "priority must be a whole number >= 0, got 1.5"),
        ({"weight": np.nan}, "weight holds NaN"),
    ],
)
def test_negative_weights_gains_and_bad_priorities(kwargs: dict, message: str) -> None:
    with pytest.raises(ArmctlError, match=message):
        FramePositionTask(**kwargs)


def test_other_bad_input(panda: armctl.Dynamics) -> None:
    with pytest.raises(InvalidParameterError, match="at least one task"):
        OperationalSpaceQP(panda, [])
    with pytest.raises(InvalidParameterError, match="unique"):
        OperationalSpaceQP(panda, [PostureTask(7), PostureTask(7)])
    with pytest.raises(InvalidParameterError):
        OperationalSpaceQP(panda, ["posture"])  # type: ignore[list-item]
    with pytest.raises(UnknownNameError, match="proxsuite"):
        OperationalSpaceQP(panda, [PostureTask(7)], solver="gurobi")
    with pytest.raises(UnknownNameError, match="qpsolvers solver"):
        OperationalSpaceQP(panda, [PostureTask(7)], solver="qpsolvers:nonexistent")
    with pytest.raises(UnknownNameError, match="contact"):  # a force task on an undeclared contact
        OperationalSpaceQP(panda, [ContactForceTask(Contact(), [0, 0, 1])])
    with pytest.raises(InvalidParameterError):
        Contact(normal=(0, 0, 0))
    with pytest.raises(UnknownNameError, match="fixed"):
        Contact(mode="rolling")
    with pytest.raises(ShapeError):
        OperationalSpaceQP(panda, [PostureTask(7)], limits=[TorqueLimit(np.ones(6))])
    with pytest.raises(InvalidParameterError):
        OperationalSpaceQP(panda, [PostureTask(7)], limits=[TorqueLimit(-1.0)])
    with pytest.raises(InvalidParameterError, match="frame MotionTask"):
        ClosedFormOSC(panda, PostureTask(7))
    ctrl = OperationalSpaceQP(panda, [PostureTask(7)])
    with pytest.raises(ShapeError):
        ctrl(0.0, np.zeros(6), np.zeros(7), armctl.Reference(Q_HOME))


def test_infeasible_qp_names_the_conflicting_rows(panda: armctl.Dynamics) -> None:
    """Holding the arm against gravity needs |τ₂| ≈ 4 and |τ₄| ≈ 22 N·m at the home posture; with |τ| ≤ 1 N·m
    and |q̈| ≤ 0.01 rad/s² no τ exists. The error carries the problem and names those joints' rows."""
    g = panda.gravity_torque(Q_HOME)
    over = {f"panda_joint{i + 1}" for i in np.flatnonzero(np.abs(g) > 1.0 + 0.5)}  # clearly out of reach
    assert {"panda_joint2", "panda_joint4"} <= over
    ctrl = OperationalSpaceQP(panda, [PostureTask(7)], limits=[TorqueLimit(1.0), AccelerationLimit(0.01)])
    with pytest.raises(InfeasibleError) as err:
        ctrl(0.0, Q_HOME, np.zeros(7), armctl.Reference(Q_HOME))
    e = err.value
    assert e.problem is not None and e.problem.A.shape == (7, 14)
    names = set(e.value)
    for j in over:
        assert f"torque_limit[{j}]" in names or f"acceleration_limit[{j}]" in names, (j, names)
    assert "torque_limit[panda_joint4]" in str(e) or "acceleration_limit[panda_joint4]" in str(e)
    assert not any(nm.startswith("dynamics[") for nm in names)  # the equation of motion is never relaxed
    assert max(e.value.values()) > 1.0  # joint 4 needs ~20 N·m more than allowed


def _contact_problem(torque: float) -> QPProblem:
    """½ q̈ − τ = 0 (physics), q̈ = 5 (a contact's row), |τ| ≤ ``torque``, cost ½‖x‖²."""
    return QPProblem(
        np.eye(2),
        np.zeros(2),
        np.array([[0.5, -1.0], [1.0, 0.0]]),
        np.array([0.0, 5.0]),
        np.array([[0.0, 1.0]]),
        np.array([-torque]),
        np.array([torque]),
        {"qdd": slice(0, 1), "tau": slice(1, 2)},
        ("dynamics[j]", "contact.acceleration[x]"),
        ("torque_limit[j]",),
    )


def test_a_row_that_binds_the_conflict_is_named_with_zero() -> None:
    """A QP made by hand: ½ q̈ − τ = 0 (physics), q̈ = 5 (a contact's row), |τ| ≤ 1. By hand, the cheapest
    relaxation is the torque limit's by 1.5 (τ = 2.5), not the contact row's by 3 (q̈ = 2, τ = 1): the contact
    row is met exactly yet binds the conflict, so it is named with 0 (module docstring of diagnose); the
    equation of motion never is."""
    from armctl.controllers.osc.diagnose import conflicting_rows
    from armctl.controllers.osc.solve import ProxQPSolver

    p = _contact_problem(1.0)
    rows = conflicting_rows(p)
    assert rows is not None and set(rows) == {"torque_limit[j]", "contact.acceleration[x]"}
    assert rows["torque_limit[j]"] == pytest.approx(1.5, abs=1e-6)
    assert rows["contact.acceleration[x]"] == 0.0
    with pytest.raises(InfeasibleError) as err:  # and the solver's error names it too
        ProxQPSolver().solve(p)
    assert err.value.value == rows
    assert "contact.acceleration[x], torque_limit[j] (relax by 1.5)" in str(err.value)


@pytest.mark.parametrize("make", ["proxsuite", "qpsolvers:quadprog", "daqp", "active-set"])
def test_every_solver_solves_a_named_problem_and_names_the_conflicting_rows(make: str) -> None:
    """Each solver of the controller's chain, called on a named problem (``solve``, from QPSolver): with |τ| ≤ 3
    the equalities alone fix x = (5, 2.5) by hand; with |τ| ≤ 1 there is no feasible point and the error names
    the rows found by hand in the test above (torque limit relaxed by 1.5, the contact row binding with 0)."""
    from armctl.controllers.osc import DaqpSolver, DualActiveSetSolver, QPSolver
    from armctl.controllers.osc.solve import make_solver

    if make == "qpsolvers:quadprog":
        quadprog_solvers()  # (skips without quadprog)
    own = {"daqp": DaqpSolver, "active-set": DualActiveSetSolver}
    solver = own[make]() if make in own else make_solver(make)
    assert isinstance(solver, QPSolver)
    sol = solver.solve(_contact_problem(3.0))
    np.testing.assert_allclose(sol.x, [5.0, 2.5], atol=1e-5)
    with pytest.raises(InfeasibleError) as err:
        solver.solve(_contact_problem(1.0))
    assert set(err.value.value) == {"torque_limit[j]", "contact.acceleration[x]"}
    assert err.value.value["torque_limit[j]"] == pytest.approx(1.5, abs=1e-6)
    assert err.value.value["contact.acceleration[x]"] == 0.0


@pytest.mark.parametrize(
    ("make", "error", "message"),
    [
        (lambda d: OperationalSpaceQP(d, None), InvalidParameterError, "tasks must be a Task or a sequence"),
        (
            lambda d: OperationalSpaceQP(d, [PostureTask(7)], limits=5),
            InvalidParameterError,
            "limits must be a Limit or a sequence",
        ),
        (lambda d: PostureTask(0), InvalidParameterError, r"n \(the number of joints\) must be a whole number >= 1"),
        (lambda d: PostureTask("a"), InvalidParameterError, "must be a whole number >= 1, got 'a'"),
        (
            lambda d: OperationalSpaceQP(d, [PostureTask(7)], limits=[TorqueLimit(["a"] * 7)]),
            InvalidParameterError,
            "torque limit must hold real numbers",
        ),
        # an infinite braking limit would turn the viability bounds into NaN (inf · 0) and so switch them off
        (
            lambda d: OperationalSpaceQP(
                d, [PostureTask(7)], limits=[JointPositionLimit(1e-3, max_deceleration=np.inf)]
            ),
            NonFiniteError,
            r"max_deceleration must be finite for every joint, got \[inf",
        ),
        (
            lambda d: OperationalSpaceQP(
                d, [PostureTask(7)], limits=[JointVelocityLimit(1e-3, max_deceleration=np.nan)]
            ),
            NonFiniteError,
            "max_deceleration must be finite",
        ),
    ],
)
def test_containers_counts_and_limits_are_checked(
    panda: armctl.Dynamics,
    make,
    error: type,  # type: ignore[no-untyped-def]
    message: str,
) -> None:
    with pytest.raises(error, match=message):
        make(panda)


def test_a_pulling_contact_force_target_is_refused_with_the_sign_convention() -> None:
    wall = Contact(normal=(-1.0, 0.0, 0.0), mode="sliding", mu=0.3)  # a wall at +x: its normal points back at -x
    # pressing 15 N into the wall: the wall pushes the robot along -x, i.e. +15 along its normal
    assert ContactForceTask(wall, 15.0).target(0.0).tolist() == [15.0]
    assert ContactForceTask(wall, (-15.0, 0.0, 0.0)).target(0.0).tolist() == [15.0]  # projected on the normal
    with pytest.raises(InvalidParameterError, match=r"normal component of -15 N, a pull .* ask for 15$"):
        ContactForceTask(wall, -15.0)
    with pytest.raises(InvalidParameterError, match=r"normal component of -15 N.*ask for 15 times the normal"):
        ContactForceTask(Contact(normal=(-1.0, 0.0, 0.0)), (15.0, 0.0, 0.0))  # the robot's push, not the wall's
    task = ContactForceTask(wall, lambda t: 10.0 - 20.0 * t)  # a callable is checked when evaluated
    assert task.target(0.25).tolist() == [5.0]
    with pytest.raises(InvalidParameterError, match="a pull"):
        task.target(1.0)
    assert ContactForceTask(wall, 0.0).target(0.0).tolist() == [0.0]  # zero: allowed (no force wanted)
    # round-off is not a pull: a tangential target on a tilted fixed contact, a ramp that ends at zero
    for tilt in np.linspace(0.0, np.pi / 2, 50):
        normal = np.array([0.0, np.sin(tilt), np.cos(tilt)])
        tangent = np.array([0.0, np.cos(tilt), -np.sin(tilt)])
        ContactForceTask(Contact(normal=normal), 7.0 * tangent).target(0.0)
    ramp = ContactForceTask(wall, lambda t: 0.3 - 0.1 * t)
    assert abs(ramp.target(3.0)[0]) < 1e-15
    with pytest.raises(InvalidParameterError, match="a pull"):
        ContactForceTask(wall, -1e-6)  # a micronewton pull is one


def test_a_normal_force_target_given_as_a_float_is_checked_as_any_other() -> None:
    """A sliding contact's force target as a Python float (what a ramp sets each step): a press is taken as the
    one-entry target, a pull, NaN or an infinite one refused as the same value given as an array is."""
    from armctl.errors import NonFiniteError

    task = ContactForceTask(Contact(mode="sliding", mu=0.3), 0.0)
    for value in (0.0, 2.5, 1e300):
        task.set_target(value)
        got = task.target(0.0)
        assert got.tolist() == [value] and got.dtype == np.float64
        task.set_target(np.array([value]))
        assert task.target(0.0).tolist() == [value]
    for bad, error in ((-1.0, InvalidParameterError), (float("nan"), NonFiniteError), (float("inf"), NonFiniteError)):
        with pytest.raises(error):
            task.set_target(bad)
        with pytest.raises(error):
            task.set_target(np.array([bad]))
