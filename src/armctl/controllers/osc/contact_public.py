"""The public side of a step of :class:`~armctl.controllers.osc.contact_qp.ContactQP`: what it leaves
(:class:`ContactStep`) and its solution on the public problem over x = [q̈; τ; f] (:func:`public_solution`): the
rows on y = [q̈; f] embedded with zero τ columns, x = [q̈; B y + h'; f], the contact, limit and cone multipliers as
they are and the equation of motion's ε_k τ + Σ z_τ (see :mod:`~armctl.controllers.osc.contact_qp`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from armctl._checks import FloatArray
from armctl.controllers.osc.build import StepQP
from armctl.controllers.osc.hierarchy import OSCSolution
from armctl.controllers.osc.levels import LevelRows
from armctl.controllers.osc.problem import QPArrays
from armctl.controllers.osc.solve import QPSolution

if TYPE_CHECKING:
    from armctl.controllers.osc.chain import SolverChain
    from armctl.controllers.osc.contact_qp import ContactQP
    from armctl.controllers.osc.generated_contact import GeneratedContactData


class ContactStep:
    """What one step of :class:`ContactQP` leaves: q̈, τ, the forces y's blocks, per level the QP and its
    verified solution (None for a level that kept the one above) and status, and the rows the public problem is
    made from (B = [M | −J_cᵀ | −h'], the contact rows, the bounds, each level's task rows)."""

    __slots__ = (
        "arrays",
        "b_rows",
        "bounds",
        "contact",
        "frozen",
        "hg",
        "hg_below",
        "outputs",
        "rows",
        "solutions",
        "status",
        "tau",
        "y",
    )

    def __init__(self) -> None:
        self.arrays: list[QPArrays] = []
        self.solutions: list[QPSolution | None] = []
        self.status: list[str] = []
        self.frozen: list[tuple[FloatArray, FloatArray] | None] = []
        self.rows: list[FloatArray] = []
        #: (H, g) of level 0 for a step taken without a solver, whose arrays are made when asked for
        self.hg: tuple[FloatArray, FloatArray] | None = None
        #: likewise (H, g) of the levels below 0 (their rows A and F of ``frozen``)
        self.hg_below: list[tuple[FloatArray, FloatArray]] = []
        #: for a step taken without a solver: its copy of the generated code's outputs and the code, until the
        #: rows above are read from it
        self.outputs: tuple[FloatArray, GeneratedContactData] | None = None
        self.b_rows: FloatArray
        self.contact: tuple[FloatArray, FloatArray]
        self.bounds: tuple[FloatArray, FloatArray]
        self.y: FloatArray
        self.tau: FloatArray


def taken_step(qp: ContactQP, gen: GeneratedContactData, chain: SolverChain, guessed: bool = False) -> ContactStep:
    """The step of an optimum that the generated code found and checked: on the contact rows alone
    (``gen.accepted``: the check of :func:`~armctl.controllers.osc.optimality.equality_optimum_ok`, in the code),
    or with ``guessed`` that of its active-set iterations (``gen.guess_ok``: the KKT check of
    :func:`~armctl.controllers.osc.optimality.kkt_ok`, in the code). Its outputs copied at once, y, λ, z and τ read
    from that copy, the rows, contact rows and (H, g) when the public solution or the check run again asks for
    them (:func:`_unpack`), the QP's arrays then (:func:`step_arrays`)."""
    flat = gen.out.copy()
    res = ContactStep()
    res.outputs = (flat, gen)
    res.bounds = gen.bounds  # type: ignore[assignment]  # set: the code accepts only with constant bounds
    if guessed:
        assert gen.guess_out is not None  # run_guess passed
        found = gen.guess_out.copy()
        y, lam, zs, act, tau = gen.guessed
        z, active = found[zs], found[act].astype(np.int8)
    else:
        assert gen.taken is not None  # the code accepts only with constant bounds
        found = flat
        y, lam, tau = gen.taken
        z, active = qp.no_multipliers, qp.no_active
    res.y = found[y]
    res.tau = found[tau]
    res.solutions.append(QPSolution(res.y, "solved", 0, "active set", found[lam], z, "active set", 0, active))
    res.status.append("solved")
    res.frozen.append(None)
    chain.record(qp.key, active)
    return res


def _unpack(res: ContactStep) -> None:
    """The rows, contact rows, each level's task rows and (H, g) of a step taken without a solver, from its copy
    of the code's outputs (views of it), if not read yet."""
    if res.outputs is None:
        return
    flat, gen = res.outputs
    brows, contact, rows, H, g, *_ = gen.outputs(flat)
    res.b_rows = brows
    res.contact = (contact[:, : gen.ny], contact[:, gen.ny])
    start = 0
    for lev in gen.levels:
        m = sum(tk.dim for tk in lev)
        res.rows.append(rows[start : start + m])
        start += m
    res.hg = (H[0], g[0])
    res.hg_below += zip(H[1:], g[1:], strict=True)
    res.outputs = None


def step_arrays(qp: ContactQP, res: ContactStep) -> list[QPArrays]:
    """The QP of each level of a step (made now for a step taken without a solver)."""
    _unpack(res)
    if not res.arrays and res.hg is not None:
        brows = res.b_rows
        C, ly, uy = qp.inequalities(brows, -brows[:, qp.ny], res.bounds)
        A, b = res.contact
        res.arrays.append(QPArrays(*res.hg, A, b, C, ly, uy))
        for k, (H, g) in enumerate(res.hg_below, 1):
            frozen = res.frozen[k]
            assert frozen is not None  # a level below 0 has its frozen rows
            F, phi = frozen
            res.arrays.append(QPArrays(H, g, np.vstack((A, F)), np.concatenate((b, phi)), C, ly, uy))
    return res.arrays


def _embed(qp: ContactQP, y: FloatArray, tau: FloatArray) -> FloatArray:
    """x = [q̈; τ; f] of y = [q̈; f] and τ."""
    n = qp.n
    x = np.empty(qp.nx)
    x[:n] = y[:n]
    x[n : 2 * n] = tau
    for _, cy, cx, _ in qp.contacts:
        x[cx] = y[cy]
    return x


def _embed_rows(qp: ContactQP, rows: FloatArray) -> FloatArray:
    """Rows on y (with a right-hand side column or not) as rows on x (zero τ columns)."""
    n, ny = qp.n, qp.ny
    extra = rows.shape[1] - ny
    out = np.zeros((rows.shape[0], qp.nx + extra))
    out[:, :n] = rows[:, :n]
    for _, cy, cx, _ in qp.contacts:
        out[:, cx] = rows[:, cy]
    if extra:
        out[:, qp.nx :] = rows[:, ny:]
    return out


def public_solution(qp: ContactQP, res: ContactStep, partial: bool = False) -> OSCSolution:
    """The public :class:`OSCSolution` of a step: its :class:`StepQP` on x = [q̈; τ; f], x, and each level's
    solution mapped onto it (the same z and contact-row multipliers; ε_k τ + Σ z_τ for the equation of
    motion). ``partial``: for a step that stopped at level 0 (only the problem is read)."""
    _unpack(res)
    n, ny, lay = qp.n, qp.ny, qp.layout
    brows = res.b_rows
    hf = -brows[:, ny]
    A_y, b_y = res.contact
    A = np.zeros((n + qp.me, qp.nx))
    A[:n, :n] = brows[:, :n]
    A[:n, n : 2 * n] = -np.eye(n)
    for _, cy, cx, _ in qp.contacts:
        A[:n, cx] = brows[:, cy]
    A[n:] = _embed_rows(qp, A_y)
    levels = []
    for k, (plan, px, _, _) in enumerate(qp.levels):
        if k >= len(res.rows):
            break
        jr = _embed_rows(qp, res.rows[k][: plan.m])
        levels.append(LevelRows(px.tasks, jr, px.scale(), px.slices))
    step = StepQP(lay, A, np.concatenate((-hf, b_y)), *res.bounds, levels, lay.regularization, False)
    frozen = [None if f is None else (_embed_rows(qp, f[0]), f[1]) for f in res.frozen]
    if partial:
        return OSCSolution(step, np.zeros(qp.nx), (None,), ("failed",), None, frozen)
    sols: list[QPSolution | None] = []
    B = brows[:, :ny]
    for k, sol in enumerate(res.solutions):
        if sol is None:
            sols.append(None)
            continue
        tau = B.dot(sol.x)
        tau += hf
        z = sol.z if sol.z is not None else np.zeros(qp.C_template.shape[0])
        y_dyn = qp.levels[k][3] * tau
        for r in qp.tau_rows:
            y_dyn = y_dyn + z[r]
        y_rest = sol.y if sol.y is not None else np.zeros(qp.me)
        sols.append(
            QPSolution(
                _embed(qp, sol.x, tau),
                sol.status,
                sol.iterations,
                sol.solver,
                np.concatenate((y_dyn, y_rest)),
                z,
                sol.stage,
                sol.fallbacks,
                sol.active,
            )
        )
    return OSCSolution(step, _embed(qp, res.y, res.tau), tuple(sols), tuple(res.status), None, frozen)
