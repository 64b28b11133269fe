"""The momentum observer's update as one call of generated C code (for ``MomentumObserver(..., compile=True)``).

One CasADi function of the stacked input x = [q; q̇; τ_{k−1}] and the observer's state s = [r; p; β; γ; h] gives
y = [r_k; p_k; β_k] and a flag e = max_j (|r_k,j| − θ_j) + 0·Σ r_k: the largest excess over the collision
thresholds θ, NaN when r_k is not finite (so that one comparison, ``not e <= 0``, tells both):

    p = M(q) q̇ = RNEA(q, 0, q̇) without gravity,      β = ∂T/∂q − g(q) − τ_f(q̇) = C(q, q̇)ᵀ q̇ − g(q) − τ_f(q̇)
    d = (h τ + ½ h (β + β_prev) − p + p_prev) / h,   r_k = γ r + (1 − γ) d

with T = ½ q̇ᵀ M(q) q̇ differentiated by reverse-mode AD (Cᵀ q̇ = ∂T/∂q since Ṁ = C + Cᵀ: the Lagrange equation
itself), the recursions of :mod:`armctl.dynamics.recursive` with the model's numbers built in (the model the
``"pinocchio"`` backend expresses), and the friction coefficients an input (friction variants share a library).
The library is built once per arm with the system's C compiler and cached on disk (:mod:`armctl.codegen.library`).

Non-finite inputs: every entry of r_k carries 0·Σx (the 0 an input the compiler cannot fold), so that a NaN or inf
anywhere in x reaches r_k even where the model does not depend on it (the Panda's M(q) does not on q₁), and checking
r_k is enough.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

import numpy as np

from armctl._checks import FloatArray
from armctl.codegen.policy import Fallback
from armctl.dynamics.kernel import Kernel
from armctl.errors import InvalidParameterError, NonFiniteError
from armctl.model.robot import RobotModel

#: bumped when the generated code changes
_CODE_VERSION = 5
#: what the observer runs where the code cannot be built
FALLBACK = Fallback(
    "the momentum observer's generated update", "the update on the dynamics' kernel", "several times slower"
)
NAME = "momentum_observer_step"


def symbolic_step(model: RobotModel) -> Any:
    """The CasADi function (x, s, c) → y of the module (c = [F_v; F̄_c; δ; θ; 0]: the friction's coefficients,
    the thresholds and the zero that carries non-finite inputs)."""
    import casadi as cs  # (not imported by ``import armctl``)

    from armctl.dynamics import recursive

    n = model.n
    x, s, c = cs.SX.sym("x", 3 * n), cs.SX.sym("s", 3 * n + n + 1), cs.SX.sym("c", 4 * n + 1)
    q, qd, tau = x[:n], x[n : 2 * n], x[2 * n :]
    r, p_prev, beta_prev, gamma, h = s[:n], s[n : 2 * n], s[2 * n : 3 * n], s[3 * n : 4 * n], s[4 * n]
    zeros = cs.SX.zeros(n)
    tf = recursive.joint_transforms(model, q)
    p = recursive.inverse_dynamics(model, q, zeros, qd, gravity=False, transforms=tf)
    g = recursive.inverse_dynamics(model, q, zeros, zeros, transforms=tf)
    sign = cs.sign(qd)
    friction = c[:n] * qd + c[n : 2 * n] * sign + c[2 * n : 3 * n] * cs.fabs(sign)
    beta = cs.gradient(0.5 * cs.dot(qd, p), q) - g - friction
    d = (h * tau + 0.5 * h * (beta + beta_prev) - p + p_prev) / h
    r_new = gamma * r + (1.0 - gamma) * d + c[4 * n] * cs.sum1(x)
    excess = cs.mmax(cs.fabs(r_new) - c[3 * n : 4 * n])
    flag = excess + c[4 * n] * cs.sum1(r_new)
    return cs.Function(NAME, [x, s, c], [cs.vertcat(r_new, p, beta), flag])


class CompiledStep:
    """The generated update bound to buffers of its own, double-buffered so that nothing is copied between steps:
    call :attr:`x` ← [q; q̇; τ], then ``runs[k]()``, which reads the state ``states[k]`` = [r; p; β; γ; h] and
    writes the new [r_k; p_k; β_k] into ``states[1 − k]``'s head and e into :attr:`flags`; the next step
    uses k ← 1 − k. γ and h are written into both states when the period changes.

    Parameters
    ----------
    kernel : Kernel
        The arm's kernel (its model and friction coefficients).
    friction : bool
        Subtract the model's friction.
    thresholds : ndarray or None
        θ [N·m] (None: infinite).
    cache_dir : path, optional
        Where compiled libraries are kept.

    Raises
    ------
    BackendError
        No C compiler (or it failed) and the library is not cached.
    """

    def __init__(
        self,
        kernel: Kernel,
        friction: bool,
        thresholds: FloatArray | None,
        cache_dir: str | os.PathLike[str] | None = None,
    ) -> None:
        from armctl.codegen import library
        from armctl.dynamics.casadi_buffer import buffer_of, view

        model = kernel.model
        self.n = n = model.n
        fn = library.cached(
            [NAME],
            f"momentum-observer|{model.fingerprint(inertial=True, tool=False)}|v{_CODE_VERSION}",
            lambda: [symbolic_step(model)],
            cache_dir,
            flags=library.CFLAGS_FAST,  # a control loop's hot path: a slower build for faster code
        )[NAME]
        ft = kernel.friction
        self.coeffs = c = np.zeros(4 * n + 1)
        if friction and ft.any:
            c[: 3 * n] = np.concatenate((ft.viscous, ft.coulomb_mean, ft.coulomb_offset))
        c[3 * n : 4 * n] = np.inf if thresholds is None else thresholds
        self.x = np.zeros(3 * n)
        self.flags = np.zeros(1)
        self.states = (np.zeros(4 * n + 1), np.zeros(4 * n + 1))
        self.heads = tuple(st[: 3 * n] for st in self.states)
        self.residuals = tuple(st[:n] for st in self.states)
        bufs, runs = [], []
        for k in (0, 1):
            buf, run = buffer_of(fn)
            for i, arr in enumerate((self.x, self.states[k], c)):
                buf.set_arg(i, view(arr))
            buf.set_res(0, view(self.heads[1 - k]))
            buf.set_res(1, view(self.flags))
            bufs.append(buf)
            runs.append(run)
        self.runs: tuple[Callable[[], None], ...] = tuple(runs)
        #: the input's pieces q, q̇, τ (views of :attr:`x`: three slice writes cost less than one concatenation)
        self.pieces = (self.x[:n], self.x[n : 2 * n], self.x[2 * n :])
        #: per side k: (its run, the residual it writes, the input's pieces, the flag array)
        self.sides = tuple((runs[k], self.residuals[1 - k], self.pieces, self.flags) for k in (0, 1))
        self._bufs = bufs  # CasADi keeps the arrays' addresses, not the arrays: they live as long as this object

    def set_period(self, gamma: FloatArray, h: float) -> None:
        """Write γ and h into both states."""
        n = self.n
        for st in self.states:
            st[3 * n : 4 * n] = gamma
            st[4 * n] = h


class CompiledUpdate:
    """The observer's update on :class:`CompiledStep` (a base of :class:`~armctl.controllers.MomentumObserver`,
    which sets ``_code`` and binds ``step`` to :meth:`_compiled_step` when it is compiled)."""

    n: int
    residual: FloatArray
    collision: Any
    _code: Any
    _side: int
    _t: float | None
    _h: float
    _gamma: FloatArray

    def _step_changed(self, h: float) -> None:  # pragma: no cover - the observer's
        raise NotImplementedError

    def _detect(self, t: float, r: FloatArray) -> None:  # pragma: no cover - the observer's
        raise NotImplementedError

    def _compiled_step(self, t: float, q: FloatArray, qd: FloatArray, tau: FloatArray) -> FloatArray:
        k = self._side
        run, out, (xq, xqd, xtau), flags = self._code.sides[k]
        xq[...] = q  # x ← [q; q̇; τ]
        xqd[...] = qd
        xtau[...] = tau
        try:
            h = t - self._t  # type: ignore[operator]  # None before the first sample
        except TypeError:  # None: the first sample, r = 0 and (p, β) from one call with γ = 1, h = 1
            code = self._code
            code.states[k][:] = 0.0
            code.set_period(np.ones(self.n), 1.0)
            run()
            self._t, self._h, self._side = t, -1.0, 1 - k
            return self.residual.copy()
        if abs(h - self._h) > 1e-9 * h:  # a new period (not the rounding of t_k = k·T)
            if not h > 0.0:
                raise InvalidParameterError(
                    f"observer updates must move forward in time: t = {t} after t = {self._t} (call reset() to "
                    f"restart)",
                    value=t,
                )
            self._step_changed(h)
            self._code.set_period(self._gamma, h)
        run()
        r = out.copy()
        if not flags.item() <= 0.0:  # a residual above its threshold, or NaN: a residual that is not finite
            if not np.isfinite(r).all():  # (the state stays that of the last good sample: side k)
                raise NonFiniteError(f"the observer's residual is not finite ({r}) at t = {t}", value=r)
            self._t, self._side, self.residual = t, 1 - k, r
            if self.collision is None:
                self._detect(t, r)
            return r
        self._t, self._side, self.residual = t, 1 - k, r
        return r
