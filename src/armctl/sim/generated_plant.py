"""The simulated plant as CasADi expressions, for the generated integration step (:mod:`armctl.sim.compiled_plant`).

The same terms as :class:`~armctl.sim.plant.Plant`, written once as symbols and generated as C:

* rigid-body dynamics: the recursions of :mod:`armctl.dynamics.recursive`, Newton–Euler for the bias
  C(q, q̇) q̇ + g(q) and composite rigid body for M(q) (the model the ``"pinocchio"`` backend expresses);
* joint friction τ_f(q̇) of :mod:`armctl.sim.friction` — the stick–slip model's kinetic curve for given sliding
  directions d (F_v q̇ + F_c(d) + (F_s − F_c)(d) exp(−(q̇/v_s)²)), or the smooth tanh curve — and its slope;
* contact: every point of every :class:`~armctl.sim.contact.Plane`, its position p(q) = p_j(q) + R_j(q) r on
  joint j's frame, J_p = ∂p/∂q, the normal law (Kelvin–Voigt or Hunt–Crossley) and the regularised Coulomb force
  along the plane, τ_c = Σ J_pᵀ F_p, with K = Σ J_pᵀ(∂F/∂p)J_p and D = Σ J_pᵀ(∂F/∂ṗ)J_p for the implicit schemes;
* the disturbance: −J_tool(q)ᵀ h_d, with h_d an input (sampled in Python, see :mod:`armctl.sim.plant`).

Sticking is a mask s (1: stuck) applied to the Cholesky solve of M q̈ = r: rows and columns of the stuck joints
are replaced by those of the identity and their right-hand side by 0, so that q̈_F = M_FF⁻¹ r_F and q̈_S = 0
*exactly* (every product that couples them is a product with an exact zero).

What is the geometry of the chain (joint axes and placements, gravity) is built into the code; what a user varies
between runs — the inertial parameters π (a payload, a perturbed model), friction levels, contact stiffness,
damping and friction, the planes, the points' offsets — is the input ``par``
(:class:`~armctl.sim.plant_layout.PlantLayout`), so that such variants share one library (the inertial parameters as
symbols cost little: the inertia tensors of real links are full anyway).
"""

from __future__ import annotations

from typing import Any, cast

import casadi as cs

from armctl.dynamics import recursive
from armctl.model.robot import RobotModel
from armctl.sim.plant_layout import FRICTION_PARAMS, POINT_PARAMS, PlantLayout


