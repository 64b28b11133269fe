"""`GeneratedInner`: the inner motion loop of admittance and force control
(:class:`~armctl.controllers.interaction.inner.InnerMotion`) as one call of generated C code.

At (q, q̇), the commanded pose x_c, twist v_c, acceleration a_c, the posture q_n and the wrench h to compensate,
one call evaluates, with the frame's kinematics from :mod:`armctl.dynamics.symbolic_frames` (J, J̇ q̇), M(q) and
Newton–Euler from :mod:`armctl.dynamics.recursive` and Cholesky factorisations written out::

    ẍ* = a_c + K_P e + K_D ė,    q̈₀ = K_P,n (q_n − q) − K_D,n q̇
    "osc":              τ = Jᵀ (J M⁻¹ Jᵀ)⁻¹ (ẍ* − J̇ q̇ − J q̈₀) + RNEA(q, q̇, q̈₀) + Jᵀ h
    "computed_torque":  q̈ = J⁺ (ẍ* − J̇ q̇ − J q̈₀) + q̈₀,  J⁺ = Jᵀ (J Jᵀ)⁻¹,   τ = RNEA(q, q̇, q̈) + Jᵀ h

(the same laws as the NumPy path: J⁺ (ẍ* − J̇ q̇) + (I − J⁺ J) q̈₀ = J⁺ (ẍ* − J̇ q̇ − J q̈₀) + q̈₀). The gains are an
input of the code; the library is compiled once per model, frame and kind and cached on disk.
"""

from __future__ import annotations

import hashlib
import itertools
from typing import Any

import casadi as cs
import numpy as np

from armctl._checks import FloatArray
from armctl.codegen import library as codegen
from armctl.controllers.interaction.generated import FLAGS, finiteness
from armctl.controllers.osc.tasks.rotation import rotation_error_sx
from armctl.dynamics.base import Dynamics
from armctl.dynamics.casadi_buffer import buffer_of, view
from armctl.dynamics.recursive import (
    cholesky_factor,
    cholesky_substitute,
    inverse_dynamics,
    joint_transforms,
    mass_matrix,
)
from armctl.dynamics.symbolic_frames import frame_kinematics
from armctl.model.robot import RobotModel

_CODE_VERSION = 3
_NAME = "interaction_inner"


def sizes(n: int) -> tuple[int, int]:
    """(inputs, parameters): x = [q; q̇; x_c (4×4 row by row); v_c; a_c; q_n; h], p = [K_P; K_D; K_P,n; K_D,n]."""
    return 2 * n + 16 + 6 + 6 + n + 6, 2 * 36 + 2 * n * n


def _exp3(w: Any) -> Any:
    """exp: ℝ³ → SO(3) (Rodrigues), with the series near 0 (no division by a vanishing angle in either branch)."""
    t2 = cs.dot(w, w)
    small = t2 < 1e-12
    theta = cs.sqrt(cs.if_else(small, 1.0, t2))
    a = cs.if_else(small, 1.0 - t2 / 6.0, cs.sin(theta) / theta)
    b = cs.if_else(small, 0.5 - t2 / 24.0, (1.0 - cs.cos(theta)) / cs.if_else(small, 1.0, t2))
    wx = cs.skew(w)
    return cs.SX.eye(3) + a * wx + b * (wx @ wx)


def admittance_stage(x: Any, par: Any, axes: int) -> tuple[Any, ...]:
    """The compliant frame's step of :class:`~armctl.controllers.Admittance` in SX: from x = [x_d (4×4 row by
    row); v_d; a_d; h; p_c; R_c (row by row); v_c; Δt] and p = [M_d⁻¹; D_d; K_d] (m×m each), the command
    (pose 4×4, twist, acceleration) and the outputs [p_c; R_c (column by column); v_c] after the step and e_c."""
    pose_d = cs.reshape(x[:16], 4, 4).T
    v_d, a_d, h = x[16:22], x[22:28], x[28:34]
    p_c, r_c, v_c, dt = x[34:37], cs.reshape(x[37:46], 3, 3).T, x[46:52], x[52]
    m, m2 = axes, axes * axes
    inv_m, damp, stiff = (cs.reshape(par[i * m2 : (i + 1) * m2], m, m) for i in range(3))
    e_c = cs.vertcat(p_c - pose_d[:3, 3], -rotation_error_sx(pose_d[:3, :3], r_c))[:m]
    acc = cs.vertcat(a_d[:m] + inv_m @ (-h[:m] - damp @ (v_c - v_d)[:m] - stiff @ e_c), a_d[m:])
    v_new = v_c + acc * dt
    if m == 3:
        v_new = cs.vertcat(v_new[:3], v_d[3:])
    p_new = p_c + v_new[:3] * dt
    r_new = _exp3(v_new[3:] * dt) @ r_c if m == 6 else pose_d[:3, :3]
    cmd = cs.vertcat(cs.horzcat(r_new, p_new), pose_d[3, :])
    return cmd, v_new, acc, cs.vertcat(p_new, cs.vec(r_new), v_new), e_c


