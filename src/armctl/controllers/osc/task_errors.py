"""What the operational-space controllers log of their frame tasks at every step, so that a run's result can
report each task's error in the task's own terms (:attr:`armctl.SimResult.task_errors`): the task's target and
its weights, which cost a step next to nothing (the errors themselves are computed by the result, from the
recorded joint positions, only when asked for).

For a built-in frame task NAME on the frame FRAME (empty for the tool frame), the entries are::

    pose_target[NAME|FRAME]          (4, 4)   the target pose (FramePoseTask)
    position_target[NAME|FRAME]      (3,)     the target position [m] (FramePositionTask)
    orientation_target[NAME|FRAME]   (3, 3)   the target rotation (FrameOrientationTask)
    task_weight[NAME]                (dim,)   the rows' weights (a row of weight 0 is free)

and the errors the result derives from them, with (p, R) the frame's pose at the recorded q::

    position_error[NAME]    = p_ref − p                 (3,) [m], world axes
    orientation_error[NAME] = log(R_ref Rᵀ)             (3,) [rad], world axes (a rotation vector)

the error e of the task's PD law (see :class:`~armctl.controllers.osc.FramePoseTask`), NaN on free rows.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Any

from armctl.controllers.osc.tasks.base import Task
from armctl.controllers.osc.tasks.frame_orientation import FrameOrientationTask
from armctl.controllers.osc.tasks.frame_pose import FramePoseTask
from armctl.controllers.osc.tasks.frame_position import FramePositionTask
from armctl.controllers.osc.tasks.frame_task import FrameTask

_KINDS: dict[type[FrameTask], str] = {
    FramePositionTask: "position",
    FrameOrientationTask: "orientation",
    FramePoseTask: "pose",
}
#: a target entry's key: (kind, task name, frame name or "" for the tool frame)
TARGET_KEY = re.compile(r"^(pose|position|orientation)_target\[(.*)\|([^|]*)\]$")


def target_key(kind: str, name: str, frame: str | None) -> str:
    """The log key of a frame task's target (see the module).

    Parameters
    ----------
    kind : {"pose", "position", "orientation"}
        The task's kind.
    name : str
        The task's name.
    frame : str or None
        Its frame (None: the tool frame).

    Returns
    -------
    str
    """
    return f"{kind}_target[{name}|{frame or ''}]"


def _kind(task: Task) -> str | None:
    """The kind of a built-in frame task, or None (another task, or a subclass with kinematics of its own, whose
    error is not the target's)."""
    for cls, kind in _KINDS.items():
        if isinstance(task, cls) and type(task).kinematics is cls.kinematics:
            return kind
    return None


class FrameTaskLog:
    """The logger of a controller's frame tasks (see the module): built once from the tasks, called at every step.

    Parameters
    ----------
    tasks : sequence of Task
        The controller's tasks; those that are not built-in frame tasks are left out.
    """

    def __init__(self, tasks: Sequence[Task]) -> None:
        self.plan: list[tuple[FrameTask, str, str]] = []
        for task in tasks:
            kind = _kind(task)
            if kind is not None and isinstance(task, FrameTask):
                self.plan.append((task, target_key(kind, task.name, task.frame), f"task_weight[{task.name}]"))

    def __call__(self, log: dict[str, Any], t: float) -> None:
        """Add the targets at t and the weights to a step's log.

        Parameters
        ----------
        log : dict
            The step's ``last_log``.
        t : float
            Time [s] (a trajectory's target is read at t).
        """
        for task, key, weight_key in self.plan:
            if task.target.is_set:
                log[key] = task.target.at(t)[0]
                log[weight_key] = task.weight