# --------------------------------------------------------------------------------------------- expressions
class PlantExpressions:
    """Builds the expressions of one plant's terms for symbolic inputs (see the module)."""

    def __init__(self, model: RobotModel, layout: PlantLayout) -> None:
        self.model = model
        self.layout = layout
        self.n = model.n

    # ------------------------------------------------------------------------------------ kinematics
    def poses(self, q: cs.SX) -> tuple[list[tuple[Any, Any]], list[tuple[cs.SX, cs.SX]]]:
        """(world poses (R_0j, p_0j) of the joint frames j = 0…n, joint transforms)."""
        tf = recursive.joint_transforms(self.model, q)
        out: list[tuple[Any, Any]] = [(cs.DM.eye(3), cs.DM.zeros(3))]
        for r, t in tf:
            rot, pos = out[-1]
            out.append((rot @ r, pos + rot @ t))
        return out, tf

    # ------------------------------------------------------------------------------------ friction
    def friction(self, v: cs.SX, direction: cs.SX, par: cs.SX) -> cs.SX:
        """τ_f(q̇) for the sliding directions d (see :meth:`Plant.kinetic_friction`). (A second source of
        :meth:`StickSlip.torque <armctl.sim.friction.StickSlip.torque>` and :meth:`SmoothFriction.torque
        <armctl.sim.friction.SmoothFriction.torque>`: a change there is a change here; tests/sim/test_compiled_plant.py
        fails when they disagree.)"""
        n, at = self.n, self.layout.friction_offset
        fv, cp, cn, hp, hn, vs = (par[at + k * n : at + (k + 1) * n] for k in range(6))
        if self.layout.friction == "stick-slip":
            level = cs.if_else(direction > 0, cp, 0) - cs.if_else(direction < 0, cn, 0)
            tau = fv * v + level
            if self.layout.stribeck:
                hump = cs.if_else(direction > 0, hp, 0) - cs.if_else(direction < 0, hn, 0)
                tau = tau + hump * cs.exp(-((v / vs) ** 2))
            return tau
        vt = par[at + FRICTION_PARAMS * n]
        return fv * v + cs.tanh(v / vt) * self._smooth_levels(v, par)

    def _smooth_levels(self, v: cs.SX, par: cs.SX) -> cs.SX:
        n, at = self.n, self.layout.friction_offset
        cp, cn, hp, hn, vs = (par[at + k * n : at + (k + 1) * n] for k in range(1, 6))
        pos = v > 0
        level = cs.if_else(pos, cp, cn)
        if self.layout.stribeck:
            x = cs.fmin(cs.fmax(v / vs, -40.0), 40.0)
            level = level + cs.if_else(pos, hp, hn) * cs.exp(-(x * x))
        return level

    def friction_slope(self, v: cs.SX, direction: cs.SX, par: cs.SX) -> cs.SX:
        """∂τ_f/∂q̇ (diagonal) (see :meth:`FrictionModel.slope`; a second source of ``StickSlip.slope`` and
        ``SmoothFriction.slope`` of :mod:`armctl.sim.friction`, as :meth:`friction` is of their torques)."""
        n, at = self.n, self.layout.friction_offset
        fv, _, _, hp, hn, vs = (par[at + k * n : at + (k + 1) * n] for k in range(6))
        x = cs.fmin(cs.fmax(v / vs, -40.0), 40.0)
        shape_slope = -2.0 * x * cs.exp(-(x * x)) / vs
        if self.layout.friction == "stick-slip":
            d = fv
            if self.layout.stribeck:
                hump = cs.if_else(direction > 0, hp, 0) - cs.if_else(direction < 0, hn, 0)
                d = d + hump * shape_slope
            return d
        vt = par[at + FRICTION_PARAMS * n]
        th = cs.tanh(v / vt)
        d = fv + (1.0 - th**2) / vt * self._smooth_levels(v, par)
        if self.layout.stribeck:
            d = d + th * cs.if_else(v > 0, hp, hn) * shape_slope
        return d

    # ------------------------------------------------------------------------------------- contact
    def points(self, q: cs.SX, par: cs.SX) -> list[tuple[cs.SX, cs.SX]]:
        """(p, J_p) of every contact point (J_p = ∂p/∂q: :meth:`linear_jacobian`)."""
        poses, _ = self.poses(q)
        out = []
        at = self.layout.points_offset
        for joint, _ in self.layout.points:
            rot, pos = poses[joint]
            p = pos + rot @ par[at + 6 : at + 9]
            out.append((p, self.linear_jacobian(poses, joint, p)))
            at += POINT_PARAMS
        return out

    def linear_jacobian(self, poses: list[tuple[Any, Any]], joint: int, p: cs.SX) -> cs.SX:
        """∂p/∂q (3 × n) of a point p [m] fixed to the frame of joint ``joint``, from the world poses of
        :meth:`poses`, column by column: a revolute joint i below it moves p along a_i × (p − o_i), a prismatic one
        along a_i (a_i its axis and o_i its frame's origin, in world axes); the joints above it not at all."""
        cols = []
        for i, j in enumerate(self.model.joints):
            if i >= joint:
                cols.append(cs.SX.zeros(3))
                continue
            rot, origin = poses[i + 1]
            axis = rot @ cs.DM(j.axis)
            cols.append(cs.cross(axis, p - origin) if j.kind == "revolute" else axis)
        return cs.horzcat(*cols)

    def _point_force(self, at: int, law: str, p: cs.SX, vp: cs.SX, par: cs.SX) -> dict[str, Any]:
        """The force F on the arm of the point at ``par[at:]`` (position p, velocity ṗ) and what its derivatives
        use. (A second source of :meth:`Plane.force <armctl.sim.contact.Plane.force>` and of the normal laws'
        ``force`` in :mod:`armctl.sim.normal_force`: a change there is a change here; tests/sim/test_compiled_plant.py
        and tests/sim/test_contact_record.py fail when they disagree.)"""
        nrm, pt = par[at : at + 3], par[at + 3 : at + 6]
        k, c, expo, mu, vslip = (par[at + i] for i in range(9, 14))
        depth = cs.dot(nrm, pt - p)
        vn = cs.dot(nrm, vp)
        rate = -vn
        if law == "kv":
            raw = k * depth + c * rate
            active = cs.logic_and(depth > 0, raw > 0)
            fn = cs.if_else(active, raw, 0)
            dfn_depth, dfn_rate = cs.if_else(active, k, 0), cs.if_else(active, c, 0)
        else:
            dpos = cs.fmax(depth, 0)
            dp = dpos**expo
            damp = 1.0 + c * rate
            active = cs.logic_and(depth > 0, damp > 0)
            fn = cs.if_else(active, k * dp * damp, 0)
            dfn_depth = cs.if_else(active, k * (expo * dpos ** (expo - 1.0)) * damp, 0)
            dfn_rate = cs.if_else(active, k * dp * c, 0)
        vt = vp - vn * nrm
        speed = cs.sqrt(cs.dot(vt, vt))
        dirn = nrm - (mu / cs.fmax(speed, vslip)) * vt
        return {
            "force": fn * dirn,
            **{"fn": fn, "dirn": dirn, "nrm": nrm, "vt": vt, "speed": speed, "mu": mu, "vslip": vslip},
            **{"dfn_depth": dfn_depth, "dfn_rate": dfn_rate},
        }

    def contact(self, q: cs.SX, v: cs.SX, par: cs.SX, stiffness: bool = False) -> tuple[cs.SX, cs.SX, cs.SX]:
        """(τ_c, K, D) of every point (see :meth:`Environment.joint_torque`); K and D are zero without
        ``stiffness``. (The force of a point: :meth:`_point_force`, a second source of :meth:`Plane.force
        <armctl.sim.contact.Plane.force>`.)"""
        n = self.n
        tau = cs.SX.zeros(n)
        kj = cs.SX.zeros(n, n)
        dj = cs.SX.zeros(n, n)
        at = self.layout.points_offset
        for (_, law), (p, jp) in zip(self.layout.points, self.points(q, par), strict=True):
            f = self._point_force(at, law, p, jp @ v, par)
            at += POINT_PARAMS
            tau = tau + jp.T @ f["force"]
            if stiffness:
                names = ("nrm", "dirn", "fn", "mu", "vslip", "vt", "speed")
                nrm, dirn, fn, mu, vslip, vt, speed = (f[x] for x in names)
                dfdp = -f["dfn_depth"] * (dirn @ nrm.T)
                proj = cs.SX.eye(3) - nrm @ nrm.T
                tang = vt / speed
                slow = (mu * fn / vslip) * proj
                fast = (mu * fn / speed) * (proj - tang @ tang.T)
                dfdv = -f["dfn_rate"] * (dirn @ nrm.T) - cs.if_else(speed <= vslip, slow, fast)
                kj = kj + jp.T @ dfdp @ jp
                dj = dj + jp.T @ dfdv @ jp
        return tau, kj, dj

    def sample(self, q: cs.SX, v: cs.SX, par: cs.SX) -> tuple[cs.SX, cs.SX, cs.SX, cs.SX]:
        """What is recorded of the contacts at one sample: (h, p, τ_ext, w) — the forces h_p = −F_p on the
        environment and the positions p of the P points (3P each, point by point), τ_ext = −τ_c and the wrench
        w = [Σ_p h_p; Σ_p (p − o) × h_p] about the tool frame's origin o. (A second source of
        :meth:`Recorder.record_external <armctl.sim.recorder.Recorder.record_external>` for a plant without a
        disturbance: a change there is a change here; tests/sim/test_contact_record.py fails when they disagree.)"""
        tau = cs.SX.zeros(self.n)
        hs, ps = [], []
        f, m = cs.SX.zeros(3), cs.SX.zeros(3)
        origin = self.tool(q, par)
        at = self.layout.points_offset
        for (_, law), (p, jp) in zip(self.layout.points, self.points(q, par), strict=True):
            force = self._point_force(at, law, p, jp @ v, par)["force"]
            at += POINT_PARAMS
            tau = tau + jp.T @ force
            h = -force
            hs.append(h)
            ps.append(p)
            f = f + h
            m = m + cs.cross(p - origin, h)
        return cs.vertcat(*hs), cs.vertcat(*ps), -tau, cs.vertcat(f, m)

    def tool(self, q: cs.SX, par: cs.SX) -> cs.SX:
        """The tool frame's origin [m], world axes (its place in its joint's frame is in ``par``)."""
        poses, _ = self.poses(q)
        rot, pos = poses[cast(int, self.layout.tool_joint)]  # set: the plant has points or a disturbance
        at = self.layout.tool_offset
        return pos + rot @ par[at : at + 3]

    def disturbance(self, q: cs.SX, hd: cs.SX, par: cs.SX) -> cs.SX:
        """−J_tool(q)ᵀ h_d: the joint torque the disturbance wrench h_d (what the arm exerts) adds to τ."""
        joint = cast(int, self.layout.disturbance_joint)  # set: the plant has a disturbance
        poses, _ = self.poses(q)
        rot, pos = poses[joint]
        at = self.layout.tool_offset
        jl = self.linear_jacobian(poses, joint, pos + rot @ par[at : at + 3])
        cols = []
        for i, j in enumerate(self.model.joints):
            if i < joint and j.kind == "revolute":
                cols.append(poses[i + 1][0] @ cs.DM(j.axis))
            else:
                cols.append(cs.SX.zeros(3))
        ja = cs.horzcat(*cols)
        return -(jl.T @ hd[:3] + ja.T @ hd[3:])

    def external(self, q: cs.SX, v: cs.SX, hd: cs.SX, par: cs.SX) -> cs.SX:
        """τ_e: contact torque plus disturbance torque (0 without either)."""
        tau = cs.SX.zeros(self.n)
        if self.layout.points:
            tau = tau + self.contact(q, v, par)[0]
        if self.layout.disturbance_joint is not None:
            tau = tau + self.disturbance(q, hd, par)
        return tau