def inner_function(
    model: RobotModel, frame: str | None, kind: str, force_loop: bool = False, admittance: int = 0
) -> cs.Function:
    """The CasADi function of the module: (x, p) → [τ; e; p] (p the frame's position). With ``force_loop``, the
    force loop of :mod:`~armctl.controllers.interaction.force_loop` comes first: x also holds f_d (3), the integral
    ∫e_f before this step (3) and Δt (1), p holds P, P K_F, P K_I (3×3 each) and whether to compensate h (1, 0 or
    1), and the command is
    p_c = p_d + P K_F e_f + P K_I (∫e_f + e_f Δt), v_c = blockdiag(I − P, I) v_d (likewise a_c), e_f = P (f_d − f),
    f = h[:3]; the outputs are then [τ; e; e_f; ∫e_f after this step; x_F]. With ``admittance`` (its axes, 3 or 6),
    the compliant frame's step (:func:`admittance_stage`) comes first: x also holds p_c, R_c (row by row), v_c and
    Δt, p holds M_d⁻¹, D_d, K_d and whether to compensate h; the pose, twist and acceleration inputs are the
    target's; the outputs are then [τ; e; p_c; R_c (column by column); v_c; e_c]. A second output is Σ x + Σ of the
    first (:func:`~armctl.controllers.interaction.generated.finiteness`)."""
    n = model.n
    nx, npar = sizes(n)
    extra = (7, 28) if force_loop else (19, 3 * admittance * admittance + 1) if admittance else (0, 0)
    x, par = cs.SX.sym("x", nx + extra[0]), cs.SX.sym("p", npar + extra[1])
    q, qd = x[:n], x[n : 2 * n]
    k = 2 * n
    pose = cs.reshape(x[k : k + 16], 4, 4).T
    k += 16
    v_c, a_c, q_n, h = x[k : k + 6], x[k + 6 : k + 12], x[k + 12 : k + 12 + n], x[k + 12 + n : k + 18 + n]
    kp, kd = cs.reshape(par[:36], 6, 6), cs.reshape(par[36:72], 6, 6)
    pkp, pkd = cs.reshape(par[72 : 72 + n * n], n, n), cs.reshape(par[72 + n * n : npar], n, n)
    if force_loop:
        f_d, before, dt = x[nx : nx + 3], x[nx + 3 : nx + 6], x[nx + 6]
        proj = cs.reshape(par[npar : npar + 9], 3, 3)
        pkf, pki = cs.reshape(par[npar + 9 : npar + 18], 3, 3), cs.reshape(par[npar + 18 : npar + 27], 3, 3)
        e_f = proj @ (f_d - h[:3])
        after = before + e_f * dt
        offset = pkf @ e_f + pki @ after
        free = cs.SX.eye(3) - proj
        pose = cs.vertcat(cs.horzcat(pose[:3, :3], pose[:3, 3] + offset), pose[3, :])
        v_c = cs.vertcat(free @ v_c[:3], v_c[3:])
        a_c = cs.vertcat(free @ a_c[:3], a_c[3:])
    if admittance:
        stage_x = cs.vertcat(x[2 * n : 2 * n + 28], h, x[nx : nx + 19])
        pose, v_c, a_c, state, e_c = admittance_stage(stage_x, par[npar:], admittance)
    tf = joint_transforms(model, q)
    pos, rot, jac, drift = frame_kinematics(model, q, qd, frame, tf)
    e = cs.vertcat(pose[:3, 3] - pos, rotation_error_sx(pose[:3, :3], rot))
    xdd = a_c + kp @ e + kd @ (v_c - jac @ qd)
    qdd0 = pkp @ (q_n - q) - pkd @ qd
    rhs = xdd - drift - jac @ qdd0
    if kind == "osc":
        low_m = cholesky_factor(mass_matrix(model, q, tf))
        mij = cholesky_substitute(low_m, jac.T)
        force = cholesky_substitute(cholesky_factor(jac @ mij), rhs)
        tau = jac.T @ force + inverse_dynamics(model, q, qd, qdd0, transforms=tf)
    else:
        qdd = jac.T @ cholesky_substitute(cholesky_factor(jac @ jac.T), rhs) + qdd0
        tau = inverse_dynamics(model, q, qd, qdd, transforms=tf)
    tau = tau + jac.T @ (h * par[-1] if force_loop or admittance else h)  # the last parameter: compensate
    name = _NAME + ("_force" if force_loop else f"_admittance{admittance}" if admittance else "")
    if force_loop:
        out = cs.vertcat(tau, e, e_f, after, offset)
    elif admittance:
        out = cs.vertcat(tau, e, state, e_c)
    else:
        out = cs.vertcat(tau, e, pos)
    return cs.Function(name, [x, par], [out, finiteness(x, out)])


