"""`GeneratedContactData`: the data of the QPs on y = [q̈; f] with active contacts
(:mod:`~armctl.controllers.osc.contact_qp`) from one call of generated C code (``OperationalSpaceQP(...,
compile=...)``).

At (q, q̇), the tasks' targets and τ_f(q̇), one call of code generated with CasADi from the model evaluates what
:meth:`~armctl.controllers.osc.contact_qp.ContactQP.step` builds from Pinocchio's terms:

* B = [M | −J_1ᵀ … −J_kᵀ] and h' = C q̇ + g + τ_f (``brows`` = [B | −h']), with J_c the linear rows of each
  contact frame's Jacobian;
* the contacts' equality rows [G_q G_f | rhs] (``contact``), as :meth:`~armctl.controllers.osc.Contact.equality_rows`
  gives them: fixed, J_c q̈ = −J̇_c q̇ − k_d v_c; sliding, nᵀJ_c q̈ = −nᵀ(J̇_c q̇ + k_d v_c) and
  (t_i + μ ŝ_i n)ᵀ f = 0 with ŝ = v_t / √(‖v_t‖² + v_ε²);
* the task rows [J | b] on y (``rows``), the motion tasks' as in :mod:`~armctl.controllers.osc.generated` and a
  contact-force task's the identity (or nᵀ) on its contact's force with its target;
* per priority level k, with T_k its weighted task rows and ε_k its regularisation:
  H_k = T_kᵀT_k + ε_k (I + BᵀB), g_k = −T_kᵀt_k + ε_k Bᵀh', c_k = ‖t_k‖² + ε_k‖h'‖²;
* with one level, the optimum on the contact rows A y = b alone (no inequality row active), y* and λ, by the Schur
  complement of H (a Cholesky factorisation written out), and its residuals A y* − b and H y* + g + Aᵀλ: the
  step takes it, without a solver, when they vanish to the optimality check's tolerances and every inequality
  row holds;
* the verdict on the frame tasks' targets (:mod:`~armctl.controllers.osc.target_code`), so that the step's Python
  checks a trajectory's output only where the code does not pass it;
* with one level and constant bounds, where that optimum breaks a row, a few primal-dual active-set iterations
  from the rows it breaks and the KKT check of their result
  (:func:`~armctl.controllers.osc.generated_optimum.active_set_optimum`): the step takes that optimum, without a
  solver, when it passes.

Gains, weights, the contacts' coefficients and ε_k are an input of the code, refreshed when a task's
``revision`` changes. The tasks it takes are those of :func:`~armctl.controllers.osc.generated.supported` and
:class:`~armctl.controllers.osc.ContactForceTask`; the library is compiled once and cached on disk, keyed by the
model, the tasks, the levels, the contacts' frames and modes and whether the model has friction.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from typing import Any, cast

import casadi as cs
import numpy as np

from armctl._checks import FloatArray
from armctl.codegen import library as codegen
from armctl.controllers.osc.contact import Contact
from armctl.controllers.osc.generated import (
    gram,
    supported,
    target_pieces,
    targets_verdict,
    task_params,
    task_rows,
    task_tag,
)
from armctl.controllers.osc.generated_data import GeneratedData
from armctl.controllers.osc.generated_optimum import active_set_optimum, equality_optimum, verdict
from armctl.controllers.osc.scale import MAX_TASK_RHS
from armctl.controllers.osc.tasks.base import Task
from armctl.controllers.osc.tasks.contact_force import ContactForceTask
from armctl.controllers.osc.tasks.frame_task import FrameTask
from armctl.controllers.osc.tasks.posture import PostureTask
from armctl.controllers.osc.tasks.target import TargetHolder
from armctl.dynamics.base import Dynamics
from armctl.dynamics.recursive import inverse_dynamics, joint_transforms, mass_matrix
from armctl.dynamics.symbolic_frames import frame_kinematics
from armctl.model.robot import RobotModel
from armctl.references import Reference

_CODE_VERSION = 7
_NAME = "osc_contact_qp"
_GUESS = "osc_contact_active_set"


def supported_contact(levels: Sequence[Sequence[Task]]) -> bool:
    """Whether the generated code takes these levels' tasks: the motion tasks of
    :func:`~armctl.controllers.osc.generated.supported` and contact-force tasks, not subclasses."""
    motion = [tk for lev in levels for tk in lev if type(tk) is not ContactForceTask]
    return all(type(tk) is ContactForceTask or supported([tk]) for lev in levels for tk in lev) and (
        not motion or supported(motion)
    )


def contact_function(
    model: RobotModel,
    levels: Sequence[Sequence[Task]],
    contacts: Sequence[Contact],
    friction: bool,
    limits: Sequence[str] | None = None,
) -> cs.Function:
    """The CasADi function of the module: ``f(inputs, params) -> (brows, contact, rows, H_0, g_0, c_0, …)`` with
    ``inputs`` = [q; q̇; per task its target; τ_f if ``friction``] and ``params`` = [per contact n, t_1, t_2, μ,
    k_d, v_ε; per motion task K_p, K_d, W^½; per force task W^½; per level ε_k]. With one level also the optimum
    on the contact rows alone and its residuals (:mod:`~armctl.controllers.osc.generated_optimum`), and with
    ``limits`` (the variable of each limit, ``"tau"`` or ``"qdd"``, whose bounds are constant) its verdict and
    τ, ``params`` then ending with [per contact its cone rows (row by row); l; u]. Its last output is the verdict
    on the frame tasks' targets (:func:`~armctl.controllers.osc.target_code.target_verdict`)."""
    n = model.n
    q, qd = cs.SX.sym("q", n), cs.SX.sym("qd", n)
    tf = joint_transforms(model, q)
    cols: dict[str, tuple[int, int]] = {}
    col = n
    for c in contacts:
        cols[c.name] = (col, col + 3)
        col += 3
    ny = col
    inputs, params = [q, qd], []
    mass = mass_matrix(model, q, tf)
    bmat = cs.SX.zeros(n, ny)
    bmat[:, :n] = mass
    crows, crhs = [], []
    for k, c in enumerate(contacts):
        _, _, jac, drift = frame_kinematics(model, q, qd, c.frame, tf)
        jv, acc0 = jac[:3, :], drift[:3]
        vel = jv @ qd
        nrm, t1, t2 = cs.SX.sym(f"normal{k}", 3), cs.SX.sym(f"t1_{k}", 3), cs.SX.sym(f"t2_{k}", 3)
        mu, kd, veps = cs.SX.sym(f"mu{k}"), cs.SX.sym(f"kd{k}"), cs.SX.sym(f"veps{k}")
        params += [nrm, t1, t2, mu, kd, veps]
        a, b = cols[c.name]
        bmat[:, a:b] = -jv.T
        g = cs.SX.zeros(3, ny)
        if c.mode == "fixed":
            g[:, :n] = jv
            rhs = -acc0 - kd * vel
        else:
            g[0, :n] = nrm.T @ jv
            vt = cs.vertcat(cs.dot(t1, vel), cs.dot(t2, vel))
            s = vt / cs.sqrt(cs.dot(vt, vt) + veps * veps)
            g[1, a:b] = (t1 + mu * s[0] * nrm).T
            g[2, a:b] = (t2 + mu * s[1] * nrm).T
            rhs = cs.vertcat(-cs.dot(nrm, acc0) - kd * cs.dot(nrm, vel), 0.0, 0.0)
        crows.append(g)
        crhs.append(rhs)
    tau_f = cs.SX.sym("tau_f", n) if friction else cs.SX.zeros(n)
    hf = inverse_dynamics(model, q, qd, cs.SX.zeros(n), transforms=tf) + tau_f
    rows: list[cs.SX] = []
    rhs_all: list[cs.SX] = []
    outputs_levels: list[tuple[cs.SX, cs.SX, cs.SX]] = []
    targets = cs.SX(1)  # the frame tasks' targets checked (target_code): the step's Python checks no more
    for lev_idx, tasks in enumerate(levels):
        jl: list[cs.SX] = []
        bl: list[cs.SX] = []
        wl: list[cs.SX] = []
        for tk in tasks:
            if type(tk) is ContactForceTask:
                force = tk
                a, b = cols[force.contact.name]
                target, w = cs.SX.sym(f"force{lev_idx}_{len(jl)}", tk.dim), cs.SX.sym(f"fw{lev_idx}_{len(jl)}", tk.dim)
                inputs.append(target)
                params.append(w)
                j = cs.SX.zeros(tk.dim, ny)
                if force.normal_only:
                    j[0, a:b] = cs.DM(force.contact.normal).T
                else:
                    j[:, a:b] = cs.SX.eye(3)
                jl.append(j)
                bl.append(target)
                wl.append(w)
            else:
                ins, ps, jacs, task_b, ws = task_rows(model, q, qd, [tk], tf)
                targets = targets_verdict([tk], ins, targets)
                inputs += ins
                params += ps
                j = cs.SX.zeros(tk.dim, ny)
                j[:, :n] = jacs[0]
                jl.append(j)
                bl.append(task_b[0])
                wl.append(ws[0])
        jall, ball, wall = cs.vertcat(*jl), cs.vertcat(*bl), cs.vertcat(*wl)
        rows.append(jall)
        rhs_all.append(ball)
        eps = cs.SX.sym(f"eps{lev_idx}")
        outputs_levels.append((jall * cs.repmat(wall, 1, ny), wall * ball, eps))
    if friction:
        inputs.append(tau_f)
    outputs = [
        cs.horzcat(bmat, -hf),
        cs.horzcat(cs.vertcat(*crows), cs.vertcat(*crhs)) if contacts else cs.SX.zeros(0, ny + 1),
        cs.horzcat(cs.vertcat(*rows), cs.vertcat(*rhs_all)),
    ]
    bth = bmat.T @ hf
    bgram = gram(bmat)
    for weighted, t, eps in outputs_levels:
        params.append(eps)
        outputs.append(gram(weighted) + eps * (cs.SX.eye(ny) + bgram))
        outputs.append(-(weighted.T @ t) + eps * bth)
        outputs.append(cs.dot(t, t) + eps * cs.dot(hf, hf))
    if len(levels) == 1 and contacts:  # the optimum on the contact rows alone (no inequality row active)
        optimum = equality_optimum(outputs[3], outputs[4], cs.vertcat(*crows), cs.vertcat(*crhs))
        outputs += optimum
        if limits is not None:
            y = optimum[0]
            tau = bmat @ y + hf
            values = [tau if var == "tau" else y[:n] for var in limits]
            for k, c in enumerate(contacts):
                rows_c = c.cone_rows()[0].shape[0]
                cone = cs.SX.sym(f"cone{k}", rows_c * 3)
                params.append(cone)
                a, b = cols[c.name]
                values.append(cs.reshape(cone, 3, rows_c).T @ y[a:b])  # row by row in
            v = cs.vertcat(*values)
            lo, up = cs.SX.sym("lower", v.shape[0]), cs.SX.sym("upper", v.shape[0])
            params += [lo, up]
            outputs += [verdict(optimum, outputs[4], outputs[5], v, lo, up), tau]
    outputs.append(targets)
    return cs.Function(_NAME, [cs.vertcat(*inputs), cs.vertcat(*params)], [cs.densify(o) for o in outputs])


