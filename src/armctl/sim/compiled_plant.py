"""`CompiledPlant`: a plant (friction, contact, a disturbance, or none) whose integration step runs as generated C.

The plant's terms are generated with CasADi (:mod:`armctl.sim.generated_plant`) and wrapped in a C driver
(``step_core.c``, ``step_schemes.c``, ``step_events.c``, appended to the generated code) that transcribes the
Python step: the stick solve of :meth:`Plant.begin <armctl.sim.plant.Plant.begin>`, the events of
:func:`armctl.sim.stepper.advance` and the schemes of :mod:`armctl.sim.integrators` and :mod:`armctl.sim.implicit`.
A step is one call into C; the runs agree with the Python step's to rounding, and a stuck joint stays exactly
where it is (q̈_S = 0 exactly, see :func:`~armctl.sim.generated_plant.masked_cholesky_solve`). Within ``simulate``,
a whole control period is one call (:meth:`CompiledPlant.period`, ``step_period.c``: the C transcription of
:meth:`PythonEngine.advance_period <armctl.sim.python_engine.PythonEngine.advance_period>`): the stick solve and what
is recorded of it, the sub-steps with their events and work, read from and written into the run's record by row
(the engine :class:`~armctl.sim.generated_engine.GeneratedEngine`).

One library per arm (the geometry of its chain), plant structure (:class:`~armctl.sim.plant_layout.PlantLayout`)
and family of schemes (explicit: ``"rk4"``, ``"euler"``; implicit: ``"semi-implicit-euler"``, ``"implicit-euler"``),
built on first use and cached on disk (:mod:`armctl.codegen.library`, compiled with :data:`FLAGS`); inertial
parameters, friction levels, contact coefficients, planes and point offsets are inputs of the code, so the variants of
a plant share its library.

The disturbance h_d(t) stays a Python callable: it is evaluated at the start, middle and end of every step and
passed in (see :meth:`Plant.sample_disturbance <armctl.sim.plant.Plant.sample_disturbance>`).
"""

from __future__ import annotations

import hashlib
import os
import platform
from functools import cache
from importlib import resources
from typing import Any

import casadi as cs
import numpy as np

from armctl._checks import FloatArray
from armctl.codegen import library as codegen
from armctl.dynamics.casadi_buffer import buffer_of, view
from armctl.errors import BackendError
from armctl.model.robot import RobotModel
from armctl.sim.generated_plant import kernels
from armctl.sim.period_binding import PeriodBinding
from armctl.sim.plant import Plant
from armctl.sim.plant_layout import PlantLayout
from armctl.sim.stick_slip import NotPositiveDefinite

#: bumped when the generated code changes, so that stale cached libraries are not loaded
CODE_VERSION = 11
#: the scheme codes of the C driver, and the family of kernels each needs
SCHEMES = {"rk4": 0, "euler": 1, "semi-implicit-euler": 2, "implicit-euler": 3}
FAMILY = {"rk4": "explicit", "euler": "explicit", "semi-implicit-euler": "implicit", "implicit-euler": "implicit"}
#: the functions of the C driver (see ``step_events.c`` and ``step_period.c``)
DRIVER = ("advance", "begin", "accel", "period")
_STATUS = {1: "mass matrix not positive definite", 2: "singular Newton matrix"}
#: the period's status for a row outside the record it is bound to (``step_period.c``)
BAD_ROW = 3
#: where a period failed (``step_period.c``'s PERIOD_*), as the messages of begin, accel and step name it
_WHERE = {0: "stick solve", 1: "accelerations", 2: "step"}
#: entries of the period's ``opt`` and ``out`` (see ``step_period.c``)
PERIOD_OPT, PERIOD_OUT = 10, 3

#: the compiler's flags for the plant's library (its step runs in the simulator's loop: a slower build, faster code,
#: and code for this machine's processor — about a third faster than portable code on x86-64 with AVX2 — in a
#: library whose key names the processor, see :func:`host`; where the compiler refuses them, :data:`PORTABLE_FLAGS`)
FLAGS = (*codegen.CFLAGS_FAST, "-march=native")
#: the flags of a build where :data:`FLAGS` fail
PORTABLE_FLAGS = codegen.CFLAGS_FAST

