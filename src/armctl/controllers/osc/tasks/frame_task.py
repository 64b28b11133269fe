"""`FrameTask`: what the tasks on a frame share — the frame, its target and the check that the frame exists."""

from __future__ import annotations

from typing import Any

from numpy.typing import ArrayLike

from armctl.controllers.osc.tasks.base import MotionTask
from armctl.controllers.osc.tasks.target import TargetHolder, Trajectory


class FrameTask(MotionTask):
    """A motion task of dimension ``dim`` on ``frame`` (default: the tool frame), named ``kind[frame]`` unless
    ``name`` is given; its target value has shape ``target_shape``."""

    def __init__(
        self,
        dim: int,
        kind: str,
        target_shape: tuple[int, ...],
        frame: str | None,
        kp: ArrayLike,
        kd: ArrayLike | None,
        weight: ArrayLike,
        priority: int,
        name: str | None,
    ) -> None:
        name = name or f"{kind}[{frame or 'tool'}]"
        super().__init__(dim, name, kp, kd, weight, priority)
        self.frame = frame
        self.target = TargetHolder(name, target_shape, dim)

    def set_trajectory(self, fn: Trajectory) -> None:
        """Follow a trajectory: the target at time t is ``fn(t)``, checked at every step as ``set_target``'s
        arguments are. Replaces a constant target; ``set_target`` replaces the trajectory.

        Parameters
        ----------
        fn : callable
            ``fn(t) -> (value, velocity, acceleration)`` with t [s], in the terms of the task's ``set_target``;
            velocity and acceleration may be None (zero).

        Raises
        ------
        InvalidParameterError
            ``fn`` is not callable. (A value it returns that is not a valid target raises at the step that
            reads it.)
        """
        self.target.follow(fn)

    def check(self, evaluator: Any, n: int, contacts: dict[str, int]) -> None:
        evaluator.check_frame(self.frame)
