"""Where a force-reading controller gets the wrench h = [f; m] the arm exerts on its environment: a force/torque
sensor (the measured ``"wrench"``) or an observer of the external joint torques (fed the applied torques,
``"tau_applied"``).

A sensor's reading is turned into world axes at the controlled frame o_c::

    f_w = R_s f,   m_w = R_s m + (o_s − o_c) × f_w        (R_s, o_s: the sensor frame's rotation and origin)

(R_s = I for a reading already in world axes). An observer is any object with ``update(t, q, qd, tau_applied)``
and ``wrench(q, frame=None)`` — :class:`armctl.controllers.MomentumObserver` is one — whose wrench is already
in world axes at ``frame``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from armctl._checks import FloatArray
from armctl.controllers.base import Controller
from armctl.controllers.measurement import Measurement
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError


def check_source(source: Any, owner: str) -> tuple[Any, frozenset[str]]:
    """``source`` ("sensor" or an observer) and the signals it makes the controller read."""
    if isinstance(source, str) and source == "sensor":
        return "sensor", frozenset({"wrench"})
    if source is not None and callable(getattr(source, "update", None)) and callable(getattr(source, "wrench", None)):
        return source, frozenset({"tau_applied"})
    raise InvalidParameterError(
        f"{owner} needs a force source: force_source='sensor' (a ForceSensor's reading, "
        f"Measurement(wrench=...)) or an observer with update(t, q, qd, tau_applied) and wrench(q, frame) "
        f"(armctl.controllers.MomentumObserver); got {source!r}",
        value=source,
    )


def sensor_wrench(dyn: Dynamics, q: FloatArray, h: FloatArray, m: Measurement, frame: str | None) -> FloatArray:
    """The reading ``h`` of measurement ``m`` in world axes, its moment about the origin of the controlled
    ``frame`` [N; N·m]."""
    if m.world_axes and m.frame == frame:
        return h
    kernel = dyn.kernel
    pose = kernel.frame_pose(q, m.frame)
    rot = pose[:3, :3]
    f, mo = (h[:3], h[3:]) if m.world_axes else (rot @ h[:3], rot @ h[3:])
    if m.frame != frame:
        mo = mo + np.cross(pose[:3, 3] - kernel.frame_pose(q, frame)[:3, 3], f)
    return np.concatenate((f, mo))


class ForceInput:
    """The force source of a controller (see the module): ``reads`` are the signals it needs, :meth:`wrench`
    gives h at the controlled frame.

    Parameters
    ----------
    source : "sensor" or observer
        Where the wrench comes from.
    owner : str
        The controller's name, for the error messages.

    Raises
    ------
    InvalidParameterError
        ``source`` is neither.
    """

    def __init__(self, source: Any, owner: str) -> None:
        self.source, self.reads = check_source(source, owner)

    def wrench(self, ctrl: Controller, t: float, q: FloatArray, qd: FloatArray, frame: str | None) -> FloatArray:
        """h (6,) [N; N·m] in world axes at ``frame`` for ``ctrl``'s measurement."""
        if self.source == "sensor":
            h = ctrl.measured("wrench")
            m = ctrl.measurement
            if m is None:  # pragma: no cover - measured() raised already
                raise InvalidParameterError("no measurement", value=None)
            dyn = ctrl.dynamics
            if dyn is None:  # pragma: no cover - the interaction controllers always have a model
                raise InvalidParameterError("the controller has no model", value=ctrl)
            return sensor_wrench(dyn, q, h, m, frame)
        self.source.update(t, q, qd, ctrl.measured("tau_applied"))
        return np.asarray(self.source.wrench(q, frame), dtype=float)

    def reset(self) -> None:
        """Reset an observer source (if it has ``reset``)."""
        reset = getattr(self.source, "reset", None)
        if self.source != "sensor" and callable(reset):
            reset()
