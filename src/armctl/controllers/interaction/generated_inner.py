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
import logging
import time
from typing import Any

import casadi as cs
import numpy as np

from armctl._checks import FloatArray
from armctl.controllers.interaction.generated import cholesky_factor, cholesky_solve_columns
from armctl.controllers.osc.tasks.rotation import rotation_error_sx
from armctl.dynamics import codegen
from armctl.dynamics.base import Dynamics
from armctl.dynamics.casadi_buffer import buffer_of, view
from armctl.dynamics.recursive import inverse_dynamics, joint_transforms, mass_matrix
from armctl.dynamics.symbolic_frames import frame_kinematics
from armctl.model.robot import RobotModel

_CODE_VERSION = 1
_NAME = "interaction_inner"
_log = logging.getLogger(__name__)


def sizes(n: int) -> tuple[int, int]:
    """(inputs, parameters): x = [q; q̇; x_c (4×4 row by row); v_c; a_c; q_n; h], p = [K_P; K_D; K_P,n; K_D,n]."""
    return 2 * n + 16 + 6 + 6 + n + 6, 2 * 36 + 2 * n * n


def inner_function(model: RobotModel, frame: str | None, kind: str, force_loop: bool = False) -> cs.Function:
    """The CasADi function of the module: (x, p) → [τ; e; p] (p the frame's position). With ``force_loop``, the
    force loop of :mod:`~armctl.controllers.interaction.force_loop` comes first: x also holds f_d (3), the integral
    ∫e_f before this step (3) and Δt (1), p holds P, P K_F, P K_I (3×3 each) and whether to compensate h (1, 0 or
    1), and the command is
    p_c = p_d + P K_F e_f + P K_I (∫e_f + e_f Δt), v_c = blockdiag(I − P, I) v_d (likewise a_c), e_f = P (f_d − f),
    f = h[:3]; the outputs are then [τ; e; e_f; ∫e_f after this step; x_F]."""
    n = model.n
    nx, npar = sizes(n)
    extra = (7, 28) if force_loop else (0, 0)
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
    tf = joint_transforms(model, q)
    pos, rot, jac, drift = frame_kinematics(model, q, qd, frame, tf)
    e = cs.vertcat(pose[:3, 3] - pos, rotation_error_sx(pose[:3, :3], rot))
    xdd = a_c + kp @ e + kd @ (v_c - jac @ qd)
    qdd0 = pkp @ (q_n - q) - pkd @ qd
    rhs = xdd - drift - jac @ qdd0
    if kind == "osc":
        low_m = cholesky_factor(mass_matrix(model, q, tf))
        mij = cholesky_solve_columns(low_m, jac.T)
        force = cholesky_solve_columns(cholesky_factor(jac @ mij), rhs)
        tau = jac.T @ force + inverse_dynamics(model, q, qd, qdd0, transforms=tf)
    else:
        qdd = jac.T @ cholesky_solve_columns(cholesky_factor(jac @ jac.T), rhs) + qdd0
        tau = inverse_dynamics(model, q, qd, qdd, transforms=tf)
    tau = tau + jac.T @ (h * par[npar + 27] if force_loop else h)  # force loop: the last parameter, compensate
    name = _NAME + ("_force" if force_loop else "")
    if force_loop:
        return cs.Function(name, [x, par], [cs.vertcat(tau, e, e_f, after, offset)])
    return cs.Function(name, [x, par], [cs.vertcat(tau, e, pos)])


def _tag(model: RobotModel, frame: str | None, kind: str) -> str:
    f = model.frame(frame)
    where = hashlib.sha256(f.placement.tobytes()).hexdigest()[:12]
    key = model.fingerprint(inertial=True, tool=False)
    return f"interaction-inner|{key}|v{_CODE_VERSION}|{f.name}:{f.joint}:{where}|{kind}"


class GeneratedInner:
    """The generated inner loop of the module, bound to buffers of its own (built or loaded on construction).

    Parameters
    ----------
    dynamics : Dynamics
        The controller's model (its cache folder too).
    frame : str or None
        The controlled frame.
    kind : {"osc", "computed_torque"}
        The law.
    force_loop : bool, optional
        With the force loop first (see :func:`inner_function`).
    """

    def __init__(self, dynamics: Dynamics, frame: str | None, kind: str, force_loop: bool = False) -> None:
        model = dynamics.model
        self.dynamics, self.frame, self.kind, self.force_loop = dynamics, frame, kind, force_loop
        cache_dir = dynamics.options.get("cache_dir")
        name = _NAME + ("_force" if force_loop else "")
        tag = _tag(model, frame, kind) + f"|force_loop={force_loop}"
        built = not codegen.is_cached([name], tag, cache_dir)
        t0 = time.perf_counter()
        fn = codegen.cached([name], tag, lambda: [inner_function(model, frame, kind, force_loop)], cache_dir)[name]
        if built:
            _log.warning(
                "armctl: generated and compiled the interaction controllers' inner loop (%s) for %r in %.1f s "
                "(cached in %s)",
                kind,
                model.name,
                time.perf_counter() - t0,
                codegen.cache_root(cache_dir),
            )
        self.n = n = model.n
        nx, npar = sizes(n)
        if force_loop:
            nx, npar = nx + 7, npar + 28
        self.inp, self.par, self.out = np.zeros(nx), np.zeros(npar), np.zeros(n + (15 if force_loop else 9))
        self._zero_wrench = np.zeros(6)
        buf, self._run = buffer_of(fn)
        buf.set_arg(0, view(self.inp))
        buf.set_arg(1, view(self.par))
        buf.set_res(0, view(self.out))
        self._buf = buf

    def __reduce__(self) -> tuple[Any, ...]:
        return (GeneratedInner, (self.dynamics, self.frame, self.kind, self.force_loop))

    def set_gains(
        self, kp: FloatArray, kd: FloatArray, posture_kp: FloatArray, posture_kd: FloatArray, *force: Any
    ) -> None:
        """K_P, K_D, K_P,n, K_D,n (and with the force loop, P, P K_F, P K_I, compensate) into the parameter buffer
        (CasADi reads a matrix column by column: the transposes)."""
        parts = [kp.T.ravel(), kd.T.ravel(), posture_kp.T.ravel(), posture_kd.T.ravel()]
        if self.force_loop:
            proj, pkf, pki, compensate = force
            parts += [proj.T.ravel(), pkf.T.ravel(), pki.T.ravel(), [1.0 if compensate else 0.0]]
        np.concatenate(parts, out=self.par)

    def run(
        self,
        q: FloatArray,
        qd: FloatArray,
        pose: FloatArray,
        twist: FloatArray,
        acceleration: FloatArray,
        posture: FloatArray,
        wrench: FloatArray | None,
    ) -> FloatArray:
        """[τ; e; p] (a new array): the torque, the frame error [m; rad] and the frame's position [m]."""
        h = self._zero_wrench if wrench is None else wrench
        np.concatenate((q, qd, pose.ravel(), twist, acceleration, posture, h), out=self.inp)
        self._run()
        return self.out.copy()

    def run_force(self, pieces: tuple[Any, ...]) -> FloatArray:
        """[τ; e; e_f; ∫e_f; x_F] (a new array) for the inputs (q, q̇, x_d, v_d, a_d, q_n, h, f_d, ∫e_f, [Δt]) of the
        force loop."""
        np.concatenate(pieces, out=self.inp)
        self._run()
        return self.out.copy()
