"""Tasks of the operational-space QP, each defined by its error and Jacobian."""

from armctl.controllers.osc.tasks.base import MotionTask, Task
from armctl.controllers.osc.tasks.contact_force import ContactForceTask
from armctl.controllers.osc.tasks.frame_orientation import FrameOrientationTask
from armctl.controllers.osc.tasks.frame_pose import FramePoseTask
from armctl.controllers.osc.tasks.frame_position import FramePositionTask
from armctl.controllers.osc.tasks.posture import PostureTask

__all__ = [
    "ContactForceTask",
    "FrameOrientationTask",
    "FramePoseTask",
    "FramePositionTask",
    "MotionTask",
    "PostureTask",
    "Task",
]
