"""How well a run tracked what its controller was asked: the errors a :class:`~armctl.sim.result.SimResult`
headlines and the test behind ``SimResult.tracked``.

A run whose controller logs task-space errors (the operational-space controllers log, for each frame task,
``position_error[NAME]`` [m] and ``orientation_error[NAME]`` [rad], see :mod:`armctl.controllers.osc.task_errors`)
is judged on them; any other run on its joint error e = q_ref − q against the reference it was given. For each
error the size at sample k is the norm of its rows, ‖e_k‖ (rows logged as NaN, a task's free rows, left out;
a sample whose rows are all free left out), and over the run

    RMS = √(mean_k ‖e_k‖²),      max = max_k ‖e_k‖

(for the joint error, the RMS over joints and samples and the largest entry, as before). The run tracked if it
finished (neither diverged nor stopped by an exception) and every headline error's RMS is within
:data:`TRACKING_TOLERANCE` of its kind.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armctl._checks import FloatArray

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


def task_errors(logs: dict[str, FloatArray]) -> dict[str, FloatArray]:
    """The task errors among a run's logs, by log key (``position_error[NAME]``, ``orientation_error[NAME]``).

    Parameters
    ----------
    logs : dict of str to ndarray
        ``SimResult.logs``.

    Returns
    -------
    dict of str to ndarray, shape (N, 3)
        The errors in world axes [m or rad], NaN on free rows and on samples without an entry.
    """
    out = {}
    for key, value in logs.items():
        prefix = key.split("[", 1)[0]
        if prefix in TASK_ERROR_KINDS and key.endswith("]") and value.ndim == 2 and value.shape[1] == 3:
            out[key] = value
    return out


def task_summaries(logs: dict[str, FloatArray]) -> list[ErrorSummary]:
    """An :class:`ErrorSummary` of every task error of a run (see :func:`task_errors`) with at least one sample.

    Parameters
    ----------
    logs : dict of str to ndarray
        ``SimResult.logs``.

    Returns
    -------
    list of ErrorSummary
    """
    out = []
    for key, e in task_errors(logs).items():
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
