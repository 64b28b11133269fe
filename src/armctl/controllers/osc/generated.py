"""`GeneratedQddData`: the data of the q̈-only QP of one priority level (:mod:`~armctl.controllers.osc.reduced`)
from one call of generated C code (``OperationalSpaceQP(..., compile=...)``).

At (q, q̇), the tasks' targets and the friction torque τ_f(q̇), one call of code generated with CasADi from the
model (its numbers built in) evaluates what the NumPy path builds from Pinocchio's terms and the tasks' rows:

* M(q) (composite rigid bodies) and h' = C q̇ + g + τ_f (Newton–Euler at q̈ = 0), from
  :mod:`armctl.dynamics.recursive`; per frame its position, rotation, J and J̇ q̇, from
  :mod:`armctl.dynamics.symbolic_frames`;
* each task's rows J_i and b_i = ẍ*_i − J̇_i q̇ (its PD law on its error; the rotation error by
  :func:`~armctl.controllers.osc.tasks.rotation.rotation_error_sx`);
* the QP on q̈ with W_i the tasks' weights and ε the regularisation:
  H = Σ J_iᵀ W_i J_i + ε I + ε Mᵀ M,   g = −Σ J_iᵀ W_i b_i + ε Mᵀ h',   c = Σ ‖W_i^½ b_i‖² + ε ‖h'‖²,
  and its unconstrained minimum q̈₀ = −H⁻¹ g (a Cholesky factorisation written out) with τ₀ = M q̈₀ + h';
* with limits whose bounds are constant (their l, u an input), the verdict on that minimum: 1 if every limit's
  row holds at it (l ≤ τ₀ ≤ u, l ≤ q̈₀ ≤ u: then it is the QP's optimum, no row active) and the level is in
  scale (c ≤ MAX_TASK_RHS²), else 0 (NaN included) — the check of the q̈-only step, in the code; where the
  minimum breaks a row, a second function (:func:`guess_function`) takes primal-dual active-set steps from the
  rows it breaks and checks their result (:func:`guessed_active_set`);
* the verdict on the frame tasks' targets (:mod:`~armctl.controllers.osc.target_code`).

The gains, weights and ε are an input of the code, refreshed when a task's ``revision`` changes: they may be
changed between steps without generating code again. The tasks it takes are :class:`FramePoseTask`,
:class:`FramePositionTask`, :class:`FrameOrientationTask` and :class:`PostureTask` themselves (a subclass may
have kinematics of its own: :func:`supported` is False for it and the controller keeps the NumPy path). The
library is compiled once and cached on disk (:mod:`armctl.codegen.library`), keyed by the model, the tasks'
kinds and frames and whether the model has friction.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from typing import Any, cast

import casadi as cs
import numpy as np

from armctl._checks import FloatArray
from armctl.codegen import library as codegen
from armctl.controllers.osc.generated_data import GeneratedData
from armctl.controllers.osc.optimality import DUAL_TOL
from armctl.controllers.osc.scale import MAX_TASK_RHS
from armctl.controllers.osc.target_code import target_verdict
from armctl.controllers.osc.tasks.base import MotionTask, Task
from armctl.controllers.osc.tasks.frame_orientation import FrameOrientationTask
from armctl.controllers.osc.tasks.frame_pose import FramePoseTask
from armctl.controllers.osc.tasks.frame_position import FramePositionTask
from armctl.controllers.osc.tasks.frame_task import FrameTask
from armctl.controllers.osc.tasks.posture import PostureTask
from armctl.controllers.osc.tasks.rotation import rotation_error_sx
from armctl.dynamics.base import Dynamics
from armctl.dynamics.recursive import (
    cholesky_factor,
    cholesky_solve,
    cholesky_substitute,
    inverse_dynamics,
    joint_transforms,
    mass_matrix,
)
from armctl.dynamics.symbolic_frames import frame_kinematics
from armctl.model.robot import RobotModel
from armctl.references import Reference

#: bumped when the generated code changes, so that stale cached libraries are not loaded
_CODE_VERSION = 8
_NAME = "osc_qdd_qp"
_GUESS = "osc_qdd_active_set"
#: the frame tasks the code takes: their kind and the shape of their target value
_FRAME_TASKS: dict[type, tuple[str, tuple[int, ...]]] = {
    FramePoseTask: ("pose", (4, 4)),
    FramePositionTask: ("position", (3,)),
    FrameOrientationTask: ("orientation", (3, 3)),
}


def supported(tasks: Sequence[Task]) -> bool:
    """Whether the generated code takes these tasks (see the module): built-in motion tasks, not subclasses."""
    return bool(tasks) and all(type(tk) in _FRAME_TASKS or type(tk) is PostureTask for tk in tasks)


def gram(a: cs.SX) -> cs.SX:
    """aᵀ a, each entry of the symmetric result computed once."""
    n = a.shape[1]
    cols = [a[:, j] for j in range(n)]
    out = cs.SX(n, n)
    for i in range(n):
        for j in range(i, n):
            out[i, j] = out[j, i] = cs.dot(cols[i], cols[j])
    return out


def task_rows(
    model: RobotModel, q: cs.SX, qd: cs.SX, tasks: Sequence[Task], tf: list[tuple[cs.SX, cs.SX]]
) -> tuple[list[cs.SX], list[cs.SX], list[cs.SX], list[cs.SX], list[cs.SX]]:
    """The motion tasks' rows at (q, q̇): (inputs, params, J_i, b_i, W_i^½) per task, with ``inputs`` its target
    (a frame task: value row by row, velocity, acceleration; a posture task: q_ref, q̇_ref, q̈_ref) and ``params``
    its K_p, K_d (row by row) and W^½; b_i = ẍ*_i − J̇_i q̇ (its PD law on its error)."""
    n = model.n
    inputs, params = [], []
    frames: dict[str | None, tuple[cs.SX, cs.SX, cs.SX, cs.SX]] = {}
    jacs, rhs, weights = [], [], []
    for k, tk in enumerate(tasks):
        d = tk.dim
        kp, kd, w = cs.SX.sym(f"kp{k}", d * d), cs.SX.sym(f"kd{k}", d * d), cs.SX.sym(f"w{k}", d)
        params += [kp, kd, w]
        gain_p, gain_d = cs.reshape(kp, d, d).T, cs.reshape(kd, d, d).T  # row by row in
        if type(tk) is PostureTask:
            q_ref, qd_ref, qdd_ref = (cs.SX.sym(f"{s}{k}", n) for s in ("q_ref", "qd_ref", "qdd_ref"))
            inputs += [q_ref, qd_ref, qdd_ref]
            jacs.append(cs.SX.eye(n))
            rhs.append(qdd_ref + gain_d @ (qd_ref - qd) + gain_p @ (q_ref - q))
        else:
            kind, shape = _FRAME_TASKS[type(tk)]
            frame = cast(FrameTask, tk).frame  # the built-in tasks here: posture or a frame task
            if frame not in frames:
                frames[frame] = frame_kinematics(model, q, qd, frame, tf)
            p, rot, jac, drift = frames[frame]
            value = cs.SX.sym(f"target{k}", int(np.prod(shape)))
            vel, acc = cs.SX.sym(f"vel{k}", d), cs.SX.sym(f"acc{k}", d)
            inputs += [value, vel, acc]
            rows = {"pose": slice(0, 6), "position": slice(0, 3), "orientation": slice(3, 6)}[kind]
            if kind == "pose":
                pose = cs.reshape(value, 4, 4).T
                err = cs.vertcat(pose[:3, 3] - p, rotation_error_sx(pose[:3, :3], rot))
            elif kind == "position":
                err = value - p
            else:
                err = rotation_error_sx(cs.reshape(value, 3, 3).T, rot)
            j = jac[rows, :]
            jacs.append(j)
            rhs.append(acc + gain_d @ (vel - j @ qd) + gain_p @ err - drift[rows])
        weights.append(w)
    return inputs, params, jacs, rhs, weights


def targets_verdict(tasks: Sequence[Task], task_inputs: Sequence[cs.SX], targets: cs.SX | None = None) -> cs.SX:
    """1 if the target of every frame task of ``tasks`` passes
    :func:`~armctl.controllers.osc.target_code.target_verdict` (``task_inputs``: the three inputs per task of
    :func:`task_rows`), and ``targets`` (a verdict so far, 1 if None) is 1; else 0."""
    targets = cs.SX(1) if targets is None else targets
    for k, tk in enumerate(tasks):
        if type(tk) is not PostureTask:
            value, vel, acc = task_inputs[3 * k : 3 * k + 3]
            targets = cs.logic_and(targets, target_verdict(_FRAME_TASKS[type(tk)][0], value, vel, acc))
    return targets


def qp_function(
    model: RobotModel, tasks: Sequence[Task], friction: bool, limits: Sequence[str] | None = None
) -> cs.Function:
    """The CasADi function of the module: ``f(inputs, params) -> (q̈₀, τ₀, H, g, c, M, h', [J | b])`` with
    ``inputs`` = [q; q̇; per frame task its target (value row by row, velocity, acceleration); τ_f if
    ``friction``; per posture task q_ref, q̇_ref, q̈_ref] and ``params`` = [per task K_p, K_d (row by row), W^½; ε];
    [J | b] the unweighted task rows, stacked in the tasks' order. With ``limits`` (each limit's variable,
    ``"tau"`` or ``"qdd"``; their bounds constant) also the verdict on (q̈₀, τ₀), ``params`` then ending with
    [l; u] (n rows per limit, in their order). Its last output is the verdict on the frame tasks' targets
    (:func:`~armctl.controllers.osc.target_code.target_verdict`: 1 if each is finite and its rotation one)."""
    n = model.n
    q, qd = cs.SX.sym("q", n), cs.SX.sym("qd", n)
    tf = joint_transforms(model, q)
    task_inputs, params, jacs, rhs, weights = task_rows(model, q, qd, tasks, tf)
    # the frame tasks' targets first, the posture tasks' references last (written only when they change)
    postures = [type(tk) is PostureTask for tk in tasks]
    inputs = [q, qd, *[x for k, x in enumerate(task_inputs) if not postures[k // 3]]]
    tau_f = cs.SX.sym("tau_f", n) if friction else cs.SX.zeros(n)
    if friction:
        inputs.append(tau_f)
    inputs += [x for k, x in enumerate(task_inputs) if postures[k // 3]]
    eps = cs.SX.sym("eps")
    params.append(eps)
    mass = mass_matrix(model, q, tf)
    hf = inverse_dynamics(model, q, qd, cs.SX.zeros(n), transforms=tf) + tau_f
    jall, ball, wall = cs.vertcat(*jacs), cs.vertcat(*rhs), cs.vertcat(*weights)
    weighted = jall * cs.repmat(wall, 1, n)  # W^½ J
    t = wall * ball  # W^½ b
    hess = gram(weighted) + eps * (cs.SX.eye(n) + gram(mass))
    grad = -(weighted.T @ t) + eps * (mass @ hf)  # M symmetric: Mᵀh' = M h'
    c = cs.dot(t, t) + eps * cs.dot(hf, hf)
    qdd0 = -cholesky_solve(hess, grad)
    tau0 = mass @ qdd0 + hf
    outputs = [qdd0, tau0, hess, grad, c, mass, hf, cs.horzcat(jall, ball)]
    targets = targets_verdict(tasks, task_inputs)  # the step's Python checks no more
    if limits is not None:
        values = cs.vertcat(*[tau0 if var == "tau" else qdd0 for var in limits])
        lo, up = cs.SX.sym("lower", n * len(limits)), cs.SX.sym("upper", n * len(limits))
        params += [lo, up]
        ok = cs.le(c, MAX_TASK_RHS**2)
        for i in range(values.shape[0]):
            ok = cs.logic_and(ok, cs.logic_and(cs.le(lo[i], values[i]), cs.le(values[i], up[i])))
        outputs.append(ok)
    outputs.append(targets)
    return cs.Function(_NAME, [cs.vertcat(*inputs), cs.vertcat(*params)], [cs.densify(o) for o in outputs])


def guessed_active_set(
    hess: cs.SX,
    grad: cs.SX,
    low: list[list[cs.SX]],
    qdd0: cs.SX,
    mass: cs.SX,
    hf: cs.SX,
    limits: Sequence[str],
    lo: cs.SX,
    up: cs.SX,
    in_scale: cs.SX,
) -> list[cs.SX]:
    """(verdict, q̈, τ, z, active): the QP on q̈ solved by primal-dual active-set steps from the rows that its
    unconstrained minimum q̈₀ breaks, and its KKT check.

    The rows are those of the q̈-only QP (:meth:`~armctl.controllers.osc.reduced.QddQP.arrays`): C = M for a
    torque limit, its bounds l − h', u − h'; C = I for a q̈ limit. Each of
    :data:`~armctl.controllers.osc.generated_optimum.ACTIVE_SET_ITERATIONS` steps (Hintermüller, Ito & Kunisch,
    SIAM J. Optim. 13, 2002) takes the rows of its active set D as equalities at their bound d, and solves (Schur
    complement, with H's Cholesky factor)

        (D C H⁻¹ Cᵀ D + I − D) z = D (C q̈₀ − d),   q̈ = q̈₀ − H⁻¹ Cᵀ z,

    z = 0 off D; the first D holds the rows with C q̈₀ above u or below l, the next keeps the rows whose
    multiplier has its sign and adds the rows the point breaks (beyond PRIMAL_TOL). The verdict is
    :func:`~armctl.controllers.osc.kkt_code.kkt_verdict` of the last step's (q̈, z) on that QP (the conditions
    and tolerances of :func:`~armctl.controllers.osc.optimality.kkt_ok`) with the level in scale: 1 only for the
    QP's optimum, whatever the steps did (dependent rows give NaN, which fails it too); ``active`` is the last
    step's D (+1 at an upper bound, −1 at a lower one)."""
    from armctl.controllers.osc.generated_optimum import ACTIVE_SET_ITERATIONS, next_active_set
    from armctl.controllers.osc.kkt_code import kkt_verdict  # its SX check

    n = mass.shape[0]
    blocks, shifts = [], []
    for var in limits:
        blocks.append(mass if var == "tau" else cs.SX.eye(n))
        shifts.append(hf if var == "tau" else cs.SX.zeros(n))
    C, shift = cs.vertcat(*blocks), cs.vertcat(*shifts)
    ly, uy = lo - shift, up - shift
    mi = C.shape[0]
    s0 = C @ qdd0
    upper = [cs.gt(s0[i], uy[i]) for i in range(mi)]
    lower = [cs.lt(s0[i], ly[i]) for i in range(mi)]
    w = cholesky_substitute(low, C.T)  # H⁻¹ Cᵀ
    k = C @ w
    dual_tol = DUAL_TOL * (1.0 + cs.mmax(cs.fabs(grad)))
    qdd, z = qdd0, cs.SX.zeros(mi)
    for step in range(ACTIVE_SET_ITERATIONS):
        on = [cs.logic_or(upper[i], lower[i]) for i in range(mi)]
        schur = cs.SX.zeros(mi, mi)
        rhs = cs.SX.zeros(mi)
        for i in range(mi):
            for j in range(mi):
                schur[i, j] = cs.if_else(cs.logic_and(on[i], on[j]), k[i, j], 1.0 if i == j else 0.0)
            bound = cs.if_else(upper[i], uy[i], ly[i])
            rhs[i] = cs.if_else(on[i], s0[i] - bound, 0.0)  # a branch: an infinite bound off D never enters
        z = cholesky_solve(schur, rhs)
        qdd = qdd0 - w @ z
        active = cs.vertcat(*[cs.if_else(upper[i], 1.0, cs.if_else(lower[i], -1.0, 0.0)) for i in range(mi)])
        if step + 1 < ACTIVE_SET_ITERATIONS:
            upper, lower = next_active_set(upper, lower, C @ qdd, z, ly, uy, dual_tol)
    ok = cs.logic_and(in_scale, kkt_verdict(hess, grad, None, None, C, ly, uy, qdd, None, z))
    return [ok, qdd, mass @ qdd + hf, z, active]


