"""The recursive algorithms in CasADi SX with the model's numbers built in: Newton–Euler inverse dynamics,
the composite-rigid-body mass matrix, and forward dynamics from them — for code generation.

They express the model the ``"pinocchio"`` backend expresses (rotors as reflected inertia k_r²I_m on the
diagonal of M, no gyroscopic coupling, no friction), joint by joint in each link's own frame, as the textbook
writes them (Siciliano et al., §7.5 and §7.6; see ``shared/references``). With every constant folded in (a
joint axis along z zeroes two thirds of its products), the generated C code is short;
:mod:`armctl.sim.compiled` builds the simulator's integration step from it.

Link frames: frame i is joint i's frame after its motion, its origin on the joint axis; R_i is the rotation
taking frame-i coordinates to frame i−1 and t_i the origin of frame i in frame i−1. Link i's inertial
parameters are m_i, the first moment h_i = m_i c_i and the inertia I_i about the frame origin, all in frame i
(the augmented-link parameters of :meth:`armctl.RobotModel.parameters`).
"""

from __future__ import annotations

from typing import Any

import casadi as cs

from armctl.dynamics.lagrange import _axis_rotation
from armctl.model.robot import PARAMS_PER_JOINT, RobotModel


def joint_transforms(model: RobotModel, q: cs.SX) -> list[tuple[cs.SX, cs.SX]]:
    """(R_i, t_i) of every joint: frame i's rotation and origin in frame i−1 at the joint position q_i."""
    out = []
    for i, j in enumerate(model.joints):
        rp, tp = cs.DM(j.placement[:3, :3]), cs.DM(j.placement[:3, 3])
        if j.kind == "revolute":
            out.append((rp @ _axis_rotation(j.axis, q[i]), cs.SX(tp)))
        else:
            out.append((cs.SX(rp), tp + rp @ cs.DM(j.axis) * q[i]))
    return out


def links(model: RobotModel, params: Any = None) -> list[tuple[Any, Any, Any, cs.DM, Any]]:
    """(m, h = m c, I about the origin, axis, reflected rotor inertia) of every link, in its frame, from the
    first eleven entries per joint of ``params`` (π of :meth:`armctl.RobotModel.parameters`, 13 per joint;
    default the model's own, as numbers that fold into the expressions; a CasADi SX vector of symbols for a
    regressor)."""
    pi = cs.DM(model.parameters()) if params is None else params
    out = []
    for i, j in enumerate(model.joints):
        p = pi[PARAMS_PER_JOINT * i : PARAMS_PER_JOINT * i + 11]
        inertia = cs.vertcat(cs.horzcat(p[4], p[5], p[7]), cs.horzcat(p[5], p[6], p[8]), cs.horzcat(p[7], p[8], p[9]))
        out.append((p[0], p[1:4], inertia, cs.DM(j.axis), p[10]))
    return out


