"""`FrameTask`: what the tasks on a frame share — the frame, its target, the check that the frame exists, the
constructor and its documentation."""

from __future__ import annotations

from abc import abstractmethod
from typing import Any, ClassVar

from numpy.typing import ArrayLike

from armctl._checks import FloatArray
from armctl.controllers.osc.docstrings import fill
from armctl.controllers.osc.state import FrameKinematics, ModelState
from armctl.controllers.osc.tasks.base import MotionTask
from armctl.controllers.osc.tasks.target import TargetHolder, Trajectory
from armctl.references import Reference

#: the line of a frame task's class docstring that :meth:`FrameTask.__init_subclass__` replaces with the
#: constructor's Parameters and Raises sections (:data:`PARAMETERS`, in the class's terms; see
#: :func:`~armctl.controllers.osc.docstrings.fill`)
PARAMETERS_MARK = "(the Parameters and Raises sections of a frame task)"

#: the Parameters and Raises sections of a frame task's constructor, for a task of ``dim`` rows (``rows``: what
#: they are, after the gains' shapes) named ``kind[FRAME]`` by default
PARAMETERS = """Parameters
----------
frame : str, optional
    A name of the model's ``frame_names`` (its joints' frames and the frames it declares); None (the default):
    the tool frame (the last joint's frame on a model without one).
kp : array_like, optional
    K_p [1/s²]: a scalar, a ({dim},) diagonal or a {dim}×{dim} symmetric positive definite matrix{rows}.
kd : array_like, optional
    K_d [1/s], likewise; None (the default): critical damping, 2 K_p^½.
weight : array_like, optional
    The rows' weights w_i ≥ 0 (scalar or ({dim},)).
priority : int, optional
    Its level, 0 the most important.
name : str, optional
    The task's name; None (the default): ``"{kind}[FRAME]"`` (``"{kind}[tool]"`` for the tool frame).

Raises
------
InvalidParameterError, ShapeError, NonFiniteError
    A gain that is not symmetric positive definite, of the wrong size or not finite; a negative weight."""


class FrameTask(MotionTask):
    """A motion task of ``task_dim`` rows on ``frame`` (default: the tool frame), named ``kind[frame]`` unless
    ``name`` is given; its target value has shape ``target_shape``. Its Jacobian, drift and velocity are the
    ``frame_rows`` of the frame's ([linear; angular]); its error e is :meth:`_frame_error`'s, the one method a
    subclass implements. A subclass sets the class attributes and writes :data:`PARAMETERS_MARK` as a line of its
    docstring where the constructor's Parameters and Raises sections go."""

    #: the number of rows (3 or 6)
    task_dim: ClassVar[int]
    #: what the task controls: it names the task (``kind[frame]``) and the kind of its target
    kind: ClassVar[str]
    #: the shape of the target's value: (3,) a point, (3, 3) a rotation, (4, 4) a pose
    target_shape: ClassVar[tuple[int, ...]]
    #: the task's rows among the frame's 6 rows [linear; angular] (of its Jacobian, drift and velocity)
    frame_rows: ClassVar[slice]
    #: what the rows are, said after the gains' shapes in the documentation (e.g. " (rows [linear; angular])")
    _rows_note: ClassVar[str] = ""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if cls.__doc__ is not None and PARAMETERS_MARK in cls.__doc__:
            sections = PARAMETERS.format(dim=cls.task_dim, kind=cls.kind, rows=cls._rows_note)
            cls.__doc__ = fill(cls.__doc__, PARAMETERS_MARK, sections)

    def __init__(
        self,
        frame: str | None = None,
        kp: ArrayLike = 400.0,
        kd: ArrayLike | None = None,
        weight: ArrayLike = 1.0,
        priority: int = 0,
        name: str | None = None,
    ) -> None:
        name = name or f"{self.kind}[{frame or 'tool'}]"
        super().__init__(self.task_dim, name, kp, kd, weight, priority)
        self.frame = frame
        self.target = TargetHolder(name, self.target_shape, self.task_dim)

    def kinematics(
        self, state: ModelState, t: float, ref: Reference
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        value, velocity, acceleration = self.target.at(t)
        fk = state.frame(self.frame)
        rows = self.frame_rows
        e = self._frame_error(value, fk)
        return fk.jacobian[rows], fk.drift[rows], e, velocity - fk.velocity[rows], acceleration

    @abstractmethod
    def _frame_error(self, value: FloatArray, fk: FrameKinematics) -> FloatArray:
        """The error e (task_dim,) [m or rad] of the frame ``fk`` from the target's ``value``."""

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
