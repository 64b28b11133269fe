"""`Measurement`: what a controller reads besides q and q̇ — a force/torque sensor's wrench, the joint torques
applied over the last control period, measured joint torques.

A controller that needs one of these signals declares it in its class attribute ``reads`` (a frozenset of the
names below); a controller that declares nothing is called as before, ``controller(t, q, qd, ref)``, and never
sees a measurement. The signals:

======================  ===============  =========================================================================
name                    shape, unit      what it is
======================  ===============  =========================================================================
``"wrench"``            (6,), [N; N·m]   a :class:`~armctl.sim.ForceSensor`'s reading h = [f; m]: what the arm
                                         exerts on the environment, in the sensor's axes or world axes
``"tau_applied"``       (n,), [N·m]      τ_{k−1}: the torque held over the last control period, after saturation
                                         (zeros at the first sample)
``"tau_measured"``      (n,), [N·m]      the joint torques a torque sensor reads (τ_{k−1} with noise)
======================  ===============  =========================================================================

:func:`armctl.simulate` passes each declared signal through the same measurement chain as q and q̇ (noise,
delay, an optional first-order filter; :class:`armctl.sim.Sensing`) and calls
``controller(t, q, qd, ref, measurement=m)``. In your own loop you do the same with what your robot reads::

    m = Measurement(wrench=ft_sensor.read(), tau_applied=tau)
    tau = controller(t, q, qd, ref, measurement=m)

``Controller.__call__`` keeps the last one in ``controller.measurement``, where ``compute`` reads it
(``self.measured("wrench")``), so ``compute(t, q, qd, ref)`` keeps its signature.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from armctl._checks import FLOAT, FloatArray, real_array, vector
from armctl.errors import InvalidParameterError, ShapeError

#: the names of the signals a controller can declare in ``reads``
SIGNALS: frozenset[str] = frozenset({"wrench", "tau_applied", "tau_measured"})


@dataclass(frozen=True)
class Measurement:
    """The signals a controller reads at one control instant besides q and q̇ (each None when not measured).

    Parameters
    ----------
    wrench : (6,) array_like, optional
        A force/torque sensor's reading [f; m] [N, N·m]: the wrench the arm exerts on the environment (the sign of
        :meth:`armctl.Dynamics.inverse_dynamics`' ``wrench``, so that τ = … + Jᵀ h), in the axes the sensor reports.
    tau_applied : (n,) array_like, optional
        The joint torques [N·m or N] held over the last control period, after saturation.
    tau_measured : (n,) array_like, optional
        Joint torques [N·m or N] read by joint torque sensors.
    frame : str, optional
        The frame the wrench is measured at (None: the tool frame).
    world_axes : bool, optional
        Whether the wrench is in world axes (True) or in the frame's own axes (False, the default).

    Raises
    ------
    ShapeError
        A signal has the wrong number of entries.
    NonFiniteError
        A signal is not finite.
    """

    wrench: FloatArray | None = None
    tau_applied: FloatArray | None = None
    tau_measured: FloatArray | None = None
    frame: str | None = None
    world_axes: bool = False

    def __post_init__(self) -> None:
        if self.wrench is not None and not _checked_vector(self.wrench, 6):
            object.__setattr__(self, "wrench", vector(self.wrench, 6, "measurement.wrench"))
        for name in ("tau_applied", "tau_measured"):
            value = getattr(self, name)
            if value is not None and not _checked_vector(value, None):
                arr = real_array(value, f"measurement.{name}")
                if arr.ndim != 1:
                    raise ShapeError(f"measurement.{name} must be a vector (n,), got shape {arr.shape}", value=value)
                object.__setattr__(self, name, vector(arr, arr.shape[0], f"measurement.{name}"))
        if self.world_axes not in (True, False):
            raise InvalidParameterError(
                f"measurement.world_axes must be True or False, got {self.world_axes!r}", value=self.world_axes
            )
        names = frozenset(f.name for f in fields(self) if f.name in SIGNALS and getattr(self, f.name) is not None)
        object.__setattr__(self, "_available", names)  # the signals are fixed (frozen): named once

    def available(self) -> frozenset[str]:
        """The names of the signals this measurement carries.

        Returns
        -------
        frozenset of str
            Names of :data:`SIGNALS` whose value is not None.
        """
        available: frozenset[str] = self._available  # type: ignore[attr-defined]  # set by __post_init__
        return available


def _checked_vector(value: Any, n: int | None) -> bool:
    """Whether ``value`` is already what the checks would make of it: a float64 ndarray (not a subclass) of shape
    (n,) (any length for None), all finite (one sum: NaN and inf propagate into it; a finite sum beyond the range
    of floats answers False, and the full check takes over)."""
    return (
        type(value) is np.ndarray
        and value.dtype == FLOAT
        and value.ndim == 1
        and (n is None or value.shape[0] == n)
        and math.isfinite(sum(value.tolist()))
    )


def check_reads(reads: Any, owner: str) -> frozenset[str]:
    """``reads`` as a frozenset of known signal names, or an InvalidParameterError naming the unknown ones."""
    names = frozenset(reads)
    unknown = names - SIGNALS
    if unknown:
        raise InvalidParameterError(
            f"{owner} reads unknown signal(s) {sorted(unknown)}; the signals are {sorted(SIGNALS)}", value=reads
        )
    return names