def inverse_dynamics(
    model: RobotModel,
    q: cs.SX,
    qd: cs.SX,
    qdd: cs.SX,
    gravity: bool = True,
    transforms: list[tuple[cs.SX, cs.SX]] | None = None,
    params: Any = None,
) -> cs.SX:
    """τ = M(q) q̈ + C(q, q̇) q̇ + g(q) by the Newton–Euler recursion (gravity=False: without g), with the
    inertial parameters ``params`` (see :func:`links`; τ is linear in them).

    Forward, in frame i (ω, ω̇ the link's angular velocity and acceleration, a the acceleration of its
    origin; gravity enters as a base acceleration −g₀):
        revolute:  ω_i = R_iᵀω_{i−1} + z q̇_i,  ω̇_i = R_iᵀω̇_{i−1} + z q̈_i + (R_iᵀω_{i−1}) × z q̇_i
        both:      a_i = R_iᵀ(a_{i−1} + ω̇_{i−1} × t_i + ω_{i−1} × (ω_{i−1} × t_i))
        prismatic: ω_i = R_iᵀω_{i−1},  ω̇_i = R_iᵀω̇_{i−1},  a_i += z q̈_i + 2 ω_i × z q̇_i
    Backward (f, μ: force and moment about the origin that link i−1 exerts on link i):
        f_i = m a_i + ω̇_i × h + ω_i × (ω_i × h) + R_{i+1} f_{i+1}
        μ_i = I ω̇_i + ω_i × I ω_i + h × a_i + R_{i+1} μ_{i+1} + t_{i+1} × R_{i+1} f_{i+1}
        τ_i = zᵀμ_i (revolute) or zᵀf_i (prismatic), + k_r²I_m q̈_i.
    """
    consts = links(model, params)
    tf = transforms if transforms is not None else joint_transforms(model, q)
    w, wd = cs.SX.zeros(3), cs.SX.zeros(3)
    acc = -cs.SX(cs.DM(model.gravity)) if gravity else cs.SX.zeros(3)
    kin = []
    for i, j in enumerate(model.joints):
        r, t = tf[i]
        z = consts[i][3]
        w_in = r.T @ w
        acc = r.T @ (acc + cs.cross(wd, t) + cs.cross(w, cs.cross(w, t)))
        if j.kind == "revolute":
            wd = r.T @ wd + z * qdd[i] + cs.cross(w_in, z * qd[i])
            w = w_in + z * qd[i]
        else:
            wd = r.T @ wd
            w = w_in
            acc = acc + z * qdd[i] + 2 * cs.cross(w, z * qd[i])
        kin.append((w, wd, acc))
    tau: list[Any] = [None] * model.n
    f_next = mu_next = None
    for i in reversed(range(model.n)):
        m, h, inertia, z, rotor = consts[i]
        w, wd, acc = kin[i]
        f = m * acc + cs.cross(wd, h) + cs.cross(w, cs.cross(w, h))
        mu = inertia @ wd + cs.cross(w, inertia @ w) + cs.cross(h, acc)
        if f_next is not None and mu_next is not None:
            r, t = tf[i + 1]
            rf = r @ f_next
            f = f + rf
            mu = mu + r @ mu_next + cs.cross(t, rf)
        tau[i] = cs.dot(z, mu if model.joints[i].kind == "revolute" else f) + rotor * qdd[i]
        f_next, mu_next = f, mu
    return cs.vertcat(*tau)


def mass_matrix(
    model: RobotModel, q: cs.SX, transforms: list[tuple[cs.SX, cs.SX]] | None = None, params: Any = None
) -> cs.SX:
    """M(q) by the composite-rigid-body recursion, with the inertial parameters ``params`` (see :func:`links`).

    The composite body of links i…n, in frame i: (m, h, I) of link i plus those of composite i+1 carried over
    R_{i+1}, t_{i+1} (h ← R h + m t, I ← R I Rᵀ − [t]ₓ[R h]ₓ − [R h]ₓ[t]ₓ − m [t]ₓ²). A unit acceleration of
    joint i, at rest and without gravity, needs from it the force and moment (f, μ) = (z × h, I z) (revolute)
    or (m z, h × z) (prismatic); M_ii = zᵀμ (or zᵀf) + k_r²I_m, and M_ki, k < i, is joint k's projection of
    (f, μ) carried down the chain (f ← R f, μ ← R μ + t × R f).
    """
    consts = links(model, params)
    tf = transforms if transforms is not None else joint_transforms(model, q)
    n = model.n
    kinds = [j.kind for j in model.joints]
    mm: list[list[Any]] = [[None] * n for _ in range(n)]
    cm: Any = 0.0
    ch: Any = cs.SX.zeros(3)
    ci: Any = cs.SX.zeros(3, 3)
    for i in reversed(range(n)):
        m, h, inertia, z, rotor = consts[i]
        if i < n - 1:  # carry composite i+1 into frame i
            r, t = tf[i + 1]
            rh = r @ ch
            tx, rhx = cs.skew(t), cs.skew(rh)
            ci = r @ ci @ r.T - tx @ rhx - rhx @ tx - cm * (tx @ tx)
            ch = rh + cm * t
        cm, ch, ci = cm + m, ch + h, ci + inertia
        if kinds[i] == "revolute":
            f, mu = cs.cross(z, ch), ci @ z
        else:
            f, mu = cm * z, cs.cross(ch, z)
        mm[i][i] = cs.dot(z, mu if kinds[i] == "revolute" else f) + rotor
        for k in range(i - 1, -1, -1):
            r, t = tf[k + 1]
            f = r @ f
            mu = r @ mu + cs.cross(t, f)
            zk = consts[k][3]
            mm[k][i] = mm[i][k] = cs.dot(zk, mu if kinds[k] == "revolute" else f)
    return cs.vertcat(*[cs.horzcat(*row) for row in mm])


