"""The Slotine–Li laws as one call of generated C code each: :class:`~armctl.controllers.PassivityBased` and the
step of :class:`~armctl.controllers.Adaptive` with ``compile="auto"`` (their default) or True.

With x = (q_d, q̇_d, q̈_d, q, q̇), the gains Λ, K_D (n × n) and the parameters π (13n, in the order of
:meth:`armctl.RobotModel.parameters`) inputs of the code, so that neither a gain change nor another payload needs
a new build:

    q̇_r = q̇_d − Λ(q − q_d),   q̈_r = q̈_d − Λ(q̇ − q̇_d),   s = q̇ − q̇_r,   a = q̇_r + s/2,   w = s/2
    Y(·) π = R(q, a, q̈_r; π) − h₀(q, w; π) + F_v q̇_r + F̄_c κ(q̇)       (M q̈_r + C(q, q̇) q̇_r + g + friction)

by the Newton–Euler recursion of :mod:`armctl.dynamics.recursive` with π as symbols (R: inverse dynamics,
h₀: its velocity terms without gravity, polarised as in :meth:`armctl.Dynamics.passivity_regressor`), and
κ(q̇) = sgn q̇ (1 + ρ sgn q̇) with the Coulomb asymmetry ratios ρ an input. The model is the one the
``"pinocchio"`` backend expresses (rotors as reflected inertia, no gyroscopic coupling).

* ``"passivity"``: (x, Λ, K_D, π, ρ) → [τ; Y π; K_D s; s] with τ = Y π − K_D s;
* ``"adaptive"``: (x, Λ, K_D, θ̂, Γ dt (13n, a diagonal Γ), θ₀, [on, σ, δ], ρ) → [τ; s], ν, θ̂⁺, Yᵀs with
  ν = 1 if on = 1 and ‖s‖ ≥ δ (else 0), θ̂⁺ = θ̂ − ν Γ dt (Yᵀs + σ(θ̂ − θ₀)) and τ = Y θ̂⁺ − K_D s. Yᵀs is the
  gradient of sᵀ Y π in π (reverse mode through the recursion: Y itself is never formed).

One library per model structure (:meth:`~armctl.RobotModel.fingerprint` without the inertial parameters),
compiled once and cached on disk (:mod:`armctl.codegen.library`); every payload, perturbed or friction variant
of an arm shares it. Λ and K_D are symbols, so every entry of τ depends on every entry of q and q̇ (through
K_D Λ): a NaN or inf in either reaches τ, and checking τ is enough (see :class:`~armctl.controllers.Controller`).
"""

from __future__ import annotations

import os
from typing import Any

import casadi as cs
import numpy as np

from armctl._checks import FloatArray
from armctl.codegen import library as codegen
from armctl.dynamics import recursive
from armctl.dynamics.base import Dynamics
from armctl.dynamics.casadi_buffer import buffer_of, view
from armctl.model.robot import PARAMS_PER_JOINT, RobotModel
from armctl.references import Reference

#: bumped when the generated code changes, so that stale cached libraries are not loaded
_CODE_VERSION = 3
NAMES = ("passivity", "adaptive")


def _model_torque(model: RobotModel, x: list[cs.SX], lam: cs.SX, kd: cs.SX, rho: cs.SX) -> tuple[Any, ...]:
    """(π ↦ Y π, s, K_D s) of the law's symbols (see the module), x = [q_d, q̇_d, q̈_d, q, q̇]."""
    n = model.n
    q_d, qd_d, qdd_d, q, qd = x
    qd_r = qd_d - cs.mtimes(lam, q - q_d)
    qdd_r = qdd_d - cs.mtimes(lam, qd - qd_d)
    s = qd - qd_r
    a, w = qd_r + 0.5 * s, 0.5 * s
    tf = recursive.joint_transforms(model, q)
    sign = cs.sign(qd)
    kappa = sign + rho * sign * sign

    def torque(pi: cs.SX) -> cs.SX:
        rigid = recursive.inverse_dynamics(model, q, a, qdd_r, transforms=tf, params=pi)
        rigid -= recursive.inverse_dynamics(model, q, w, cs.SX.zeros(n), gravity=False, transforms=tf, params=pi)
        k = PARAMS_PER_JOINT
        return rigid + cs.vertcat(*[pi[k * i + 11] * qd_r[i] + pi[k * i + 12] * kappa[i] for i in range(n)])

    return torque, s, cs.mtimes(kd, s)


