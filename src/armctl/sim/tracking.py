"""How well a run tracked what its controller was asked: the errors a :class:`~armctl.sim.result.SimResult` headlines
and the test behind ``SimResult.tracked``.

A run whose controller logs its frame tasks' targets (the operational-space controllers do, see
:mod:`armctl.controllers.osc.task_errors`) is judged on the tasks' errors, ``position_error[NAME]`` [m] and
``orientation_error[NAME]`` [rad], computed from the recorded joint positions by the plant's forward kinematics; any
other run on its joint error e = q_ref − q against the reference it was given. For each error the size at sample k
is the norm of its rows, ‖e_k‖ (rows logged as NaN, a task's free rows, left out; a sample whose rows are all free
left out), and over the run

    RMS = √(mean_k ‖e_k‖²),      max = max_k ‖e_k‖

(for the joint error, the RMS over joints and samples and the largest entry). The run tracked if it
finished (neither diverged nor stopped by an exception) and every headline error's RMS is within
:data:`TRACKING_TOLERANCE` of its kind.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from armctl._checks import FloatArray
from armctl.controllers.osc.task_errors import TARGET_KEY
from armctl.controllers.osc.tasks.rotation import rotation_error
from armctl.dynamics.base import Dynamics
from armctl.errors import UnknownNameError

if TYPE_CHECKING:
    from armctl.model.robot import RobotModel

#: RMS errors within which a run counts as tracked: task positions [m], task orientations [rad], joints
#: [rad or m]
TRACKING_TOLERANCE: dict[str, float] = {"position": 5e-3, "orientation": 2e-2, "joint": 2e-2}

#: the log keys' prefixes of the task errors and their kinds
TASK_ERROR_KINDS: dict[str, str] = {"position_error": "position", "orientation_error": "orientation"}

_UNITS = {"position": "m", "orientation": "rad", "joint": "rad or m"}


@dataclass(frozen=True)
class ErrorSummary:
    """One headline error of a run.

    Attributes
    ----------
    name : str
        The task's name, or ``"joints"``.
    kind : str
        ``"position"``, ``"orientation"`` or ``"joint"``.
    rms, max : float
        Its RMS and largest size over the run (see the module) [m or rad].
    where : str
        For the joint error, the joint of the largest entry; else "".
    """

    name: str
    kind: str
    rms: float
    max: float
    where: str = ""

    @property
    def unit(self) -> str:
        """The error's unit."""
        return _UNITS[self.kind]

    @property
    def within(self) -> bool:
        """Its RMS is within :data:`TRACKING_TOLERANCE`."""
        return bool(self.rms <= TRACKING_TOLERANCE[self.kind])

    def text(self) -> str:
        """One line of the run's summary.

        Returns
        -------
        str
            The error's name, kind, RMS, max and unit.
        """
        if self.kind == "joint":
            return (
                f"tracking error: RMS {self.rms:.3g}, max {self.max:.3g} ({self.where}) [rad or m]"
                if self.name == "joints"
                else f"joint error against the joint reference: RMS {self.rms:.3g}, max {self.max:.3g} "
                f"({self.where}) [rad or m]"
            )
        return f"{self.name} {self.kind} error: RMS {self.rms:.3g}, max {self.max:.3g} [{self.unit}]"


def task_errors(
    logs: dict[str, FloatArray], plant: RobotModel | None = None, q: FloatArray | None = None
) -> dict[str, FloatArray]:
    """The frame tasks' errors of a run, by key (``position_error[NAME]``, ``orientation_error[NAME]``): those the
    logs hold (a result read from a file), and those computed from the logged targets and weights (see
    :mod:`armctl.controllers.osc.task_errors`) at the recorded joint positions, by the plant's forward
    kinematics.

    Parameters
    ----------
    logs : dict of str to ndarray
        ``SimResult.logs``.
    plant : RobotModel, optional
        The plant (None: no errors are computed, only those the logs hold).
    q : ndarray, shape (N, n), optional
        The recorded joint positions [rad or m].

    Returns
    -------
    dict of str to ndarray, shape (N, 3)
        e = target − actual in world axes [m or rad], NaN on free rows and on samples without a target.
    """
    out = {}
    for key, value in logs.items():
        prefix = key.split("[", 1)[0]
        if prefix in TASK_ERROR_KINDS and key.endswith("]") and value.ndim == 2 and value.shape[1] == 3:
            out[key] = value
    if plant is None or q is None:
        return out
    targets = [(m.groups(), key) for key in logs if (m := TARGET_KEY.match(key))]
    kernel = Dynamics(plant).kernel if targets else None
    for (kind, name, frame), key in targets:
        if f"position_error[{name}]" in out or f"orientation_error[{name}]" in out:
            continue
        try:
            plant.frame(frame or None)
        except UnknownNameError:  # the controller's model has a frame the plant does not: nothing to compare
            continue
        out.update(_errors_of(kernel, logs, key, kind, name, frame or None, q))
    return out