def guess_function(n: int, m: int, limits: Sequence[str]) -> cs.Function:
    """The CasADi function ``f(out, params) -> (verdict, q̈, τ, z, active)`` of :func:`guessed_active_set`, its data
    read from the outputs of :func:`qp_function` (``out``: them one after the other up to the rows, as
    :attr:`GeneratedQddData.out` holds them; ``m`` task rows) and ``params`` = [l; u]. Run only where the
    unconstrained minimum breaks a row."""
    sizes = [n, n, n * n, n, 1, n * n, n, (n + 1) * m]
    out = cs.SX.sym("out", sum(sizes))
    lo, up = cs.SX.sym("lower", n * len(limits)), cs.SX.sym("upper", n * len(limits))
    parts, pos = [], 0
    for size in sizes:
        parts.append(out[pos : pos + size])
        pos += size
    qdd0, _, hess, grad, c, mass, hf = parts[:7]
    hess, mass = cs.reshape(hess, n, n), cs.reshape(mass, n, n)  # symmetric: column by column is row by row
    found = guessed_active_set(
        hess, grad, cholesky_factor(hess), qdd0, mass, hf, limits, lo, up, cs.le(c, MAX_TASK_RHS**2)
    )
    return cs.Function(_GUESS, [out, cs.vertcat(lo, up)], [cs.densify(o) for o in found])