def law_functions(model: RobotModel) -> list[cs.Function]:
    """The CasADi functions of :data:`NAMES` for ``model`` (see the module)."""
    n, p = model.n, PARAMS_PER_JOINT * model.n
    x, rho = [cs.SX.sym(name, n) for name in ("q_d", "qd_d", "qdd_d", "q", "qd")], cs.SX.sym("rho", n)
    lam, kd = cs.SX.sym("lam", n, n), cs.SX.sym("kd", n, n)
    pi, theta, rate, theta0 = (cs.SX.sym(name, p) for name in ("pi", "theta", "rate", "theta0"))
    scalars = cs.SX.sym("scalars", 3)  # on, σ, δ
    torque, s, kd_s = _model_torque(model, x, lam, kd, rho)
    model_pi = torque(pi)
    passivity = cs.Function(
        "passivity", [*x, lam, kd, pi, rho], [cs.densify(cs.vertcat(model_pi - kd_s, model_pi, kd_s, s))]
    )
    # Yᵀs: the gradient in π of sᵀ Y π (linear in π, so at any π: here the symbols, then set to zero)
    yts = cs.substitute(cs.gradient(cs.dot(s, model_pi), pi), pi, cs.SX.zeros(p))
    on, sigma, delta = scalars[0], scalars[1], scalars[2]
    nu = cs.if_else(on * (cs.dot(s, s) >= delta * delta), 1.0, 0.0)
    new = cs.if_else(nu, theta - rate * (yts + sigma * (theta - theta0)), theta)
    # common subexpressions merged: the kinematics of the gradient's recursion and of τ at θ̂⁺ are the same
    outputs = cs.cse([cs.densify(cs.vertcat(torque(new) - kd_s, s)), nu, cs.densify(new), cs.densify(yts)])
    adaptive = cs.Function("adaptive", [*x, lam, kd, theta, rate, theta0, scalars, rho], outputs)
    return [passivity, adaptive]


def library(model: RobotModel, cache_dir: str | os.PathLike[str] | None = None) -> dict[str, cs.Function]:
    """The compiled functions of :data:`NAMES` for ``model``'s structure, built if not cached yet."""
    return codegen.cached(
        list(NAMES),
        f"slotine-li|{model.fingerprint(inertial=False, tool=False)}|v{_CODE_VERSION}",
        lambda: law_functions(model),
        cache_dir,
        what=f"the Slotine–Li laws of {model.name!r}",
    )


def _bind(buf: Any, arrays: list[FloatArray], outs: list[FloatArray]) -> None:
    for k, arr in enumerate(arrays):
        buf.set_arg(k, view(arr))
    for k, arr in enumerate(outs):
        buf.set_res(k, view(arr))


class _Law:
    """What both laws bind: the inputs x = (q_d, q̇_d, q̈_d, q, q̇) (each its own array), the gains Λ and K_D
    (column by column, overwritten in place by :meth:`set_gains`), ρ; each instance its own buffers (one per
    controller and thread)."""

    def __init__(self, dynamics: Dynamics, lam: FloatArray, kd: FloatArray) -> None:
        n = dynamics.n
        self.n = n
        self.x = [np.zeros(n) for _ in range(5)]
        self.lam, self.kd = np.zeros(n * n), np.zeros(n * n)
        self.set_gains(lam, kd)
        self.rho = np.array(dynamics.kernel.friction.ratio, dtype=float)

    def set_gains(self, lam: FloatArray, kd: FloatArray) -> None:
        """Λ and K_D (n × n) into the bound arrays, column by column (CasADi's order)."""
        self.lam[...] = lam.ravel(order="F")
        self.kd[...] = kd.ravel(order="F")

    def _set_state(self, q: FloatArray, qd: FloatArray, ref: Reference) -> None:
        """The inputs x = (q_d, q̇_d, q̈_d, q, q̇) into their bound arrays (copies cost less than one
        concatenation)."""
        x = self.x
        x[0][...] = ref.q
        x[1][...] = ref.qd
        x[2][...] = ref.qdd
        x[3][...] = q
        x[4][...] = qd


