"""Scale of a level's task rows: targets or gains that make the QP meaningless are refused before solving.

A level's cost is ½‖W^{1/2}(J x − b)‖² + ½ε‖x‖², with b the desired task accelerations (ẍ* − J̇q̇ of a motion
task: K_p e + K_d ė + ẍ_ref − J̇q̇) or forces. Its Hessian does not depend on b, but its gradient −JᵀW b does, and
the solver's tolerances are absolute: once ‖W^{1/2} b‖ reaches 1e9 (a billion m/s² — a target kilometres off
with the usual gains, or gains of 1e9), the rounding of the cost (1e-16 of b²) is above the regularisation's
curvature ε, tolerances of 1e-6 are below double precision, and b² overflows at 1e154. Such a QP has an answer
only in name. The check costs one number per step: ‖W^{1/2} b‖² is an entry of the Gram matrix the cost is
built from.
"""

from __future__ import annotations

from typing import Any, NoReturn

import numpy as np

from armctl._checks import FloatArray
from armctl.controllers.osc.levels import LevelRows
from armctl.controllers.osc.state import ModelState
from armctl.controllers.osc.tasks.base import MotionTask, Task
from armctl.errors import InvalidParameterError
from armctl.references import Reference

#: the largest weighted norm of a level's desired task accelerations (or forces), ‖W^{1/2} b‖, accepted
MAX_TASK_RHS = 1e9


def check_level_scale(lev: LevelRows, state: ModelState, t: float, ref: Reference) -> None:
    """Refuse (InvalidParameterError) a level whose ‖W^{1/2} b‖ exceeds :data:`MAX_TASK_RHS` or is not finite."""
    col = lev.Tn[:, lev.nx]
    with np.errstate(over="ignore"):
        size = float(col.dot(col))
    if not size <= MAX_TASK_RHS**2:
        refuse_scale(lev.tasks, [lev.slices[tk.name] for tk in lev.tasks], lev.jr, lev.nx, state, t, ref)


def refuse_scale(
    tasks: tuple[Task, ...], rows: list[slice], jr: FloatArray, nx: int, state: ModelState, t: float, ref: Reference
) -> NoReturn:
    """Raise InvalidParameterError naming the task whose rows are out of scale (the largest ‖W^{1/2} b‖), with
    its error and gains."""
    worst, size = tasks[0], -1.0
    with np.errstate(all="ignore"):
        for tk, r in zip(tasks, rows, strict=True):
            b = jr[r, nx] * tk.sqrt_weight
            s = float(np.sqrt(b.dot(b))) if np.isfinite(b).all() else np.inf
            if s > size:
                worst, size = tk, s
    detail = ""
    if isinstance(worst, MotionTask):
        with np.errstate(all="ignore"):
            err: Any = np.linalg.norm(worst.error(state, t, ref))
            kp = float(np.abs(worst.kp).max())
        detail = f" Its error is {err:.3g} (m or rad) and its kp reaches {kp:.3g}."
    raise InvalidParameterError(
        f"task {worst.name!r} asks for {size:.3g} (weighted norm of its desired task acceleration or force), above "
        f"{MAX_TASK_RHS:g}: at that scale the QP is meaningless in double precision.{detail} Check the task's "
        "target, gains and weight.",
        value=size,
    )
