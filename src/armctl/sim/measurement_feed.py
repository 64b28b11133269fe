"""`MeasurementFeed`: the signals a controller declares in ``reads``, measured at every control instant of a run.

At sample k the feed hands the controller (see :mod:`armctl.controllers.measurement`)

- ``wrench``: the first :class:`~armctl.sim.ForceSensor`'s reading at the state of sample k, through its chain;
- ``tau_applied``: τ_{k−1}, the torque held over the last period after saturation (zeros at k = 0), exact;
- ``tau_measured``: τ_{k−1} through its chain (a joint torque sensor's noise and filter).

Each chain (:class:`~armctl.sim.signal_chain.SignalChain`) adds the noise of :class:`~armctl.sim.options.Sensing`,
its filter, and the run's measurement delay, as q and q̇ have it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from armctl._checks import FloatArray
from armctl.controllers.measurement import Measurement, check_reads
from armctl.errors import InvalidParameterError
from armctl.sim.contact import ForceSensor
from armctl.sim.signal_chain import SignalChain


def declared_reads(controller: Any) -> frozenset[str]:
    """The signals ``controller`` declares in ``reads`` (empty for a controller that reads q and q̇ only)."""
    reads = getattr(controller, "reads", None)
    if not reads:
        return frozenset()
    return check_reads(reads, type(controller).__name__)


class MeasurementFeed:
    """The measurement of each sample of one run (made by ``simulate`` for a controller that reads signals).

    Parameters
    ----------
    reads : frozenset of str
        The signals the controller declares.
    n : int
        The number of joints.
    control_dt : float
        Δt_c [s].
    sensors : tuple of ForceSensor
        The run's sensors; the first one feeds ``wrench``.
    noise_wrench, noise_tau : float or array_like
        Standard deviations of the wrench's [N, N·m] (6,) and the measured torques' [N·m] (n,) noise.
    cutoff : float, optional
        The first-order filter's cut-off [Hz] of the wrench and the measured torques (None: none).
    delay : int
        Control periods of measurement delay.
    seed : int
        The run's seed (the chains draw from streams of their own, so q's and q̇'s noise does not change).
    effort_limit : (n,) ndarray
        The plant's effort limits [N·m] (the saturation of the applied torque).
    saturate : bool
        Whether the run clips τ at them.

    Raises
    ------
    InvalidParameterError
        The controller reads ``wrench`` and the run has no ForceSensor.
    """

    def __init__(
        self,
        reads: frozenset[str],
        n: int,
        control_dt: float,
        sensors: tuple[ForceSensor, ...],
        noise_wrench: Any,
        noise_tau: Any,
        cutoff: float | None,
        delay: int,
        seed: int,
        effort_limit: FloatArray,
        saturate: bool,
    ) -> None:
        self.reads = reads
        self.sensor = sensors[0] if sensors else None
        if "wrench" in reads and self.sensor is None:
            raise InvalidParameterError(
                "the controller reads 'wrench', and the run has no force sensor: give one, "
                "simulate(..., sensing=Sensing(sensors=ForceSensor(frame=...)))",
                value=sensors,
            )
        self.wrench_chain = (
            SignalChain(6, control_dt, noise_wrench, delay, cutoff, seed=[seed, 1]) if "wrench" in reads else None
        )
        self.tau_chain = (
            SignalChain(n, control_dt, noise_tau, delay, cutoff, seed=[seed, 2]) if "tau_measured" in reads else None
        )
        self._applied = np.zeros(n)
        self._limit = effort_limit
        self._clip = saturate and bool(np.isfinite(effort_limit).any())

    def at(self, sensor_reading: FloatArray | None) -> Measurement:
        """The measurement of the current sample, from the first sensor's reading at its state."""
        chain = self.wrench_chain
        wrench = chain(sensor_reading) if chain is not None and sensor_reading is not None else None
        applied = self._applied if "tau_applied" in self.reads else None
        measured = self.tau_chain(self._applied) if self.tau_chain is not None else None
        sensor = self.sensor
        return Measurement(
            wrench=wrench,
            tau_applied=applied,
            tau_measured=measured,
            frame=sensor.frame if sensor is not None else None,
            world_axes=sensor.world_axes if sensor is not None else False,
        )

    def applied(self, tau: FloatArray) -> None:
        """Note τ_k, as the plant will hold it (saturated), for the next sample's ``tau_applied``."""
        self._applied = np.clip(tau, -self._limit, self._limit) if self._clip else np.array(tau, dtype=float)