def cholesky_factor(a: Any) -> list[list[Any]]:
    """L (lower triangular, as nested lists of SX entries) with L Lᵀ = A for a symmetric positive definite A,
    written out entry by entry (the generated code then has no loops or branches; a matrix that is not positive
    definite gives NaN)."""
    n = a.shape[0]
    low: list[list[Any]] = [[None] * n for _ in range(n)]
    for i in range(n):
        for k in range(i + 1):
            s = a[i, k]
            for p in range(k):
                s = s - low[i][p] * low[k][p]
            low[i][k] = cs.sqrt(s) if i == k else s / low[k][k]
    return low


def cholesky_substitute(low: list[list[Any]], b: Any) -> Any:
    """X with L Lᵀ X = B, from L of :func:`cholesky_factor`: forward then backward substitution, column by column
    of B (a vector or a matrix)."""
    n = len(low)
    cols = []
    for c in range(b.shape[1]):
        y: list[Any] = [None] * n
        for i in range(n):
            s = b[i, c]
            for p in range(i):
                s = s - low[i][p] * y[p]
            y[i] = s / low[i][i]
        x: list[Any] = [None] * n
        for i in reversed(range(n)):
            s = y[i]
            for p in range(i + 1, n):
                s = s - low[p][i] * x[p]
            x[i] = s / low[i][i]
        cols.append(cs.vertcat(*x))
    return cs.horzcat(*cols)


def cholesky_solve(a: cs.SX, b: cs.SX) -> cs.SX:
    """x with A x = b for a symmetric positive definite A, by Cholesky A = L Lᵀ (:func:`cholesky_factor`,
    :func:`cholesky_substitute`)."""
    return cholesky_substitute(cholesky_factor(a), b)


def forward_dynamics(model: RobotModel, q: cs.SX, qd: cs.SX, tau: cs.SX) -> cs.SX:
    """q̈ = M(q)⁻¹(τ − C(q, q̇) q̇ − g(q)): one Newton–Euler pass at q̈ = 0, the composite-rigid-body M, Cholesky."""
    tf = joint_transforms(model, q)
    bias = inverse_dynamics(model, q, qd, cs.SX.zeros(model.n), transforms=tf)
    return cholesky_solve(mass_matrix(model, q, transforms=tf), tau - bias)


def functions(model: RobotModel) -> dict[str, cs.Function]:
    """CasADi functions ``tau(q, qd, qdd)``, ``M(q)`` and ``qdd(q, qd, tau)`` of this model (numbers built in)."""
    n = model.n
    q, qd, qdd, tau = (cs.SX.sym(s, n) for s in ("q", "qd", "qdd", "tau"))
    return {
        "tau": cs.Function("tau", [q, qd, qdd], [inverse_dynamics(model, q, qd, qdd)]),
        "M": cs.Function("M", [q], [mass_matrix(model, q)]),
        "qdd": cs.Function("qdd", [q, qd, tau], [forward_dynamics(model, q, qd, tau)]),
    }