def _tag(model: RobotModel, frame: str | None, kind: str) -> str:
    f = model.frame(frame)
    where = hashlib.sha256(f.placement.tobytes()).hexdigest()[:12]
    key = model.fingerprint(inertial=True, tool=False)
    return f"interaction-inner|{key}|v{_CODE_VERSION}|{f.name}:{f.joint}:{where}|{kind}"


class GeneratedInner:
    """The generated inner loop of the module, bound to buffers of its own (built or loaded on construction).

    Parameters
    ----------
    dynamics, frame
        As for :class:`~armctl.controllers.interaction.generated.GeneratedImpedance`.
    kind : {"osc", "computed_torque"}
        The law.
    force_loop : bool, optional
        With the force loop first (see :func:`inner_function`).
    admittance : int, optional
        With the compliant frame of that many axes (3 or 6) first; 0: none.
    """

    def __init__(
        self, dynamics: Dynamics, frame: str | None, kind: str, force_loop: bool = False, admittance: int = 0
    ) -> None:
        model = dynamics.model
        self.dynamics, self.frame, self.kind = dynamics, frame, kind
        self.force_loop, self.admittance = force_loop, admittance
        cache_dir = dynamics.options.get("cache_dir")
        name = _NAME + ("_force" if force_loop else f"_admittance{admittance}" if admittance else "")
        tag = _tag(model, frame, kind) + f"|force_loop={force_loop}|admittance={admittance}"
        make = lambda: [inner_function(model, frame, kind, force_loop, admittance)]  # noqa: E731
        what = f"the interaction controllers' inner loop ({kind}) for {model.name!r}"  # logged if it is built
        fn = codegen.cached([name], tag, make, cache_dir, flags=FLAGS, what=what)[name]
        self.n = n = model.n
        nx, npar = sizes(n)
        if force_loop:
            nx, npar, nout = nx + 7, npar + 28, n + 15
        elif admittance:
            nx, npar, nout = nx + 19, npar + 3 * admittance * admittance + 1, n + 24 + admittance
        else:
            nout = n + 9
        self.inp, self.par, self.out = np.zeros(nx), np.zeros(npar), np.zeros(nout)
        self._zero_wrench = np.zeros(6)
        buf, self._run = buffer_of(fn)
        buf.set_arg(0, view(self.inp))
        buf.set_arg(1, view(self.par))
        buf.set_res(0, view(self.out))
        self.check = np.zeros(1)  # the finiteness sum of the last call
        buf.set_res(1, view(self.check))
        self._buf = buf
        if force_loop:  # views of the input buffer, each of its piece's shape
            bounds = np.cumsum([0, n, n, 16, 6, 6, n, 6, 3, 3])
            views = [self.inp[a:b] for a, b in itertools.pairwise(bounds)]
            views[2] = views[2].reshape(4, 4)  # row by row
            self._pieces = tuple(views)
            self._dt_at = int(bounds[-1])
        self._target: tuple[FloatArray, ...] | None = None  # the target in the input buffer
        self._force: FloatArray | None = None  # the fixed f_d in the input buffer

    def __reduce__(self) -> tuple[Any, ...]:
        # rebuilt (the library loads from the cache: the buffers are this process's), with the gains
        args = (self.dynamics, self.frame, self.kind, self.force_loop, self.admittance)
        return (GeneratedInner, args, {"par": self.par.copy()})

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.par[...] = state["par"]

    def set_gains(
        self, kp: FloatArray, kd: FloatArray, posture_kp: FloatArray, posture_kd: FloatArray, *force: Any
    ) -> None:
        """K_P, K_D, K_P,n, K_D,n (and with the force loop, P, P K_F, P K_I, compensate; with the admittance,
        M_d⁻¹, D_d, K_d, compensate) into the parameter buffer (CasADi reads a matrix column by column: the
        transposes)."""
        parts = [kp.T.ravel(), kd.T.ravel(), posture_kp.T.ravel(), posture_kd.T.ravel()]
        if self.force_loop or self.admittance:
            *matrices, compensate = force
            parts += [a.T.ravel() for a in matrices] + [np.array([1.0 if compensate else 0.0])]
        np.concatenate(parts, out=self.par)

    def run(
        self,
        q: FloatArray,
        qd: FloatArray,
        goal: tuple[FloatArray, FloatArray, FloatArray],
        posture: FloatArray,
        wrench: FloatArray | None,
    ) -> FloatArray:
        """[τ; e; p] (a new array): the torque, the frame error [m; rad] and the frame's position [m], for the
        commanded motion ``goal`` = (pose (4×4), twist (6,), acceleration (6,))."""
        pose, twist, acceleration = goal
        h = self._zero_wrench if wrench is None else wrench
        np.concatenate((q, qd, pose.ravel(), twist, acceleration, posture, h), out=self.inp)
        self._run()
        return self.out.copy()

    def run_force_loop(
        self,
        q: FloatArray,
        qd: FloatArray,
        target: tuple[FloatArray, FloatArray, FloatArray],
        posture: FloatArray,
        wrench: FloatArray,
        force: FloatArray,
        fixed_force: bool,
        integral: FloatArray,
        dt: float,
    ) -> FloatArray:
        """With the force loop: [τ; e; e_f; ∫e_f; x_F] (a new array) at (q, q̇) for the ``target`` (x_d, v_d,
        a_d), the posture q_n, the wrench h, f_d, ∫e_f before this step and Δt [s]; :attr:`check` is then the
        finiteness sum of the call. A target that is the same tuple as at the last call is not copied again
        (pass a new tuple when its values change), nor a ``force`` that is the same read-only array
        (``fixed_force``: it never changes)."""
        q_in, qd_in, pose_in, twist_in, acc_in, posture_in, h_in, force_in, integral_in = self._pieces
        q_in[...] = q  # into views of the input buffer: cheaper than one concatenation of many pieces
        qd_in[...] = qd
        if target is not self._target:
            pose_in[...], twist_in[...], acc_in[...] = target
            self._target = target  # kept: its identity is not reused while it lives
        posture_in[...] = posture
        h_in[...] = wrench
        if force is not self._force:
            force_in[...] = force
            self._force = force if fixed_force else None
        integral_in[...] = integral
        self.inp[self._dt_at] = dt
        self._run()
        return self.out.copy()

    def run_force(self, pieces: tuple[Any, ...]) -> FloatArray:
        """The outputs (a new array) for the inputs ``pieces``, concatenated: with the force loop (q, q̇, x_d, v_d,
        a_d, q_n, h, f_d, ∫e_f, [Δt]) → [τ; e; e_f; ∫e_f; x_F]; with the admittance (q, q̇, x_d, v_d, a_d, q_n, h,
        p_c, R_c, v_c, [Δt]) → [τ; e; p_c; R_c; v_c; e_c]."""
        np.concatenate(pieces, out=self.inp)
        self._run()
        return self.out.copy()