#: the C driver's files, in the order they are appended to the generated code
DRIVER_FILES = ("step_core.c", "step_schemes.c", "step_events.c", "step_period.c")


@cache
def _driver_source() -> str:
    files = resources.files("armctl.sim")
    return "\n".join(files.joinpath(name).read_text() for name in DRIVER_FILES)


def _shapes(layout: PlantLayout) -> list[cs.Function]:
    """Functions with the inputs and outputs of the driver's functions (their generated sparsity patterns are
    what the driver reports to CasADi)."""
    n, ns = layout.n, 4 * layout.n + 8
    pts = max(3 * len(layout.points), 1)  # (the record's contact rows: one entry bound where there are none)

    def dense(name: str, sizes: list[int]) -> list[cs.SX]:
        return [cs.SX.sym(f"{name}{k}", s) for k, s in enumerate(sizes)]

    spec = {
        "advance": ([n, n, n, 18, layout.size, 3, ns], [n, n, n, 5, ns]),
        "begin": ([n, n, n, 18, layout.size, ns], [ns, 4]),
        "accel": ([n, n, n, 18, layout.size, ns], [n, 4]),
        # the record's outputs are declared as one row (bound to the whole arrays, see step_period.c)
        "period": (
            [n, 18, layout.size, PERIOD_OPT, ns, n],
            [n, n, n, n, n, 1, 1, PERIOD_OUT, ns, n, pts, pts, n, 6],
        ),
    }
    out = []
    for name, (ins, outs) in spec.items():
        args = dense("i", ins)
        out.append(cs.Function(f"{name}_shape", args, [cs.densify(cs.SX.zeros(s)) for s in outs]))
    return out


@cache
def host() -> str:
    """The processor the code is built for (a digest of its model and features, from ``/proc/cpuinfo`` where there
    is one): part of the library's key, so that a cache folder shared by machines of different processors does not
    load code built for another one."""
    text = f"{platform.machine()}|{platform.processor()}"
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            lines = [ln for ln in f.read().splitlines() if ln.split(":")[0].strip() in ("model name", "flags")]
        text += "|" + "|".join(dict.fromkeys(lines))
    except OSError:
        pass
    return hashlib.sha256(text.encode()).hexdigest()[:12]


def library_tag(model: RobotModel, layout: PlantLayout, family: str) -> tuple[str, str]:
    """(the library's cache tag, the C source appended to its generated code)."""
    defines = {
        "ARMCTL_N": layout.n,
        "ARMCTL_NPAR": layout.size,
        "ARMCTL_STICKY": int(layout.sticky),
        "ARMCTL_FRICTION": int(layout.has_friction),
        "ARMCTL_EXTERNAL": int(layout.has_external),
        "ARMCTL_POINTS": len(layout.points),
        "ARMCTL_EXPLICIT": int(family == "explicit"),
    }
    source = "".join(f"#define {k} {v}\n" for k, v in defines.items()) + _driver_source()
    digest = hashlib.sha256(source.encode()).hexdigest()[:16]
    tag = f"sim-plant|{model.fingerprint(inertial=False, tool=False)}|{layout.tag()}|{family}|{digest}|v{CODE_VERSION}"
    tag += f"|{host()}"
    return tag, source


def library(
    model: RobotModel,
    layout: PlantLayout,
    family: str,
    cache_dir: str | os.PathLike[str] | None = None,
    what: str = "",
) -> dict[str, cs.Function]:
    """The driver's functions for ``model`` with ``layout`` (built if the library is not cached yet; ``what``: the
    plant in words, for the line logged with the build's time).

    Raises
    ------
    BackendError
        No C compiler, or one that fails (see :func:`armctl.codegen.library.cached`).
    """
    tag, source = library_tag(model, layout, family)

    def make() -> list[cs.Function]:
        return [*kernels(model, layout, family), *_shapes(layout)]

    def build(flags: tuple[str, ...]) -> dict[str, cs.Function]:
        return codegen.cached(list(DRIVER), tag, make, cache_dir, source=source, flags=flags, what=what)

    try:
        return build(FLAGS)
    except BackendError:  # (a compiler without -march=native, say: the portable build, which raises the same)
        return build(PORTABLE_FLAGS)