def guess_function(n: int, contacts: Sequence[Contact], limits: Sequence[str], m: int) -> cs.Function:
    """The CasADi function ``f(out, params) -> (verdict, y, λ, z, active, τ)`` of the active-set iterations
    (:func:`~armctl.controllers.osc.generated_optimum.active_set_optimum`) on the QP of one level, its data read
    from the outputs of :func:`contact_function` (``out``: them one after the other, as
    :attr:`GeneratedContactData.out` holds them, up to τ; ``m`` task rows) and ``params`` = [per contact its cone
    rows (row by row); l; u]. Run only where the optimum on the contact rows alone breaks a row."""
    ny, me = n + 3 * len(contacts), 3 * len(contacts)
    cone_counts = [c.cone_rows()[0].shape[0] for c in contacts]
    mi = n * len(limits) + sum(cone_counts)
    sizes = [(ny + 1) * n, (ny + 1) * me, (ny + 1) * m, ny * ny, ny, 1, ny, me, me, ny, 1, n]
    out = cs.SX.sym("out", sum(sizes))
    par = cs.SX.sym("par", 3 * sum(cone_counts) + 2 * mi)
    blocks_out, pos = [], 0
    for size in sizes:
        blocks_out.append(out[pos : pos + size])
        pos += size
    brows = cs.reshape(blocks_out[0], n, ny + 1)  # column by column, as CasADi wrote it
    contact = cs.reshape(blocks_out[1], me, ny + 1)
    hess, grad, c_val, y_star = cs.reshape(blocks_out[3], ny, ny), blocks_out[4], blocks_out[5], blocks_out[6]
    bmat, hf = brows[:, :ny], -brows[:, ny]
    # the inequality rows on y (those of ContactQP.inequalities): B for a torque limit (bounds shifted by h'),
    # [I 0] for a q̈ limit, each contact's cone rows on its force
    rows, shifts = [], []
    for var in limits:
        if var == "tau":
            rows.append(bmat)
            shifts.append(hf)
        else:
            blk = cs.SX.zeros(n, ny)
            blk[:, :n] = cs.SX.eye(n)
            rows.append(blk)
            shifts.append(cs.SX.zeros(n))
    pos = 0
    for k, count in enumerate(cone_counts):
        cone_rows = cs.reshape(par[pos : pos + 3 * count], 3, count).T  # row by row in
        pos += 3 * count
        blk = cs.SX.zeros(count, ny)
        blk[:, n + 3 * k : n + 3 * k + 3] = cone_rows
        rows.append(blk)
        shifts.append(cs.SX.zeros(count))
    lo, up = par[pos : pos + mi], par[pos + mi : pos + 2 * mi]
    shift = cs.vertcat(*shifts)
    in_scale = cs.le(c_val, MAX_TASK_RHS**2)
    ok, y, lam, z, active = active_set_optimum(
        hess, grad, contact[:, :ny], contact[:, ny], cs.vertcat(*rows), lo - shift, up - shift, y_star, in_scale
    )
    return cs.Function(_GUESS, [out, par], [cs.densify(o) for o in (ok, y, lam, z, active, bmat @ y + hf)])