def masked_cholesky_solve(mass: cs.SX, rhs: cs.SX, stuck: cs.SX) -> tuple[cs.SX, cs.SX]:
    """(x, smallest pivot): x_F = M_FF⁻¹ r_F and x_S = 0 for the stuck joints (s_i = 1), by a Cholesky solve of
    M with the stuck rows and columns replaced by the identity's and their right-hand side by 0 (see the module).
    The smallest pivot before its square root is ≤ 0 where M_FF is not positive definite."""
    n = mass.shape[0]
    keep = 1 - stuck
    masked = cs.SX(n, n)
    for i in range(n):
        for j in range(n):
            masked[i, j] = keep[i] * mass[i, j] + stuck[i] if i == j else keep[i] * keep[j] * mass[i, j]
    b = keep * rhs
    low: list[list[Any]] = [[None] * n for _ in range(n)]
    inv: list[Any] = [None] * n  # 1 / L_kk: one division a row, products elsewhere (divisions cost ~10 products)
    pivots = []
    for i in range(n):
        for k in range(i + 1):
            s = masked[i, k]
            for p in range(k):
                s = s - low[i][p] * low[k][p]
            if i == k:
                pivots.append(s)
                inv[i] = 1.0 / cs.sqrt(s)
            else:
                low[i][k] = s * inv[k]
    y: list[Any] = [None] * n
    for i in range(n):
        s = b[i]
        for p in range(i):
            s = s - low[i][p] * y[p]
        y[i] = s * inv[i]
    x: list[Any] = [None] * n
    for i in reversed(range(n)):
        s = y[i]
        for p in range(i + 1, n):
            s = s - low[p][i] * x[p]
        x[i] = s * inv[i]
    return cs.vertcat(*x), cs.mmin(cs.vertcat(*pivots))


