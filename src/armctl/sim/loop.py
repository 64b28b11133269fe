"""`ClosedLoop`: one run of :func:`armctl.sim.simulate`, sample by sample.

At each control instant t_k = k·Δt_c the loop

1. *checks* the plant's state (finite, within the stop rules),
2. *measures* it (noise, delay) and records it,
3. *controls*: calls the controller on the measurement and the reference, checks τ_k and saturates it,
4. *integrates* the plant over [t_k, t_k + Δt_c) under the held τ_k with m sub-steps of the integrator.

The loop stops early when the state or the torque is not finite, the state leaves the stop rules, or the plant's
mass matrix stops being positive definite (``divergence``); an exception from the controller, the reference or
the plant stops it too (``failure``), and :func:`~armctl.sim.simulate` hands the samples before it on with the
exception.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any, cast

import numpy as np

from armctl._checks import FLOAT, FloatArray, real_array
from armctl.errors import InvalidParameterError, ShapeError
from armctl.references import Reference
from armctl.sim import period as codes
from armctl.sim import setup
from armctl.sim.integrators import Step
from armctl.sim.measurement_feed import MeasurementFeed
from armctl.sim.period import WholePeriods
from armctl.sim.plant import Plant
from armctl.sim.recorder import Recorder
from armctl.sim.stepper import advance
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
    plant: Plant
    step: Step
    fast: Callable[..., tuple[FloatArray, FloatArray, FloatArray]] | None  # a plant without forces: (q, q̇, τ, h)
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
    """The loop of one run from the state (q, q̇) at t = 0 (see the module).

    On a plant that integrates a whole control period in one call (:mod:`armctl.sim.period`: the generated step's
    :meth:`~armctl.sim.compiled_plant.CompiledPlant.period`), that call does on the rows of the record what
    :meth:`control` does with τ_k after recording it (the finiteness check, the saturation) and what
    :meth:`integrate` does in Python (the stick solve at the period's start and its records, the sub-steps, the
    work), and checks the state it leaves as :meth:`check` does: the state of sample k then lives in row k of the
    record.
    """

    def __init__(self, settings: LoopSettings, q: FloatArray, qd: FloatArray) -> None:
        self.s = s = settings
        self.q, self.qd = q, qd
        self.rows = s.periods + 1  # samples recorded
        self.divergence: Divergence | None = None
        self.failure: BaseException | None = None
        self.failed_at = math.nan  # the time [s] of the sample at which ``failure`` was raised
        self.clipped: list[int] = []  # rows where saturation clipped τ
        self._work_friction = self._work_external = 0.0
        # what every period uses, bound once
        self._rec = rec = s.recorder
        self._plant = pl = s.plant
        self._controller = s.controller
        self._call = s.call
        #: a controller that reads signals and is not a Controller gets them as the call's keyword
        self._plain_call = s.call
        self._by_keyword = s.feed is not None and s.call is s.controller
        self._fixed_reference = s.fixed_reference
        self._reference_fn = s.reference_fn
        self._shape = (s.n,)
        self._log_add = rec.log.add
        self._references, self._taus = rec.references, rec.tau
        self._external = not pl.simple and pl.has_external
        limit = s.effort_limit
        self._clip = s.saturate and bool(np.isfinite(limit).any())
        self._limits = limit.tolist()
        self._lowest_limit = min(self._limits, default=math.inf)  # |τ| below it needs no clipping
        # read-only views of the recorded rows: the controller is given these (it cannot change the record)
        self._views = [a.view() for a in (rec.q, rec.qd, rec.q_measured, rec.qd_measured)]
        for view in self._views:
            view.flags.writeable = False
        self._q_view, self._qd_view, self._qm_view, self._qdm_view = self._views
        #: the (samples, n) noise of q and q̇ measured, or None
        self._noise = (s.noise_q, s.noise_qd) if s.noise_q is not None and s.noise_qd is not None else None
        #: the plant's whole control period in one call (:mod:`armctl.sim.period`), or None (the Python of
        #: control's checks of τ and integrate)
        self._whole: WholePeriods | None = None
        self._period: Callable[[int, float], float] | None = None
        #: why the state the last period left stops the run (0: it does not), as that call checked it; None: checked
        #: here
        self._state_code: float | None = None
        if not pl.simple:  # the friction torque of a sample the run stops at before its stick solve: NaN
            rec.tau_friction.fill(math.nan)
        if hasattr(pl, "bind_record"):
            self._whole = whole = cast(WholePeriods, pl)
            whole.bind_record(
                rec.tau,
                rec.q,
                rec.qd,
                rec.qdd,
                rec.tau_friction,
                rec.stuck,
                rec.work_friction,
                rec.work_external,
                limit,
                self._clip,
                s.substeps,
                s.dt,
                s.implicit,
                s.max_velocity,
                s.max_position,
            )
            self._period = whole.period
            rec.q[0] = q
            rec.qd[0] = qd

    def run(self) -> None:
        """Run every sample; afterwards ``rows``, ``divergence``, ``failure`` and ``clipped`` say what happened."""
        s = self.s
        check, measure, control, integrate = self.check, self.measure, self.control, self.integrate
        last, cdt = s.periods, s.control_dt
        with np.errstate(all="ignore"):
            for k in range(last + 1):
                t = k * cdt
                try:
                    why = check(t)
                    if why is not None:
                        self._stop(k, t, why, *self._state(k))
                        return
                    qm, vm = measure(k)
                    tau = control(k, t, qm, vm)
                    if tau is None:
                        return
                except BaseException as exc:  # the controller's or the reference's: the run so far is kept
                    self._fail(exc, k, t)
                    return
                try:
                    if k == last:  # the last sample: its state and torque, no step after it
                        self._last_sample(k, t, tau)
                        return
                    if integrate(k, t, tau):
                        return
                except (NotPositiveDefinite, np.linalg.LinAlgError) as exc:  # the latter: the Lagrange backend's
                    q, qd = self._state(k)
                    if k == last:
                        self._stop(k + 1, t, f"{exc} at t = {t:g} s", q.copy(), qd.copy())
                    else:
                        why = f"{exc} during the control period from t = {t:g} s"
                        self._stop(k + 1, t + cdt, why, q.copy(), qd.copy())
                    return
                except BaseException as exc:  # the plant's (a disturbance's, say): the run so far is kept
                    self._fail(exc, k, t)
                    return

    def _fail(self, exc: BaseException, k: int, t: float) -> None:
        """Stop at sample k (time t [s]) on ``exc``, keeping sample k: its state is recorded, and what the loop did
        not compute there stays NaN (τ_k if the controller gave none, q̈_k, the friction torque)."""
        self.failure, self.failed_at, self.rows = exc, t, k + 1

    def _stop(self, rows: int, t: float, why: str, q: FloatArray, qd: FloatArray) -> None:
        self.divergence, self.rows = (t, why, np.array(q), np.array(qd)), rows

    def _state(self, k: int) -> tuple[FloatArray, FloatArray]:
        """The state of sample k (the current one)."""
        if self._period is not None:
            return self._rec.q[k], self._rec.qd[k]
        return self.q, self.qd

    # ----------------------------------------------------------------------------------- the four steps
    def check(self, t: float) -> str | None:
        """Why the state at t stops the run (None: it does not)."""
        code = self._state_code
        if code is not None:  # the period that reached this state checked it
            if not code:
                return None
            return self._why(int(code))
        ql, vl = self.q.tolist(), self.qd.tolist()
        if not math.isfinite(sum(ql) + sum(vl)) and not (np.isfinite(self.q).all() and np.isfinite(self.qd).all()):
            return self._why(1)  # (the sum of finite entries can overflow: the entries decide)
        s = self.s
        if max(vl) > s.max_velocity or -min(vl) > s.max_velocity:
            return self._why(2)
        if s.max_position < math.inf and (max(ql) > s.max_position or -min(ql) > s.max_position):
            return self._why(3)
        return None

    def _why(self, code: int) -> str:
        """The reason of :meth:`check`: 1 not finite, 2 a velocity beyond the bound, 3 a position beyond it."""
        if code == 1:
            return "the state is not finite"
        if code == 2:
            return f"a joint velocity is beyond max_velocity = {self.s.max_velocity:g}"
        return f"a joint position is beyond max_position = {self.s.max_position:g}"

    def measure(self, k: int) -> tuple[FloatArray, FloatArray]:
        """Record the state of sample k; the (read-only) measurement the controller is given."""
        rec = self._rec
        if self._period is None:  # (else the period recorded it)
            rec.q[k] = self.q
            rec.qd[k] = self.qd
            if not self._plant.simple:
                rec.work_friction[k] = self._work_friction
                rec.work_external[k] = self._work_external
        if self._external:  # contact forces, wrench and sensors at this state (before the controller reads them)
            rec.record_external(k, self._plant, k * self.s.control_dt, rec.q[k], rec.qd[k])
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

    def control(self, k: int, t: float, qm: FloatArray, vm: FloatArray) -> FloatArray | None:
        """τ_k from the controller, checked and recorded; the applied (saturated) torque, or None if τ_k is not
        finite (the run stops as diverged)."""
        ref = self._fixed_reference
        if ref is None:
            ref = self._reference_fn(t)  # type: ignore[misc]  # set when there is no fixed one
            if not isinstance(ref, Reference) or ref.q.shape != self._shape:
                setup.check_reference(ref, self.s.n, t)  # (raises, naming what is wrong)
        self._references[k] = ref
        feed = self.s.feed
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
        if feed is not None:
            feed.applied(tau)
        if self._period is not None:  # the period checks and saturates τ_k, read from the record (see integrate)
            self._taus[k] = tau
            return tau
        tl = tau.tolist()
        if not math.isfinite(sum(tl)) and not np.isfinite(tau).all():  # (a sum of finite entries can overflow)
            self._stop(k, t, f"the controller returned a non-finite torque {tau}", *self._state(k))
            return None
        self._taus[k] = tau  # the applied torque is τ too, but for the clipped rows (see applied_torques)
        low = self._lowest_limit
        if self._clip and (max(tl) > low or -min(tl) > low) and any(map(operator.gt, map(abs, tl), self._limits)):
            self.clipped.append(k)
            return np.clip(tau, -self.s.effort_limit, self.s.effort_limit)
        return tau

    def _give_measurement(self, feed: MeasurementFeed, k: int) -> None:
        """Hand the controller the signals it reads at sample k (:mod:`armctl.sim.measurement_feed`): as its
        ``measurement`` (a :class:`~armctl.controllers.Controller` whose ``compute`` the loop calls), or through
        the call's ``measurement`` keyword (another callable)."""
        rec = self._rec
        m = feed.at(rec.sensor[k, 0] if feed.sensor is not None else None)
        if self._by_keyword:
            self._call = partial(self._plain_call, measurement=m)
        else:
            self._controller.measurement = m

    def integrate(self, k: int, t: float, tau: FloatArray) -> bool:
        """Integrate the plant over [t, t + Δt_c) under the held τ (sub-steps of the integrator). True: the run
        stopped (a plant's whole period found τ not finite)."""
        period = self._period
        if period is not None:
            code = self._state_code = period(k, t)
            if code > codes.STATE_MASK:
                return self._period_events(k, t, tau, int(code))
            return False
        s, rec, pl = self.s, self._rec, self._plant
        q, qd, h = self.q, self.qd, s.dt
        if not pl.simple:
            pl.begin(t, q, qd, tau)
            rec.record_friction(k, pl, qd)
        if s.implicit:
            rec.qdd[k] = pl.accel(t, q, qd, tau)
        if s.fast is not None:  # no friction, contact or disturbance
            for i in range(s.substeps):
                q, qd, a0 = s.fast(q, qd, tau, h)
                if i == 0:
                    rec.qdd[k] = a0
        else:
            for i in range(s.substeps):
                q, qd, a_sub, dwf, dwe = advance(pl, s.step, t + i * h, q, qd, tau, h, begun=i == 0)
                if i == 0 and a_sub is not None:
                    rec.qdd[k] = a_sub
                self._work_friction += dwf
                self._work_external += dwe
        self.q, self.qd = q, qd
        return False

    def _period_events(self, k: int, t: float, tau: FloatArray, code: int) -> bool:
        """What a whole period's ``code`` says besides the state's (:mod:`armctl.sim.period`), as control and
        integrate do it in Python: a τ_k that is not finite stops the run at sample k (True), a clipped one is
        recorded; a failure is raised."""
        if code & codes.TORQUE_NOT_FINITE:
            self._stop(k, t, f"the controller returned a non-finite torque {tau}", *self._state(k))
            return True
        if code & codes.CLIPPED:
            self.clipped.append(k)
        if code & codes.FAILED:
            self._whole.raise_failure()  # type: ignore[union-attr]  # a code of the whole period's
        self._state_code = code & codes.STATE_MASK
        return False

    def _last_sample(self, k: int, t: float, tau: FloatArray) -> None:
        rec, pl = self._rec, self._plant
        q, qd = self._state(k)
        if self._whole is not None:
            code = self._whole.last_sample(k, t)
            if code:
                self._period_events(k, t, tau, int(code))
            return
        if not pl.simple:
            pl.begin(t, q, qd, tau)
            rec.record_friction(k, pl, qd)
        rec.qdd[k] = pl.accel(t, q, qd, tau)

    def applied_torques(self) -> None:
        """Write the applied (saturated) torques of the run into the recorder."""
        rec, limit = self.s.recorder, self.s.effort_limit
        if not self.clipped:  # the commanded torques (the record is complete: nothing writes into it any more)
            rec.tau_applied = rec.tau
            return
        rec.tau_applied[:] = rec.tau
        if self.clipped:
            rec.tau_applied[self.clipped] = np.clip(rec.tau[self.clipped], -limit, limit)
