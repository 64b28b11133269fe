"""What the operational-space controllers log of their frame tasks at every step: each task's position and
orientation error, so that a run's result (``SimResult.logs``, :meth:`~armctl.sim.result.SimResult.task_errors`)
reads in the task's own terms.

For a frame task with target (p_ref, R_ref) and the frame's pose (p, R) at the measured q::

    position_error[NAME]    = p_ref − p                 (3,) [m], world axes
    orientation_error[NAME] = log(R_ref Rᵀ)             (3,) [rad], world axes (a rotation vector)

the error e of the task's PD law (see :class:`~armctl.controllers.osc.FramePoseTask`). A row whose weight is 0 is
free (the task does not ask anything of it, e.g. the normal row of a pose task while a contact holds the force):
it is logged as NaN.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from armctl._checks import FloatArray
from armctl.controllers.osc.tasks.base import Task
from armctl.controllers.osc.tasks.frame_orientation import FrameOrientationTask
from armctl.controllers.osc.tasks.frame_pose import FramePoseTask
from armctl.controllers.osc.tasks.frame_position import FramePositionTask
from armctl.controllers.osc.tasks.frame_task import FrameTask
from armctl.controllers.osc.tasks.rotation import rotation_error

#: the log keys' prefixes: ``position_error[NAME]`` and ``orientation_error[NAME]``
POSITION_KEY = "position_error"
ORIENTATION_KEY = "orientation_error"

_KINDS: dict[type[FrameTask], tuple[bool, bool]] = {
    FramePositionTask: (True, False),
    FrameOrientationTask: (False, True),
    FramePoseTask: (True, True),
}


def _kind(task: Task) -> tuple[bool, bool] | None:
    """(position, orientation) logged for a built-in frame task, or None (another task, or a subclass with
    kinematics of its own, whose error is not the target's)."""
    for cls, kind in _KINDS.items():
        if isinstance(task, cls) and type(task).kinematics is cls.kinematics:
            return kind
    return None


class FrameTaskErrors:
    """The logger of a controller's frame tasks (see the module): built once from the tasks, called at every step.

    Parameters
    ----------
    tasks : sequence of Task
        The controller's tasks; those that are not built-in frame tasks are left out.
    """

    def __init__(self, tasks: Sequence[Task]) -> None:
        self.plan: list[tuple[FrameTask, bool, bool, str, str]] = []
        for task in tasks:
            kind = _kind(task)
            if kind is not None and isinstance(task, FrameTask):
                keys = f"{POSITION_KEY}[{task.name}]", f"{ORIENTATION_KEY}[{task.name}]"
                self.plan.append((task, *kind, *keys))
        #: per task, the weight revision seen and its free rows (None: every row weighted)
        self._free: dict[int, tuple[int, np.ndarray | None]] = {}

    def _free_rows(self, task: FrameTask) -> np.ndarray | None:
        seen = self._free.get(id(task))
        if seen is None or seen[0] != task.revision:
            zero = task.weight <= 0.0
            seen = (task.revision, zero if zero.any() else None)
            self._free[id(task)] = seen
        return seen[1]

    def __call__(
        self, frame_pose: Callable[[FloatArray, str | None], FloatArray], q: FloatArray, t: float
    ) -> dict[str, Any]:
        """The errors at (t, q).

        Parameters
        ----------
        frame_pose : callable
            ``frame_pose(q, frame) -> (4, 4)`` pose of a frame in the world (the controller's model).
        q : ndarray, shape (n,)
            The measured joint positions [rad or m].
        t : float
            Time [s] (a trajectory's target is read at t).

        Returns
        -------
        dict of str to ndarray
            ``position_error[NAME]`` (3,) [m] and ``orientation_error[NAME]`` (3,) [rad]; NaN on rows of weight 0.
        """
        out: dict[str, Any] = {}
        for task, position, orientation, key_p, key_o in self.plan:
            if not task.target.is_set:
                continue
            value = task.target.at(t)[0]
            pose = frame_pose(q, task.frame)
            free = self._free_rows(task)
            if position:
                e = (value[:3, 3] if value.shape == (4, 4) else value) - pose[:3, 3]
                if free is not None:
                    e[free[:3]] = np.nan
                out[key_p] = e
            if orientation:
                e = rotation_error(value[:3, :3], pose[:3, :3])
                if free is not None:
                    e[free[3:] if position else free] = np.nan
                out[key_o] = e
        return out