# ------------------------------------------------------------------------------------------------- kernels
#: the kernels of each family: explicit schemes ("rk4", "euler") and implicit ones
KERNELS = {
    "explicit": ("pk_rhs", "pk_terms", "pk_mass", "pk_friction"),
    "implicit": ("pk_rhs", "pk_terms", "pk_mass", "pk_friction", "pk_bias", "pk_implicit", "pk_symplectic"),
}


def kernels(model: RobotModel, layout: PlantLayout, family: str) -> list[cs.Function]:
    """The generated kernels of ``family`` (see :data:`KERNELS`), called by the step's C driver.

    * ``pk_rhs(q, q̇, τ, d, s, h_d, par) → (q̈, τ_f, τ_e, smallest pivot)``: the accelerations with the stuck joints
      held, and the friction and external torques they used;
    * ``pk_terms(q, q̇, τ, d, h_d, par) → (M, r, τ_f, τ_e)``: the mass matrix and r = τ − τ_f − C q̇ − g + τ_e, for
      the stick solve (whose accelerations are then RK4's first stage), with the friction and external torques;
    * ``pk_mass(q, par) → M``; ``pk_friction(q̇, d, par) → τ_f``; ``pk_bias(q, q̇, par) → (C q̇ + g, g)``;
    * ``pk_implicit(q, q̇₁, h, d, h_d, par) → (−τ_f + τ_e(q + h q̇₁, q̇₁), h diag(∂τ_f/∂q̇) − h(D + hK), τ_f, τ_e)``:
      backward Euler's velocity-dependent force and its Jacobian;
    * ``pk_symplectic(q, v̄, h, d, h_d, par) → (C(q, v̄)ᵀv̄ − τ_f + τ_e, h diag(∂τ_f/∂q̇) − hD, τ_f, τ_e, K)``:
      the same for symplectic Euler (C(q, v̄)ᵀv̄ = ∂T/∂q at v̄);
    * with contact points, ``pk_sample(q, q̇, par) → (h, p, τ_ext, w)``: what is recorded of the contacts at a
      sample (:meth:`PlantExpressions.sample`).
    """
    n = model.n
    ex = PlantExpressions(model, layout)
    q, v, tau, d, s = (cs.SX.sym(x, n) for x in ("q", "qd", "tau", "dir", "stuck"))
    hd = cs.SX.sym("hd", 6)
    par = cs.SX.sym("par", layout.size)
    h = cs.SX.sym("h")
    _, tf = ex.poses(q)
    pi = par[: layout.friction_offset]
    zeros = cs.SX.zeros(n)

    def rnea(vel: cs.SX, acc: cs.SX, gravity: bool = True) -> cs.SX:
        return recursive.inverse_dynamics(model, q, vel, acc, gravity=gravity, transforms=tf, params=pi)

    def bias(vel: cs.SX) -> cs.SX:
        return rnea(vel, zeros)

    mass = recursive.mass_matrix(model, q, transforms=tf, params=pi)

    fric = ex.friction(v, d, par) if layout.has_friction else zeros
    ext = ex.external(q, v, hd, par)
    made: dict[str, cs.Function] = {}

    def add(name: str, inputs: list[cs.SX], outputs: list[cs.SX]) -> None:
        made[name] = cs.Function(name, inputs, [cs.densify(o) for o in outputs])

    acc, pivot = masked_cholesky_solve(mass, tau - fric + ext - bias(v), s)
    add("pk_rhs", [q, v, tau, d, s, hd, par], [acc, fric, ext, pivot])
    add("pk_terms", [q, v, tau, d, hd, par], [mass, tau - fric + ext - bias(v), fric, ext])
    add("pk_mass", [q, par], [mass])
    add("pk_friction", [v, d, par], [fric])
    if family == "implicit":
        add("pk_bias", [q, v, par], [bias(v), bias(zeros)])
        slope = ex.friction_slope(v, d, par) if layout.has_friction else zeros
        # backward Euler: the external force at (q + h q̇₁, q̇₁)
        q1 = q + h * v
        ext1 = ex.external(q1, v, hd, par)
        jac = h * cs.diag(slope)
        if layout.points:
            _, kj, dj = ex.contact(q1, v, par, stiffness=True)
            jac = jac - h * (dj + h * kj)
        add("pk_implicit", [q, v, h, d, hd, par], [-fric + ext1, jac, fric, ext1])
        # symplectic Euler: ∂T/∂q at v̄ (C(q, v̄)ᵀ v̄ for the Christoffel C), T = ½ v̄ᵀ M v̄ with M v̄ by Newton–Euler
        dtdq = cs.gradient(0.5 * cs.dot(v, rnea(zeros, v, gravity=False)), q)
        jac_s = h * cs.diag(slope)
        kj0 = cs.SX.zeros(n, n)
        if layout.points:
            _, kj0, dj0 = ex.contact(q, v, par, stiffness=True)
            jac_s = jac_s - h * dj0
        add("pk_symplectic", [q, v, h, d, hd, par], [dtdq - fric + ext, jac_s, fric, ext, kj0])
    if layout.points:
        add("pk_sample", [q, v, par], list(ex.sample(q, v, par)))
    return [made[name] for name in KERNELS[family] + (("pk_sample",) if layout.points else ())]