def _tag(
    model: RobotModel,
    levels: Sequence[Sequence[Task]],
    contacts: Sequence[Contact],
    friction: bool,
    limits: Sequence[str] | None,
) -> str:
    parts = [f"osc-contact|{model.fingerprint(inertial=True, tool=False)}|v{_CODE_VERSION}|friction={friction}"]
    parts.append("limits:" + ("-" if limits is None else ",".join(limits)))
    for c in contacts:
        f = model.frame(c.frame)
        where = hashlib.sha256(f.placement.tobytes()).hexdigest()[:12]
        parts.append(f"contact:{c.mode}:{c.cone_rows()[0].shape[0]}:{f.name}:{f.joint}:{where}")
    names = [c.name for c in contacts]
    for k, tasks in enumerate(levels):
        parts.append(f"level{k}")
        for tk in tasks:
            if type(tk) is ContactForceTask:
                force = tk
                nrm = ",".join(f"{v:.17g}" for v in force.contact.normal) if force.normal_only else "all"
                parts.append(f"force:{names.index(force.contact.name)}:{nrm}")
            else:
                parts.append(task_tag(model, tk))
    return "|".join(parts)


class GeneratedContactData(GeneratedData):
    """The generated function of the module for ``levels`` (the tasks per priority level, in order) and
    ``contacts`` (the active ones, in the layout's order) on ``dynamics``, bound to buffers of its own. After
    :meth:`run`, the outputs are arrays that the next run overwrites: ``brows`` (n × (ny+1)), ``contact``
    (3k × (ny+1)), ``rows`` (m × (ny+1)), per level ``H[k]``, ``g[k]``, ``c[k]``, with one level ``equality``, and
    with ``bounds`` (one level, constant bounds l, u of the limits' and cones' rows, the limits' variables
    ``limits``) ``accepted`` (1,) and ``tau`` (n,); with ``bounds`` also :meth:`run_guess`, the active-set
    iterations on those outputs (``guess_out``, ``guessed``); ``targets_ok`` (1,) the code's verdict on the
    frame tasks' targets. Not thread-safe."""

    def __init__(
        self,
        dynamics: Dynamics,
        levels: Sequence[Sequence[Task]],
        contacts: Sequence[Contact],
        regularization: Sequence[float],
        limits: Sequence[str] | None = None,
        bounds: tuple[FloatArray, FloatArray] | None = None,
    ) -> None:
        super().__init__(dynamics)
        model, n = dynamics.model, self.n
        self.levels = tuple(tuple(lev) for lev in levels)
        self.contacts = tuple(contacts)
        self.regularization = tuple(float(e) for e in regularization)
        one = len(self.levels) == 1 and bool(self.contacts)
        self.limits = tuple(limits) if limits is not None and bounds is not None and one else None
        self.bounds = bounds if self.limits is not None else None
        tag = _tag(model, self.levels, self.contacts, self.friction is not None, self.limits)
        what = f"the operational-space QP's contact data for {model.name!r}"
        fn = codegen.cached(
            [_NAME],
            tag,
            lambda: [contact_function(model, self.levels, self.contacts, self.friction is not None, self.limits)],
            self.cache_dir,
            what=what,
        )[_NAME]
        ny = n + 3 * len(self.contacts)
        m = sum(tk.dim for lev in self.levels for tk in lev)
        self.ny, self.m, self.me = ny, m, 3 * len(self.contacts)
        #: every output, one after the other in one buffer (:meth:`outputs` reads a copy of it the same way)
        self.out = np.zeros(self._size())
        (
            self.brows,
            self.contact,
            self.rows,
            self.H,
            self.g,
            self.c,
            self.equality,
            self.accepted,
            self.tau,
        ) = self.outputs(self.out)
        self._bind(fn, [self.out[start:stop] for start, stop in self._spans()])
        #: per task in the inputs' order: its target's holder for a frame task, else the task
        self._sources = tuple(
            cast(FrameTask, tk).target if type(tk) not in (ContactForceTask, PostureTask) else tk
            for lev in self.levels
            for tk in lev
        )
        #: with ``bounds``: where y*, λ and τ of the optimum on the contact rows alone sit in :attr:`out`
        self.taken: tuple[slice, slice, slice] | None = None
        #: with ``bounds``: the active-set iterations (:func:`guess_function`), their outputs one after the other
        #: (verdict, y, λ, z, active set, τ) and where y, λ, z, the active set and τ sit in it
        self.guess_out: FloatArray | None = None
        self.guessed: tuple[slice, ...] = ()
        self._run_guess: Any = None
        if self.limits is not None:
            spans = self._spans()
            first = 3 + 3 * len(self.levels)
            self.taken = (slice(*spans[first]), slice(*spans[first + 1]), slice(*spans[first + 5]))
            self._bind_guess(model, tag)
        self._revisions: list[int] | None = None

    def _bind_guess(self, model: RobotModel, tag: str) -> None:
        """Build or load :func:`guess_function` and bind it: its inputs :attr:`out` and its own parameters (the
        cones' rows and the bounds, set by :meth:`_params`), its outputs :attr:`guess_out`."""
        limits = self.limits
        assert limits is not None and self.bounds is not None  # called with constant bounds only
        n, ny, me, m = self.n, self.ny, self.me, self.m
        fn = codegen.cached(
            [_GUESS],
            tag + "|active-set",
            lambda: [guess_function(n, self.contacts, limits, m)],
            self.cache_dir,
            what=f"the contact QP's active-set iterations for {model.name!r}",
        )[_GUESS]
        mi = self.bounds[0].shape[0]
        self.par_guess = np.zeros(fn.size1_in(1))
        self.guess_out = np.zeros(1 + ny + me + 2 * mi + n)
        start, spans = 0, []
        for size in (1, ny, me, mi, mi, n):
            spans.append(slice(start, start + size))
            start += size
        self._bind_active_set(fn, fn.size1_in(0), self.par_guess, [self.guess_out[s] for s in spans])
        self.guessed = tuple(spans[1:])

    def run_guess(self) -> bool:
        """Run the active-set iterations on the outputs of the last :meth:`run` (with ``bounds`` only); True if
        their optimum passed its check (then in :attr:`guess_out`)."""
        out = self.guess_out
        assert out is not None  # bound with bounds, the only case the step calls this in
        self._run_guess()
        return bool(out[0] == 1.0)

    def _sizes(self) -> list[int]:
        """The sizes of the function's outputs, in its order (see :meth:`outputs`)."""
        n, ny, m, me = self.n, self.ny, self.m, self.me
        sizes = [(ny + 1) * n, (ny + 1) * me, (ny + 1) * m]
        sizes += [ny * ny, ny, 1] * len(self.levels)
        if self.equality_rows:
            sizes += [ny, me, me, ny]
        if self.limits is not None:
            sizes += [1, n]
        return sizes

    @property
    def equality_rows(self) -> bool:
        """Whether the code gives the optimum on the contact rows alone (one level, with contacts)."""
        return len(self.levels) == 1 and bool(self.contacts)

    def _spans(self) -> list[tuple[int, int]]:
        """(start, stop) of each output in :attr:`out`."""
        spans, start = [], 0
        for size in self._sizes():
            spans.append((start, start + size))
            start += size
        return spans

    def _size(self) -> int:
        return sum(self._sizes())

    def outputs(self, flat: FloatArray) -> tuple[Any, ...]:
        """The outputs as arrays viewing ``flat`` (:attr:`out`, or a copy of it): (brows, contact, rows, H, g, c,
        equality, accepted, tau) as in the class docstring (H, g, c lists per level; equality None with more
        levels; accepted and tau empty without ``bounds``)."""
        n, ny, m, me = self.n, self.ny, self.m, self.me
        spans = iter(self._spans())

        def take(*shape: int) -> FloatArray:
            start, stop = next(spans)
            return flat[start:stop].reshape(shape)

        # CasADi writes a matrix column by column: each (r × c) output read as its transpose, row by row
        brows, contact, rows = take(ny + 1, n).T, take(ny + 1, me).T, take(ny + 1, m).T
        H, g, c = [], [], []
        for _ in self.levels:
            H.append(take(ny, ny))  # symmetric: column by column is row by row
            g.append(take(ny))
            c.append(take(1))
        equality = (take(ny), take(me), take(me), take(ny)) if self.equality_rows else None
        accepted, tau = (take(1), take(n)) if self.limits is not None else (np.zeros(1), np.zeros(n))
        return brows, contact, rows, H, g, c, equality, accepted, tau

    def __reduce__(self) -> tuple[Any, ...]:
        # rebuilt (the library loads from the cache): the buffers are this process's
        return (
            GeneratedContactData,
            (self.dynamics, self.levels, self.contacts, self.regularization, self.limits, self.bounds),
        )

    def _params(self) -> None:
        """The contacts' coefficients, the gains and weights and ε_k into the parameter buffer (in place), in the
        function's order."""
        parts: list[FloatArray] = []
        for c in self.contacts:
            parts += [c.normal, c.tangents[0], c.tangents[1], np.array([c.mu, c.kd, c.slip_velocity])]
        for lev in self.levels:
            for tk in lev:
                parts += [tk.sqrt_weight] if type(tk) is ContactForceTask else task_params([tk])
        parts.append(np.array(self.regularization))
        if self.bounds is not None:
            tail = [c.cone_rows()[0].ravel() for c in self.contacts] + list(self.bounds)
            parts += tail
            np.concatenate(tail, out=self.par_guess)
        np.concatenate(parts, out=self.par)

    def run(self, q: FloatArray, qd: FloatArray, t: float, ref: Reference) -> None:
        """Evaluate the outputs at (q, q̇) with the tasks' targets at t. A trajectory's new output is checked in the
        code (see :mod:`~armctl.controllers.osc.target_code`; one the code does not pass gets the NumPy path's
        check, which raises its named error).

        Raises
        ------
        InvalidParameterError, NonFiniteError, ShapeError
            A trajectory's output is not a valid target (as the NumPy path says)."""
        revisions = [tk.revision for lev in self.levels for tk in lev]
        if revisions != self._revisions:
            self._params()
            self._revisions = revisions
        pieces = [q, qd]
        unchecked = None
        for src in self._sources:
            if type(src) is TargetHolder:
                out, checked = src.shaped(t)
                pieces += (out[0].ravel(), out[1], out[2])  # the value row by row
                if not checked:
                    unchecked = [(src, out)] if unchecked is None else [*unchecked, (src, out)]
            elif type(src) is ContactForceTask:
                pieces.append(src.target(t))
            else:
                target_pieces([cast(Task, src)], t, ref, pieces)
        if self.friction is not None:
            pieces.append(self.friction.torque(qd))
        np.concatenate(pieces, out=self.inp)
        self._run()
        if unchecked is not None:
            valid = self.targets_ok[0] == 1.0
            for holder, out in unchecked:
                holder.confirm(t, out, valid)