class PassivityLaw(_Law):
    """τ = Y π − K_D s of :class:`~armctl.controllers.PassivityBased` in one call, with π the dynamics' own
    parameters; ``law(q, q̇, ref)`` → the rows τ, Y π, K_D s, s (4 × n, a new array)."""

    def __init__(self, functions: dict[str, cs.Function], dynamics: Dynamics, lam: FloatArray, kd: FloatArray):
        super().__init__(dynamics, lam, kd)
        self.pi = np.array(dynamics.parameters(), dtype=float)
        self.out = np.zeros((4, self.n))  # C order: the rows are the output's four blocks
        self.buf, self._run = buffer_of(functions["passivity"])  # CasADi keeps no reference to the arrays: we do
        _bind(self.buf, [*self.x, self.lam, self.kd, self.pi, self.rho], [self.out.reshape(-1)])

    def __call__(self, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        self._set_state(q, qd, ref)
        self._run()
        return self.out.copy()


class AdaptiveLaw(_Law):
    """The step of :class:`~armctl.controllers.Adaptive` in one call (see the module's ``"adaptive"``):
    ``law(q, q̇, ref, θ̂)`` → the rows τ, s (2 × n, a new array), and ν, θ̂⁺ and Yᵀs in the bound outputs ``nu``,
    ``new`` and ``yts`` (copy them to keep them), with the step's other inputs set by :meth:`set_step`; and
    :meth:`torque`, τ = Y θ − K_D s for a given θ (the laws' ``"passivity"`` function, after a projection or a
    composite step)."""

    def __init__(self, functions: dict[str, cs.Function], dynamics: Dynamics, lam: FloatArray, kd: FloatArray):
        super().__init__(dynamics, lam, kd)
        n, p = self.n, PARAMS_PER_JOINT * self.n
        self.theta, self.rate, self.theta0 = np.zeros(p), np.zeros(p), np.zeros(p)
        self.scalars = np.zeros(3)
        self.out, self.nu, self.new, self.yts = np.zeros((2, n)), np.zeros(1), np.zeros(p), np.zeros(p)
        self.buf, self._run = buffer_of(functions["adaptive"])
        args = [*self.x, self.lam, self.kd, self.theta, self.rate, self.theta0, self.scalars, self.rho]
        _bind(self.buf, args, [self.out.reshape(-1), self.nu, self.new, self.yts])
        self.pi, self.tau_out = np.zeros(p), np.zeros(4 * n)
        self.tau_buf, self._tau_run = buffer_of(functions["passivity"])
        _bind(self.tau_buf, [*self.x, self.lam, self.kd, self.pi, self.rho], [self.tau_out])
        self._rate_of: Any = None
        self._key: Any = None

    def set_step(self, rate: FloatArray | None, theta0: FloatArray, on: bool, sigma: float, delta: float) -> None:
        """The step's inputs: ``rate`` Γ dt (copied when it is another array than the last one given; None: kept),
        θ₀ (copied with σ ≠ 0 only: otherwise it does not enter), whether to update (``on``), σ and δ."""
        if rate is not None and rate is not self._rate_of:
            self.rate[...] = rate
            self._rate_of = rate
        if sigma:
            self.theta0[...] = theta0
        key = (on, sigma, delta)
        if key != self._key:
            self.scalars[...] = key
            self._key = key

    def __call__(self, q: FloatArray, qd: FloatArray, ref: Reference, theta: FloatArray) -> FloatArray:
        self._set_state(q, qd, ref)
        self.theta[...] = theta
        self._run()
        return self.out.copy()

    def torque(self, theta: FloatArray) -> FloatArray:
        """Y θ − K_D s at the state of the last call (a new array)."""
        self.pi[...] = theta
        self._tau_run()
        return self.tau_out[: self.n].copy()