def target_pieces(tasks: Sequence[Task], t: float, ref: Reference, pieces: list[FloatArray]) -> None:
    """Append the motion tasks' targets at t to ``pieces``, in the order of :func:`task_rows`' inputs (a
    trajectory's output checked as the NumPy path checks it; the posture tasks' references)."""
    for tk in tasks:
        if type(tk) is PostureTask:
            r = tk.reference(ref)
            pieces += [r.q, r.qd, r.qdd]
        else:
            value, vel, acc = cast(FrameTask, tk).target.at(t)
            pieces += [value.reshape(-1), vel, acc]


def task_params(tasks: Sequence[Task]) -> list[FloatArray]:
    """The motion tasks' parameters in the order of :func:`task_rows`': K_p, K_d (row by row), W^½."""
    parts = []
    for tk in tasks:
        motion = cast(MotionTask, tk)  # every task here is a motion task
        parts += [np.ravel(motion.kp), np.ravel(motion.kd), motion.sqrt_weight]
    return parts


def task_tag(model: RobotModel, tk: Task) -> str:
    """What of a motion task the generated code depends on (its kind, frame and the frame's placement)."""
    if type(tk) is PostureTask:
        return "posture"
    f = model.frame(cast(FrameTask, tk).frame)
    where = hashlib.sha256(f.placement.tobytes()).hexdigest()[:12]
    return f"{_FRAME_TASKS[type(tk)][0]}:{f.name}:{f.joint}:{where}"


