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

from collections.abc import Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from armctl._checks import FloatArray
from armctl.controllers.osc.tasks.base import Task
from armctl.controllers.osc.tasks.frame_orientation import FrameOrientationTask
from armctl.controllers.osc.tasks.frame_pose import FramePoseTask
from armctl.controllers.osc.tasks.frame_position import FramePositionTask
from armctl.controllers.osc.tasks.frame_task import FrameTask
from armctl.controllers.osc.tasks.rotation import rotation_error
from armctl.dynamics.kernel import Kernel
from armctl.dynamics.pinocchio_backend import PinocchioKernel

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
        #: per task, the last target value seen and its position and rotation
        self._targets: dict[int, tuple[FloatArray, FloatArray, FloatArray]] = {}
        #: Pinocchio's frame ids, by frame name (None: the tool frame)
        self._frame_ids: dict[str | None, int] = {}

    def _free_rows(self, task: FrameTask) -> np.ndarray | None:
        seen = self._free.get(id(task))
        if seen is None or seen[0] != task.revision:
            zero = task.weight <= 0.0
            seen = (task.revision, zero if zero.any() else None)
            self._free[id(task)] = seen
        return seen[1]

    def __call__(self, kernel: Kernel, q: FloatArray, t: float) -> dict[str, Any]:
        """The errors at (t, q).

        Parameters
        ----------
        kernel : Kernel
            The controller's model (its frames' poses; with Pinocchio one forward kinematics for every task).
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
        if not self.plan:
            return out
        fast = kernel if isinstance(kernel, PinocchioKernel) else None
        if fast is not None:
            pm, pd = fast.pin_model, fast.pin_data
            pin.forwardKinematics(pm, pd, q)
        for task, position, orientation, key_p, key_o in self.plan:
            if not task.target.is_set:
                continue
            p_ref, r_ref = self._target(task, t)
            if fast is not None:
                fid = self._frame_ids.get(task.frame)
                if fid is None:
                    fid = self._frame_ids[task.frame] = fast.frame_id(task.frame)
                placement = pin.updateFramePlacement(pm, pd, fid) if fid else pin.SE3.Identity()
                p, rot = placement.translation, placement.rotation
            else:
                pose = kernel.frame_pose(q, task.frame)
                p, rot = pose[:3, 3], pose[:3, :3]
            free = self._free_rows(task)
            if position:
                e = p_ref - p
                if free is not None:
                    e[free[:3]] = np.nan
                out[key_p] = e
            if orientation:
                e = rotation_error(r_ref, rot)
                if free is not None:
                    e[free[3:] if position else free] = np.nan
                out[key_o] = e
        return out

    def _target(self, task: FrameTask, t: float) -> tuple[FloatArray, FloatArray]:
        """(p_ref, R_ref) of a task's target at t (a constant target's split once)."""
        value = task.target.at(t)[0]
        seen = self._targets.get(id(task))
        if seen is not None and seen[0] is value:
            return seen[1], seen[2]
        if value.shape == (4, 4):
            split = value[:3, 3].copy(), value[:3, :3].copy()
        else:  # a position (3,) or a rotation (3, 3): the other part is not read
            split = value, value
        self._targets[id(task)] = (value, *split)
        return split
