"""`ClosedLoop`: one run of :func:`armctl.sim.simulate`, sample by sample, on any engine.

At each control instant t_k = k·Δt_c the loop

1. *checks* the state of sample k (finite, within the stop rules: the engine evaluates the rule where the state
   is, the loop stops the run),
2. *measures* it: the engine records what the plant shows there (contact forces, sensors), the loop what the
   controller is given — q and q̇ with noise and delay, and the signals it declares it reads
   (:mod:`armctl.sim.measurement_feed`: a force sensor's wrench, τ_{k−1} applied, measured torques),
3. *controls*: calls the controller on the measurement and the reference, checks τ_k (a real array of n entries) and
   records it,
4. *saturates* τ_k — finite, clipped at the effort limits, recorded as the torque applied — by the run's one rule,
   :class:`~armctl.sim.saturation.Saturation`, which it hands its *engine* (:mod:`armctl.sim.engine`) with τ_k: the
   engine holds τ_k by it (the generated engine by its C transcription, in the same call as the period) and
5. advances the plant over [t_k, t_k + Δt_c) under the torque held: the Python step, the generated C period or
   MuJoCo. The engine records the plant's side of the sample (q̈, the friction and external torques, contact
   forces, the work) and the state it reaches, in row k + 1.

The loop stops early when the state or the torque is not finite, the state leaves the stop rules, or the engine
cannot advance the plant (a mass matrix that is not positive definite): ``divergence``. An exception from the
controller, the reference or the plant stops it too (``failure``), and :func:`~armctl.sim.simulate` hands the
samples before it on with the exception.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np

from armctl._checks import FLOAT, FloatArray, real_array
from armctl.errors import InvalidParameterError, ShapeError
from armctl.references import Reference
from armctl.sim import setup
from armctl.sim.engine import (
    STATE_NOT_FINITE,
    STATE_VELOCITY,
    TORQUE_NOT_FINITE,
    Engine,
    EngineRun,
    state_code,
)
from armctl.sim.measurement_feed import MeasurementFeed
from armctl.sim.recorder import Recorder
from armctl.sim.saturation import Saturation
from armctl.sim.stick_slip import NotPositiveDefinite

#: (time [s], why, q, q̇): where and why a run stopped as diverged
Divergence = tuple[float, str, FloatArray, FloatArray]


@dataclass
class LoopSettings:
    """The checked settings of one run (made by :func:`armctl.sim.simulate`)."""

    n: int
    control_dt: float
    dt: float
    periods: int
    substeps: int
    implicit: bool  # the scheme gives no q̈ at the step start (recorded with an extra evaluation)
    controller: Any
    call: Callable[..., Any]  # how the controller is called: controller(t, q, q̇, ref) or its compute
    fixed_reference: Reference | None
    reference_fn: Callable[[float], Reference] | None
    recorder: Recorder
    noise_q: FloatArray | None  # (samples, n) noise added to the measurements, or None
    noise_qd: FloatArray | None
    delay: int
    effort_limit: FloatArray
    saturate: bool
    max_velocity: float
    max_position: float
    feed: MeasurementFeed | None = None  # the signals the controller reads besides q and q̇, or None


class ClosedLoop:
    """The loop of one run from the state (q, q̇) at t = 0 on ``engine`` (see the module)."""

    def __init__(self, settings: LoopSettings, engine: Engine, q: FloatArray, qd: FloatArray) -> None:
        self.s = s = settings
        self.engine = engine
        self.rows = s.periods + 1  # samples recorded
        self.divergence: Divergence | None = None
        self.failure: BaseException | None = None
        self.failed_at = math.nan  # the time [s] of the sample at which ``failure`` was raised
        # what every period uses, bound once
        self._rec = rec = s.recorder
        self._controller = s.controller
        self._call = s.call
        #: a controller that reads signals and is not a Controller gets them as the call's keyword
        self._plain_call = s.call
        self._by_keyword = s.feed is not None and s.call is s.controller
        self._fixed_reference = s.fixed_reference
        self._reference_fn = s.reference_fn
        self._shape = (s.n,)
        self._log_add = rec.log.add
        self._references, self._taus, self._applied = rec.references, rec.tau, rec.tau_applied
        self._q, self._qd = rec.q, rec.qd
        #: the rule τ_k is held by (every engine applies it: see the module)
        self.saturation = Saturation(rec.tau_applied, s.effort_limit, s.saturate)
        # read-only views of the recorded rows: the controller is given these (it cannot change the record)
        self._views = [a.view() for a in (rec.q, rec.qd, rec.q_measured, rec.qd_measured)]
        for view in self._views:
            view.flags.writeable = False
        self._q_view, self._qd_view, self._qm_view, self._qdm_view = self._views
        #: the (samples, n) noise of q and q̇ measured, or None
        self._noise = (s.noise_q, s.noise_qd) if s.noise_q is not None and s.noise_qd is not None else None
        rec.q[0] = q
        rec.qd[0] = qd
        sensors_read = s.feed is not None and s.feed.wrench_chain is not None
        engine.bind(
            EngineRun(rec, self.saturation, s.substeps, s.dt, s.implicit, s.max_velocity, s.max_position, sensors_read)
        )
        #: why the state of the current sample stops the run (:func:`~armctl.sim.engine.state_code`; the engine
        #: gives it for the state a period reaches)
        self._code = state_code(q, qd, s.max_velocity, s.max_position)
        self._observe = engine.observe if engine.observes else None
        self._feed = s.feed

    def run(self) -> None:
        """Run every sample; afterwards ``rows``, ``divergence`` and ``failure`` say what happened."""
        s, engine, feed = self.s, self.engine, self._feed
        measure, control, advance = self.measure, self.control, engine.advance_period
        # the measurement is the record's row itself: read here (measure's first case, without its call)
        plain = not self._rec.measured and self._observe is None
        q_view, qd_view = self._q_view, self._qd_view
        applied = self._applied
        last, cdt = s.periods, s.control_dt
        code = self._code
        with np.errstate(all="ignore"):
            for k in range(last + 1):
                t = k * cdt
                try:
                    if code:  # check: the state of sample k stops the run
                        self._stop(k, t, self.reason(code), k)
                        return
                    if plain:
                        qm, vm = q_view[k], qd_view[k]
                    else:
                        qm, vm = measure(k, t)
                    tau = control(k, t, qm, vm)
                except BaseException as exc:  # the controller's or the reference's: the run so far is kept
                    self._fail(exc, k, t)
                    return
                try:
                    # saturate (the engine holds τ_k by self.saturation) and advance; the last sample: its torque
                    # held and its state recorded, no step after it
                    code = advance(k, t, tau) if k < last else engine.last_sample(k, t, tau)
                except (NotPositiveDefinite, np.linalg.LinAlgError) as exc:  # the latter: the Lagrange backend's
                    if k == last:
                        self._stop(k + 1, t, f"{exc} at t = {t:g} s", k)
                    else:
                        self._stop(k + 1, t + cdt, f"{exc} during the control period from t = {t:g} s", k)
                    return
                except BaseException as exc:  # the plant's (a disturbance's, say): the run so far is kept
                    self._fail(exc, k, t)
                    return
                if code == TORQUE_NOT_FINITE:
                    self._stop(k, t, f"the controller returned a non-finite torque {tau}", k)
                    return
                if feed is not None:
                    feed.applied(applied[k])

    def _fail(self, exc: BaseException, k: int, t: float) -> None:
        """Stop at sample k (time t [s]) on ``exc``, keeping sample k: its state is recorded, and what the loop did
        not compute there stays NaN (τ_k if the controller gave none, q̈_k, the friction torque)."""
        self.failure, self.failed_at, self.rows = exc, t, k + 1

    def _stop(self, rows: int, t: float, why: str, k: int) -> None:
        """Stop as diverged at t [s] keeping ``rows`` samples; the state reported is that of sample k."""
        self.divergence, self.rows = (t, why, self._q[k].copy(), self._qd[k].copy()), rows

    # ------------------------------------------------------------------------------------ the steps
    def reason(self, code: int) -> str:
        """Why a state stops the run, from its code by the stop rules (:func:`armctl.sim.engine.state_code`, which
        the engine evaluates where the state is)."""
        if code == STATE_NOT_FINITE:
            return "the state is not finite"
        if code == STATE_VELOCITY:
            return f"a joint velocity is beyond max_velocity = {self.s.max_velocity:g}"
        return f"a joint position is beyond max_position = {self.s.max_position:g}"

    def measure(self, k: int, t: float) -> tuple[FloatArray, FloatArray]:
        """The (read-only) measurement of sample k (time t [s]) the controller is given, recorded; what the plant
        shows there recorded by the engine (before the controller reads a sensor)."""
        observe = self._observe
        if observe is not None:
            observe(k, t)
        rec = self._rec
        if not rec.measured:
            return self._q_view[k], self._qd_view[k]
        s = self.s
        noise = self._noise
        if noise is not None:
            rec.q_measured[k] = rec.q[k] + noise[0][k]
            rec.qd_measured[k] = rec.qd[k] + noise[1][k]
        else:
            rec.q_measured[k] = rec.q[k]
            rec.qd_measured[k] = rec.qd[k]
        j = k - s.delay if k >= s.delay else 0
        return self._qm_view[j], self._qdm_view[j]

    def control(self, k: int, t: float, qm: FloatArray, vm: FloatArray) -> FloatArray:
        """τ_k from the controller, checked (a real array of n entries) and recorded; whether it is finite is the
        saturation's check, where the engine holds it."""
        ref = self._fixed_reference
        if ref is None:
            ref = self._reference_fn(t)  # type: ignore[misc]  # set when there is no fixed one
            if not isinstance(ref, Reference) or ref.q.shape != self._shape:
                setup.check_reference(ref, self.s.n, t)  # (raises, naming what is wrong)
        self._references[k] = ref
        feed = self._feed
        if feed is not None:
            self._give_measurement(feed, k)
        try:
            tau = self._call(t, qm, vm, ref)
        except ValueError as exc:
            if "read-only" not in str(exc):
                raise
            raise InvalidParameterError(
                f"the controller wrote into a read-only array at t = {t:g} s ({exc}); the q and q̇ it is given are "
                "read-only views of the run's record: work on a copy (q = q.copy()) or on new arrays (e = q - ref.q)",
                value=t,
            ) from exc
        if type(tau) is not np.ndarray or tau.dtype != FLOAT:  # complex or text: named errors
            tau = real_array(tau, f"the controller's torque at t = {t:g} s")
        log = getattr(self._controller, "last_log", None)  # (read every step: a controller may set it later)
        if log:
            self._log_add(k, log)
        if tau.shape != self._shape:
            raise ShapeError(
                f"the controller returned a torque of shape {tau.shape} at t = {t}; expected {self._shape}", value=tau
            )
        self._taus[k] = tau
        return tau

    def _give_measurement(self, feed: MeasurementFeed, k: int) -> None:
        """Hand the controller the signals it reads at sample k (:mod:`armctl.sim.measurement_feed`): as its
        ``measurement`` (a :class:`~armctl.controllers.Controller` whose ``compute`` the loop calls), or through
        the call's ``measurement`` keyword (another callable)."""
        m = feed.at(self._rec.sensor[k, 0] if feed.sensor is not None else None)
        if self._by_keyword:
            self._call = partial(self._plain_call, measurement=m)
        else:
            self._controller.measurement = m