def _tag(model: RobotModel, tasks: Sequence[Task], friction: bool, limits: Sequence[str] | None = None) -> str:
    parts = [f"osc-qdd|{model.fingerprint(inertial=True, tool=False)}|v{_CODE_VERSION}|friction={friction}"]
    parts.append("limits:" + ("-" if limits is None else ",".join(limits)))
    parts += [task_tag(model, tk) for tk in tasks]
    return "|".join(parts)


class GeneratedQddData(GeneratedData):
    """The generated function of the module for ``tasks`` on ``dynamics`` (its model, its friction, its cache
    folder), bound to buffers of its own. After :meth:`run`, the outputs are arrays that the next run
    overwrites: ``qdd0``, ``tau0`` (n,), ``H`` (n×n), ``g`` (n,), ``c`` (1,), ``M`` (n×n), ``hf`` (n,) and
    ``rows`` (m × (n+1)), as in the module, and with ``limits`` and their constant ``bounds`` (l, u, n rows per
    limit) ``accepted`` (1,), the verdict on (q̈₀, τ₀), and ``guess``, the active-set steps from the rows q̈₀ breaks.
    Builds or loads the library (the first time for a model
    and tasks: seconds; then milliseconds). Not thread-safe."""

    def __init__(
        self,
        dynamics: Dynamics,
        tasks: Sequence[Task],
        regularization: float,
        limits: Sequence[str] | None = None,
        bounds: tuple[FloatArray, FloatArray] | None = None,
    ) -> None:
        super().__init__(dynamics)
        model, n = dynamics.model, self.n
        self.tasks = tuple(tasks)
        self.regularization = float(regularization)
        self.limits = tuple(limits) if limits is not None and bounds is not None else None
        self.bounds = bounds if self.limits is not None else None
        tag = _tag(model, self.tasks, self.friction is not None, self.limits)
        kinds = ", ".join(type(tk).__name__ for tk in self.tasks)
        what = f"the operational-space QP's data for {model.name!r} ({kinds})"
        fn = codegen.cached(
            [_NAME],
            tag,
            lambda: [qp_function(model, self.tasks, self.friction is not None, self.limits)],
            self.cache_dir,
            what=what,
        )[_NAME]
        m = sum(tk.dim for tk in self.tasks)
        # the outputs one after the other in one buffer (the active-set iterations read it): views of it
        sizes = [n, n, n * n, n, 1, n * n, n, (n + 1) * m] + ([1] if self.limits is not None else [])
        #: the outputs, one after the other
        self.out = np.zeros(sum(sizes))
        spans, start = [], 0
        for size in sizes:
            spans.append(self.out[start : start + size])
            start += size
        self.qdd0, self.tau0, self.g, self.hf, self.c = spans[0], spans[1], spans[3], spans[6], spans[4]
        self.H, self.M = spans[2].reshape(n, n), spans[5].reshape(n, n)  # symmetric: column by column is row by row
        self.rows = spans[7].reshape(n + 1, m).T  # CasADi writes a matrix column by column: [J | b]ᵀ row by row
        #: with ``bounds``: 1.0 if the unconstrained minimum holds every limit's row and the level is in scale
        self.accepted: FloatArray | None = spans[8] if self.limits is not None else None
        self._bind(fn, spans)
        #: per task, its target's holder (None: a posture task) and the task
        self._frames = tuple(cast(FrameTask, tk).target for tk in self.tasks if type(tk) is not PostureTask)
        lead = 2 * n + sum(int(np.prod(holder.value_shape)) + 2 * holder.rate for holder in self._frames)
        lead += n if self.friction is not None else 0
        #: the inputs written at every step (q, q̇, the frame tasks' targets, τ_f)
        self._lead = self.inp[:lead]
        #: per posture task: the task, its inputs' part of the buffer and the Reference last written there
        self._postures: list[list[Any]] = []
        for k, tk in enumerate(tk for tk in self.tasks if type(tk) is PostureTask):
            self._postures.append([tk, self.inp[lead + 3 * n * k : lead + 3 * n * (k + 1)], None])
        assert lead + 3 * n * len(self._postures) == self.inp.size  # the layout of qp_function's inputs
        #: with ``bounds``: the active-set steps from the rows that q̈₀ breaks (:meth:`run_guess`): its verdict (1.0:
        #: the QP's optimum, checked), q̈, τ, z and the active set (+1, −1, 0 per row, as floats)
        self.guess: tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray] | None = None
        self._run_guess: Any = None
        if self.limits is not None:
            self._bind_guess(model, tag, m, start - 1)
        self._revisions: list[int] | None = None
        self._pieces: list[FloatArray] = []

    def _bind_guess(self, model: RobotModel, tag: str, m: int, used: int) -> None:
        """Build or load :func:`guess_function` and bind it: its inputs the first ``used`` entries of :attr:`out`
        and the bounds, its outputs :attr:`guess`."""
        limits = self.limits
        assert limits is not None and self.bounds is not None  # called with constant bounds only
        n = self.n
        fn = codegen.cached(
            [_GUESS],
            tag + "|active-set",
            lambda: [guess_function(n, m, limits)],
            self.cache_dir,
            what=f"the q̈-only QP's solve on the rows its minimum breaks for {model.name!r}",
        )[_GUESS]
        mi = n * len(limits)
        self.par_guess = np.concatenate(self.bounds)
        self.guess = (np.zeros(1), np.zeros(n), np.zeros(n), np.zeros(mi), np.zeros(mi))
        self._bind_active_set(fn, used, self.par_guess, self.guess)

    def run_guess(self) -> bool:
        """Solve by active-set steps from the rows that the last :meth:`run`'s unconstrained minimum breaks (with
        ``bounds`` only, :func:`guessed_active_set`); True if the point passed its check (then in :attr:`guess`)."""
        guess = self.guess
        assert guess is not None  # bound with bounds, the only case the step calls this in
        self._run_guess()
        return bool(guess[0][0] == 1.0)

    def __reduce__(self) -> tuple[Any, ...]:
        # rebuilt (the library loads from the cache): the buffers are this process's
        return (GeneratedQddData, (self.dynamics, self.tasks, self.regularization, self.limits, self.bounds))

    def _params(self) -> None:
        """The gains, weights and ε into the parameter buffer (in place: the buffer reads it)."""
        parts = task_params(self.tasks)
        parts.append(np.array([self.regularization]))
        if self.bounds is not None:
            parts += list(self.bounds)
        np.concatenate(parts, out=self.par)

    def run(self, q: FloatArray, qd: FloatArray, t: float, ref: Reference) -> None:
        """Evaluate the outputs at (q, q̇) with the tasks' targets at t and the posture tasks' references. A
        trajectory's new output is checked in the code (see :mod:`~armctl.controllers.osc.target_code`; one
        the code does not pass gets the NumPy path's check, which raises its named error).

        Raises
        ------
        InvalidParameterError, NonFiniteError, ShapeError
            A trajectory's output is not a valid target (as the NumPy path says)."""
        tasks = self.tasks
        revisions = [tk.revision for tk in tasks]
        if revisions != self._revisions:
            self._params()
            self._revisions = revisions
        pieces = [q, qd]
        unchecked = None
        for holder in self._frames:
            out, checked = holder.shaped(t)
            pieces += (out[0].ravel(), out[1], out[2])  # the value row by row
            if not checked:
                unchecked = [(holder, out)] if unchecked is None else [*unchecked, (holder, out)]
        if self.friction is not None:
            pieces.append(self.friction.torque(qd))
        np.concatenate(pieces, out=self._lead)
        for posture in self._postures:
            r = posture[0].reference(ref)
            if r is not posture[2]:  # a Reference is immutable (read-only arrays): written when another one comes
                np.concatenate((r.q, r.qd, r.qdd), out=posture[1])
                posture[2] = r if type(r) is Reference else None  # a subclass's arrays: read at every step
        self._run()
        if unchecked is not None:
            valid = self.targets_ok[0] == 1.0
            for holder, out in unchecked:
                holder.confirm(t, out, valid)
