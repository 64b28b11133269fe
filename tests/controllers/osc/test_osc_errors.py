"""Bad input and infeasible problems raise ArmctlError subclasses that name the value (issue 5)."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.controllers.osc import (
    AccelerationLimit,
    ClosedFormOSC,
    Contact,
    ContactForceTask,
    FramePoseTask,
    FramePositionTask,
    OperationalSpaceQP,
    PostureTask,
    TorqueLimit,
)
from armctl.errors import ArmctlError, InfeasibleError, InvalidParameterError, ShapeError, UnknownNameError

from .conftest import Q_HOME


def test_unknown_frame_lists_the_valid_names(panda: armctl.Dynamics) -> None:
    with pytest.raises(UnknownNameError) as err:
        OperationalSpaceQP(panda, [FramePositionTask("panda_hand_tpc")])
    assert "panda_hand_tcp" in str(err.value) and "panda_link7" in str(err.value)
    assert "panda_hand_tcp" in err.value.valid
    with pytest.raises(UnknownNameError, match="panda_hand_tcp"):
        OperationalSpaceQP(panda, [PostureTask(7)], contacts=[Contact("gripper")])


@pytest.mark.parametrize("make", [
    lambda: PostureTask(6),  # a 6-joint posture on a 7-joint arm: raised when given to the controller
    lambda: FramePoseTask(kp=np.ones(3)),
    lambda: FramePositionTask(kp=100.0, kd=np.ones(4)),
    lambda: FramePositionTask(weight=[1.0, 1.0]),
    lambda: PostureTask(7, kp=np.ones((7, 6))),
])
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


@pytest.mark.parametrize("kwargs", [{"weight": -1.0}, {"weight": [1.0, -0.1, 1.0]}, {"kp": -5.0},
                                    {"kp": [[1.0, 2.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], "kd": 1.0},
                                    {"priority": -1}, {"priority": 1.5}, {"weight": np.nan}])
def test_negative_weights_gains_and_bad_priorities(kwargs: dict) -> None:
    with pytest.raises(ArmctlError):
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