def _rows(logs: dict[str, FloatArray], key: str) -> FloatArray:
    """The samples a log entry was recorded at."""
    return np.asarray(logs.get(f"{key}:sample", np.arange(len(logs[key]))), dtype=int)


def _errors_of(
    kernel: Any, logs: dict[str, FloatArray], key: str, kind: str, name: str, frame: str | None, q: FloatArray
) -> dict[str, FloatArray]:
    samples = len(q)
    pos = np.full((samples, 3), np.nan) if kind != "orientation" else None
    rot = np.full((samples, 3), np.nan) if kind != "position" else None
    values = logs[key]
    for r, k in enumerate(_rows(logs, key)):
        if k >= samples:
            break
        pose = kernel.frame_pose(q[k], frame)
        v = values[r]
        if pos is not None:
            pos[k] = (v[:3, 3] if kind == "pose" else v) - pose[:3, 3]
        if rot is not None:
            rot[k] = rotation_error(v[:3, :3], pose[:3, :3])
    weight_key = f"task_weight[{name}]"
    if weight_key in logs:
        weights, rows = logs[weight_key], _rows(logs, weight_key)
        keep = rows < samples
        free = weights[keep] <= 0.0
        if pos is not None:
            pos[rows[keep]] = np.where(free[:, :3], np.nan, pos[rows[keep]])
        if rot is not None:
            rot[rows[keep]] = np.where(free[:, -3:], np.nan, rot[rows[keep]])
    out = {}
    if pos is not None:
        out[f"position_error[{name}]"] = pos
    if rot is not None:
        out[f"orientation_error[{name}]"] = rot
    return out


def task_summaries(errors: dict[str, FloatArray]) -> list[ErrorSummary]:
    """An :class:`ErrorSummary` of every task error of a run (see :func:`task_errors`) with at least one sample.

    Parameters
    ----------
    errors : dict of str to ndarray
        :func:`task_errors` of the run.

    Returns
    -------
    list of ErrorSummary
    """
    out = []
    for key, e in errors.items():
        prefix, name = key.split("[", 1)
        rows = ~np.isnan(e)
        used = rows.any(axis=1)
        if not used.any():
            continue
        size = np.sqrt(np.where(rows, e, 0.0)[used] ** 2 @ np.ones(3))
        out.append(
            ErrorSummary(name[:-1], TASK_ERROR_KINDS[prefix], float(np.sqrt(np.mean(size**2))), float(size.max()))
        )
    return out


def joint_summary(error: FloatArray, joint_names: tuple[str, ...], name: str = "joints") -> ErrorSummary | None:
    """The :class:`ErrorSummary` of a joint error (N, n) (samples with a NaN left out), or None without one.

    Parameters
    ----------
    error : ndarray, shape (N, n)
        q_ref − q [rad or m].
    joint_names : tuple of str
        The joints' names.
    name : str, optional
        ``"joints"`` when it is the run's headline error, another name when task errors come first.

    Returns
    -------
    ErrorSummary or None
    """
    e = np.abs(error)
    e = e[~np.isnan(e).any(axis=1)]
    if not e.size:
        return None
    where = joint_names[int(e.max(axis=0).argmax())]
    return ErrorSummary(name, "joint", float(np.sqrt((e**2).mean())), float(e.max()), where)
