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
        """Target from ``fn(t) -> (value, velocity, acceleration)`` in the task's terms (see ``set_target``)."""
        self.target.follow(fn)

    def check(self, evaluator: Any, n: int, contacts: dict[str, int]) -> None:
        evaluator.check_frame(self.frame)