class CompiledPlant:
    """The plant ``plant`` integrated by generated code with the scheme ``scheme``: what ``simulate`` and the
    recorder use of a :class:`~armctl.sim.plant.Plant` (``begin``, ``accel``, ``friction_torque``, ``stuck``,
    ``stats``, the recording's ``external`` …), and :meth:`step`, one step with its stick–slip events.

    ``sticky`` is None: the events happen inside :meth:`step`, so :func:`armctl.sim.stepper.advance` calls it as
    a plain step. :meth:`begin` (the stick solve at a state) is kept for the next :meth:`step` from that state,
    as the Python plant's is. :meth:`bind_record`, :meth:`period` and :meth:`last_sample` integrate whole control
    periods on a run's record (:mod:`armctl.sim.generated_engine`). Not thread-safe: one object per run.
    """

    def __init__(self, plant: Plant, scheme: str, layout: PlantLayout, functions: dict[str, cs.Function]) -> None:
        self.python = plant
        self.dyn = plant.dyn
        self.n = n = plant.n
        self.friction = plant.friction
        self.environments = plant.environments
        self.kinematics = plant.kinematics
        self.disturbance = plant.disturbance
        self.has_external = plant.has_external
        self.simple = plant.simple
        self.sticky = None
        self.layout = layout
        self.par = layout.parameters(plant)
        self.state = np.zeros(4 * n + 8)
        self.samples = np.zeros(18)  # h_d at the step's start, middle and end
        self._sampled: tuple[float, float] | None = None
        self._w_times: tuple[float | None, float | None] = (None, None)  # times of the samples at start and end
        self.tau = np.zeros(n)
        self.opt = np.array([0.0, 0.0, float(SCHEMES[scheme])])
        self.out = np.zeros(5)  # the step's: W_f, W_e, q̈ valid, status, the next period needs no stick solve
        self._info = np.zeros(4)  # begin's and accel's: any stuck, all stuck, -, status
        self._free = False  # the state the last step left needs no stick solve (see begin)
        self._stuck: FloatArray | None = None  # the stuck joints at the last begin
        self.a0 = np.zeros(n)
        # two (q, q̇) pairs take turns: a step reads pair i and writes pair 1 − i, which the next step finds in place
        self._pairs = [np.zeros((2, n)), np.zeros((2, n))]
        self._rows = [(p[0], p[1]) for p in self._pairs]
        self._turn = 0
        self._tau_set: Any = None
        self._advance, self._begin = [], []
        self._buffers: list[Any] = []  # kept alive with the calls that use them
        for i in (0, 1):
            qi, vi = self._rows[i]
            qo, vo = self._rows[1 - i]
            self._advance.append(
                _bound(
                    functions["advance"],
                    [qi, vi, self.tau, self.samples, self.par, self.opt, self.state],
                    [qo, vo, self.a0, self.out, self.state],
                    self._buffers,
                )
            )
            self._begin.append(
                _bound(
                    functions["begin"],
                    [qi, vi, self.tau, self.samples, self.par, self.state],
                    [self.state, self._info],
                    self._buffers,
                )
            )
        self._acc_in = np.zeros((3, n))
        self._acc_samples = np.zeros(18)
        self._acc = np.zeros(n)
        self._accel = _bound(
            functions["accel"],
            [self._acc_in[0], self._acc_in[1], self._acc_in[2], self._acc_samples, self.par, self.state],
            [self._acc, self._info],
            self._buffers,
        )
        self._period_fn = functions["period"]
        self._run_period: Any = None  # the period bound to a record (see bind_record)
        self._period_opt = np.zeros(PERIOD_OPT)
        self._period_out = np.zeros(PERIOD_OUT)
        self._period_samples = np.zeros(18)
        self._period_h = 0.0
        self._substeps = 0

    # ------------------------------------------------------------------------------------------- state
    @property
    def stuck(self) -> FloatArray | None:
        """The stuck joints (boolean mask) of the current period's start, or None (see :meth:`begin`)."""
        return self._stuck

    @property
    def all_stuck(self) -> bool:
        return bool(self.state[4 * self.n + 2])

    @property
    def direction(self) -> FloatArray:
        return self.state[: self.n].copy()

    @property
    def hold(self) -> FloatArray:
        n = self.n
        return self.state[2 * n : 3 * n].copy()

    @property
    def stats(self) -> dict[str, int]:
        """Events counted so far (as :attr:`Plant.stats <armctl.sim.plant.Plant.stats>`)."""
        s = self.state[4 * self.n + 3 : 4 * self.n + 7].tolist()
        out = {"stick_events": int(s[0]), "breakaway_events": int(s[1]), "implicit_unconverged": int(s[3])}
        if s[2]:
            out["event_overflow"] = int(s[2])
        return out

    # ------------------------------------------------------------------------------------------ steps
    def _load(self, q: FloatArray, v: FloatArray) -> int:
        """Put (q, q̇) into the current pair (unless they are it) and return its index."""
        i = self._turn
        qi, vi = self._rows[i]
        if q is not qi or v is not vi:
            self._pairs[i][...] = np.array((q, v))  # first: q or v may be a view of these very rows
        return i

    def _check(self, status: float, what: str) -> None:
        if status:
            raise NotPositiveDefinite(f"{_STATUS.get(int(status), 'failure')} ({what} of the generated step)")

    def begin(self, t: float, q: FloatArray, v: FloatArray, tau: FloatArray, held: Any = None) -> None:
        """Decide which joints stick at (t, q, q̇) under τ (:meth:`Plant.begin <armctl.sim.plant.Plant.begin>`)
        and the friction torque there (:meth:`friction_torque`); the next :meth:`step` starts from it. (Where the
        last step left this state with no joint that can stick at rest, there is nothing to solve: the step did it.)"""
        i = self._turn
        qi, vi = self._rows[i]
        if self._free and q is qi and v is vi:
            self._stuck = None
            return
        i = self._load(q, v)
        self.tau[...] = tau
        self._tau_set = tau
        if self.disturbance is not None:
            self.samples[:6] = self.python.disturbance_wrench(t)
            self._w_times = (t, None)
            self._sampled = None
        self._begin[i]()
        info = self._info.tolist()
        self._check(info[3], "stick solve")
        n = self.n
        self._stuck = self.state[n : 2 * n] != 0.0 if info[0] else None

    def step(
        self, t: float, q: FloatArray, v: FloatArray, tau: FloatArray, h: float
    ) -> tuple[FloatArray, FloatArray, FloatArray | None, float, float]:
        """One step of length h from (t, q, q̇) under τ, stick–slip events included: (q₁, q̇₁, q̈ at the start or
        None, friction work, external work). q₁ and q̇₁ stay valid until the step after next; q̈ until the next."""
        i = self._load(q, v)
        if tau is not self._tau_set:
            self.tau[...] = tau
        self._tau_set = None
        opt = self.opt
        if h != opt[1]:
            opt[1] = h
        if self.disturbance is not None:
            self._sample(t, h)
        self._advance[i]()
        out = self.out.tolist()
        if out[3]:
            self._free = False
            self._check(out[3], "step")
        self._free = bool(out[4])
        self._turn = j = i ^ 1
        q1, v1 = self._rows[j]
        return q1, v1, self.a0 if out[2] else None, out[0], out[1]

    def fast(
        self, q: FloatArray, v: FloatArray, tau: FloatArray, h: float
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """:meth:`step` of a plant without friction, contact or disturbance (whose step has no work to book and no
        time to know): (q₁, q̇₁, q̈ at the start), the signature of :func:`armctl.sim.integrators.fast_step`'s."""
        i = self._load(q, v)
        self.tau[...] = tau
        opt = self.opt
        if h != opt[1]:
            opt[1] = h
        self._advance[i]()
        if self.out[3]:
            self._check(self.out[3], "step")
        self._turn = j = i ^ 1
        q1, v1 = self._rows[j]
        return q1, v1, self.a0

    def sample_disturbance(self, t: float, h: float) -> None:
        """h_d at the start, middle and end of the step [t, t + h] (:meth:`Plant.sample_disturbance
        <armctl.sim.plant.Plant.sample_disturbance>`), for the next :meth:`step`."""
        self._sample(t, h)

    def end_step(self) -> None:
        """(Nothing to do: the samples are the step's input.)"""

    def _sample(self, t: float, h: float) -> None:
        """h_d at t, t + h/2 and t + h into :attr:`samples` (the one at t kept from :meth:`begin` or from the last
        step's end, when they were taken at t)."""
        if self._sampled == (t, h):
            return
        d = self.python.disturbance_wrench
        w = self.samples
        if self._w_times[0] != t:
            if self._w_times[1] == t:
                w[:6] = w[12:]
            else:
                w[:6] = d(t)
        w[6:12] = d(t + 0.5 * h)
        w[12:] = d(t + h)
        self._w_times = (t, t + h)
        self._sampled = (t, h)

    def accel(self, t: float, q: FloatArray, v: FloatArray, tau: FloatArray) -> FloatArray:
        """q̈ at (t, q, q̇) under τ for the current stick state (a new array)."""
        self._acc_in[0], self._acc_in[1], self._acc_in[2] = q, v, tau
        if self.disturbance is not None:
            self._acc_samples[:6] = self.python.disturbance_wrench(t)
        self._accel()
        self._check(self._info[3], "accelerations")
        return self._acc.copy()

    def friction_torque(self, qd: FloatArray) -> FloatArray:
        """τ_f at the state of the last :meth:`begin` (``qd`` is that state's q̇): the model's torque for the
        sliding joints, the holding torque for the stuck ones (a view, valid until the next step)."""
        n = self.n
        return self.state[3 * n : 4 * n]

    # ---------------------------------------------------------------------------- control periods
    def bind_record(self, binding: PeriodBinding) -> None:
        """Make :meth:`period` and :meth:`last_sample` integrate on the rows of a run's record (``binding``, see
        :class:`~armctl.sim.period_binding.PeriodBinding`)."""
        b = binding
        rows = len(b.q)
        record = (b.tau, b.q, b.qd, b.qdd, b.tau_friction, b.stuck, b.work_friction, b.work_external, b.tau_applied)
        given = (b.contact_force, b.contact_position, b.tau_ext, b.wrench)
        pts = max(3 * len(self.layout.points), 1)  # (scratch rows of the declared sizes, see _shapes)
        contacts: tuple[FloatArray, ...] = (np.zeros(pts), np.zeros(pts), np.zeros(self.n), np.zeros(6))
        if b.record_contacts:
            if any(a is None for a in given) or not self.layout.points or self.disturbance is not None:
                raise ValueError("recording the contacts takes a plant with points, no disturbance, and their rows")
            contacts = tuple(a for a in given if a is not None)
        for a in record + (contacts if b.record_contacts else ()):
            if a.dtype != np.float64 or not a.flags.c_contiguous or len(a) != rows or a.size != rows * a[0].size:
                raise ValueError("the record's arrays must be C-contiguous float64 arrays of the same samples")
        self._substeps, self._period_h = b.substeps, b.dt
        self._period_samples = np.zeros(18 * max(b.substeps, 1))
        self._period_limit = np.array(b.effort_limit, dtype=float)
        opt = self._period_opt
        opt[:] = (
            *(0.0, b.dt, self.opt[2], b.substeps, rows, float(b.accel_at_start)),
            *(b.max_velocity, b.max_position, float(b.saturate), float(b.record_contacts)),
        )
        self._record = (record, contacts)  # kept alive with the binding
        self._run_period = _bound(
            self._period_fn,
            [b.tau, self._period_samples, self.par, opt, self.state, self._period_limit],
            [*record[1:-1], self._period_out, self.state, b.tau_applied, *contacts],
            self._buffers,
        )
        self._free = False

    def record_sample(self, k: int) -> None:
        """Record the contacts at the state of sample k into the bound record's rows (what :meth:`period` records
        at the state it leaves, see :class:`~armctl.sim.period_binding.PeriodBinding`): for the run's first
        sample, before any period.

        Raises
        ------
        IndexError
            A row outside the bound record.
        """
        opt = self._period_opt
        m = opt[3]
        opt[3], opt[0] = -1.0, k
        try:
            self._run_period()
        finally:
            opt[3] = m
        if self._period_out[0]:
            self._raise(k)

    def period(self, k: int, t: float, tau: object = None) -> int:
        """Integrate the control period [t, t + Δt_c) from the state of sample k on the record bound by
        :meth:`bind_record` under the torque in row k of its ``tau``, held (``step_period.c``'s ``armctl_hold``, the
        transcription of :meth:`Saturation.hold <armctl.sim.saturation.Saturation.hold>`) into row k of its
        ``tau_applied``: the stick solve at t and its records at row k (q̈, friction torque, stuck joints), the
        sub-steps with their events, the state and the work at row k + 1. Returns why that state stops the run
        (:func:`armctl.sim.engine.state_code`'s code, 0: it does not), or
        :data:`~armctl.sim.engine.TORQUE_NOT_FINITE` (τ_k is not finite: nothing else written). ``tau``: not read
        (τ_k is the record's row; the argument lets the call stand for :meth:`Engine.advance_period
        <armctl.sim.engine.Engine.advance_period>`).

        Raises
        ------
        NotPositiveDefinite
            The mass matrix (or the Newton matrix of an implicit scheme) failed its factorisation.
        IndexError
            A row outside the bound record (a bug of the caller).
        """
        self._period_opt[0] = k
        if self.disturbance is not None:
            self._disturbance_samples(t, self._substeps)
        self._run_period()
        out = self._period_out.tolist()
        if out[0]:
            self._raise(k)
        return int(out[2])

    def last_sample(self, k: int, t: float) -> int:
        """The run's last sample k (no step after it): the torque held, the stick solve at t, the friction torque,
        the stuck joints and q̈ at row k; returns 0 or :data:`~armctl.sim.engine.TORQUE_NOT_FINITE` (raises as
        :meth:`period`)."""
        opt = self._period_opt
        m = opt[3]
        opt[3] = 0.0
        try:
            opt[0] = k
            if self.disturbance is not None:
                self._disturbance_samples(t, 0)
            self._run_period()
        finally:
            opt[3] = m
        status, _, code = self._period_out.tolist()
        if status:
            self._raise(k)
        return int(code)

    def _raise(self, k: int) -> None:
        """Raise why the last period from sample k failed (see :meth:`period`)."""
        status, where = self._period_out.tolist()[:2]
        if status == BAD_ROW:
            rows = self._period_opt[4]
            raise IndexError(f"sample {k} is outside the record bound to the generated step ({rows:.0f} rows)")
        self._check(status, _WHERE.get(int(where), "step"))

    def _disturbance_samples(self, t: float, substeps: int) -> None:
        """h_d at the start, middle and end of every sub-step of the period from t (at t only: ``substeps`` = 0),
        evaluated at the times the steps would sample it one by one (:meth:`_sample`)."""
        d, w, h = self.python.disturbance_wrench, self._period_samples, self._period_h
        w[:6] = d(t)
        end = t
        for i in range(substeps):
            ti = t + i * h
            at = 18 * i
            if i:
                w[at : at + 6] = w[at - 6 : at] if end == ti else d(ti)
            w[at + 6 : at + 12] = d(ti + 0.5 * h)
            end = ti + h
            w[at + 12 : at + 18] = d(end)

    # ------------------------------------------------------------------------------ recording (Python)
    def external(self, t: float, q: FloatArray, qd: FloatArray) -> FloatArray:
        return self.python.external(t, q, qd)

    def disturbance_wrench(self, t: float) -> FloatArray:
        return self.python.disturbance_wrench(t)

    def kinetic(self, q: FloatArray, qd: FloatArray) -> float:
        return self.python.kinetic(q, qd)


def _bound(fn: cs.Function, inputs: list[FloatArray], outputs: list[FloatArray], keep: list[Any]) -> Any:
    """``fn`` evaluated on fixed arrays (CasADi's zero-copy buffers): returns the call; its buffer is kept in
    ``keep``."""
    buf, run = buffer_of(fn)
    for k, a in enumerate(inputs):
        buf.set_arg(k, view(a))
    for k, a in enumerate(outputs):
        buf.set_res(k, view(a))
    keep.append(buf)
    return run
