"""A trajectory's output is checked at every step on the generated path as on the NumPy path, with contacts or
without: the same named errors for each kind of bad target, the same τ for valid ones."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

import armctl
from armctl.controllers.osc import (
    Contact,
    ContactForceTask,
    FrameOrientationTask,
    FramePoseTask,
    FramePositionTask,
    OperationalSpaceQP,
    PostureTask,
    TorqueLimit,
)
from armctl.controllers.osc.task_errors import target_key
from armctl.errors import InvalidParameterError, NonFiniteError
from tests.controllers.osc.helpers import Q_HOME, rotation_zyx


def _pose(rot: np.ndarray, p: Any = (0.4, 0.0, 0.5)) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = rot
    out[:3, 3] = p
    return out


ROT = rotation_zyx(np.pi, 0.1, 0.2)
ZERO = np.zeros(6)
#: (bad pose target, velocity, the error and what it says), each found by the NumPy path's check
BAD_POSES: list[tuple[np.ndarray, np.ndarray, type, str]] = [
    (_pose(ROT @ np.diag([1.0, 1.0, -1.0])), ZERO, InvalidParameterError, "reflection"),
    (_pose(1.001 * ROT), ZERO, InvalidParameterError, "not orthonormal"),
    (_pose(ROT + 2e-4), ZERO, InvalidParameterError, "not orthonormal"),
    (_pose(np.zeros((3, 3))), ZERO, InvalidParameterError, "not orthonormal"),
    (_pose(ROT) + np.diag([0.0, 0.0, 0.0, 1e-9]), ZERO, InvalidParameterError, "last row"),
    (_pose(ROT, (0.4, np.nan, 0.5)), ZERO, NonFiniteError, "NaN or inf"),
    (_pose(ROT, (0.4, np.inf, 0.5)), ZERO, NonFiniteError, "NaN or inf"),
    (_pose(ROT), np.array([0.0, 0.0, -np.inf, 0.0, 0.0, 0.0]), NonFiniteError, "velocity"),
]


def _controller(dyn: armctl.Dynamics, task: Any, compile: bool | str) -> OperationalSpaceQP:
    return OperationalSpaceQP(dyn, [task, PostureTask(7, weight=1e-3)], limits=[TorqueLimit()], compile=compile)


def _switching(good: Callable[[float], tuple], bad: tuple) -> Callable[[float], tuple]:
    """A trajectory: ``good(t)`` before t = 0.5 s, then the bad output."""
    return lambda t: good(t) if t < 0.5 else bad


def _same_error_then_on(make: Callable[[str | bool, FramePoseTask], OperationalSpaceQP], bad: int, **task: Any) -> None:
    """On the generated path and on NumPy's, a trajectory's bad pose (``BAD_POSES[bad]``) after a good one raises
    the same named error, and a valid target afterwards gives the step the same τ on both paths."""
    value, vel, kind, message = BAD_POSES[bad]
    ref = armctl.Reference(Q_HOME)
    good = lambda t: (_pose(ROT, (0.4, 0.1 * t, 0.5)), ZERO.copy(), ZERO.copy())  # noqa: E731
    taus = []
    for compile in ("auto", False):
        pose = FramePoseTask(kp=100.0, **task)
        pose.set_trajectory(_switching(good, (value, vel, ZERO.copy())))
        ctrl = make(compile, pose)
        assert ctrl.uses_generated_code is (compile == "auto")
        taus.append(ctrl(0.25, Q_HOME, np.zeros(7), ref))
        with pytest.raises(kind, match=message):
            ctrl(1.0, Q_HOME, np.zeros(7), ref)
        # a valid target afterwards: the step goes on
        taus.append(ctrl(0.3, Q_HOME, np.zeros(7), ref))
    np.testing.assert_allclose(taus[0], taus[2], atol=1e-6)
    np.testing.assert_allclose(taus[1], taus[3], atol=1e-6)


@pytest.mark.parametrize("bad", range(len(BAD_POSES)))
def test_a_bad_pose_from_a_trajectory_raises_the_numpy_paths_error(panda: armctl.Dynamics, bad: int) -> None:
    _same_error_then_on(lambda compile, pose: _controller(panda, pose, compile), bad)


@pytest.mark.parametrize("levels", [1, 2])
@pytest.mark.parametrize("bad", range(len(BAD_POSES)))
def test_a_bad_pose_raises_the_numpy_paths_error_with_a_contact(panda: armctl.Dynamics, bad: int, levels: int) -> None:
    """With an active contact (the contact QP's generated data, one level or two): the same named error, and the
    step goes on with a valid target afterwards."""

    def make(compile: str | bool, pose: FramePoseTask) -> OperationalSpaceQP:
        contact = Contact(mode="sliding", mu=0.3, kd=100.0)
        tasks = [pose, ContactForceTask(contact, 8.0), PostureTask(7, kp=25.0, weight=1e-3, priority=levels - 1)]
        return OperationalSpaceQP(panda, tasks, limits=[TorqueLimit()], contacts=[contact], compile=compile)

    _same_error_then_on(make, bad, weight=[1, 1, 0, 1, 1, 1])


def test_orientation_and_position_trajectories_are_checked(panda: armctl.Dynamics) -> None:
    ref = armctl.Reference(Q_HOME)
    for compile in ("auto", False):
        orientation = FrameOrientationTask(kp=50.0)
        orientation.set_trajectory(_switching(lambda t: (ROT, np.zeros(3), np.zeros(3)), (2.0 * ROT, None, None)))
        ctrl = _controller(panda, orientation, compile)
        assert ctrl.uses_generated_code is (compile == "auto")
        ctrl(0.0, Q_HOME, np.zeros(7), ref)
        with pytest.raises(InvalidParameterError, match="not orthonormal"):
            ctrl(1.0, Q_HOME, np.zeros(7), ref)
        position = FramePositionTask(kp=50.0)
        nan_acc = np.array([0.0, np.nan, 0.0])
        position.set_trajectory(
            _switching(lambda t: (np.full(3, 0.3), np.zeros(3), np.zeros(3)), (np.zeros(3), np.zeros(3), nan_acc))
        )
        ctrl = _controller(panda, position, compile)
        ctrl(0.0, Q_HOME, np.zeros(7), ref)
        with pytest.raises(NonFiniteError, match="acceleration"):
            ctrl(1.0, Q_HOME, np.zeros(7), ref)


def test_rounded_rotations_and_other_kinds_of_output_are_taken(panda: armctl.Dynamics) -> None:
    """A rotation rounded in the 4th decimal passes (as set_target takes it); lists and None velocities are
    converted as the NumPy path converts them; the log holds the target read."""
    rounded = np.array([[0.7071, -0.7071, 0.0], [0.7071, 0.7071, 0.0], [0.0, 0.0, 1.0]]) @ np.diag([1.0, -1.0, -1.0])
    outputs = [
        (_pose(rounded), ZERO, ZERO),
        (_pose(ROT).tolist(), None, None),
        (_pose(ROT).astype(np.float32), ZERO, ZERO),
        (np.asfortranarray(_pose(ROT)), ZERO, ZERO),
    ]
    ref = armctl.Reference(Q_HOME)
    for out in outputs:
        taus = []
        for compile in ("auto", False):
            task = FramePoseTask(kp=100.0)
            task.set_trajectory(lambda t, out=out: out)
            ctrl = _controller(panda, task, compile)
            taus.append(ctrl(0.0, Q_HOME, np.zeros(7), ref))
            logged = ctrl.last_log[target_key("pose", task.name, task.frame)]
            np.testing.assert_array_equal(logged, np.asarray(out[0], dtype=float))
        np.testing.assert_allclose(taus[0], taus[1], atol=1e-6)
