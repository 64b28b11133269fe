"""`GeneratedImpedance`: the whole Cartesian impedance law as one call of generated C code, for the laws with a
constant damping and no inertia shaping (``CartesianImpedance(..., compile=...)``).

At (q, q̇), the target (p_d, R_d, v_d) and the posture q_n, one call of code generated with CasADi from the model
(its numbers built in) evaluates

    τ = Jᵀ F + C q̇ + g  [+ Nᵀ τ_n],     F = K e + D (v_d − J q̇) + Λ a_d

with the frame's kinematics from :mod:`armctl.dynamics.symbolic_frames`, C q̇ + g by Newton–Euler at q̈ = 0 and
M(q) by composite rigid bodies (:mod:`armctl.dynamics.recursive`), e as the OSC tasks (the rotation error by
:func:`~armctl.controllers.osc.tasks.rotation.rotation_error_sx`) and, with null-space stiffness,
Nᵀ τ_n = τ_n − Jᵀ (J M⁻¹ Jᵀ)⁻¹ J M⁻¹ τ_n by Cholesky factorisations written out. K, D, K_n and D_n are an input of
the code. The library is compiled once per model, frame and variant and cached on disk
(:mod:`armctl.codegen.library`); a singular configuration gives NaN, which the controller answers by its NumPy
path (and its named error).
"""

from __future__ import annotations

import hashlib
import itertools
from typing import Any

import casadi as cs
import numpy as np
from scipy.linalg import lapack

from armctl._checks import FloatArray
from armctl.codegen import library as codegen
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
from armctl.errors import InvalidParameterError
from armctl.model.robot import RobotModel

#: bumped when the generated code changes, so that stale cached libraries are not loaded
_CODE_VERSION = 6
_NAME = "cartesian_impedance"
#: the compiler's flags: the law runs at every control step (a slower build for faster code)
FLAGS = codegen.CFLAGS_FAST


def sizes(n: int, axes: int) -> tuple[int, int]:
    """(inputs, parameters): x = [q; q̇; target (the 4×4 pose row by row, or p_d); v_d; a_d; q_n],
    p = [K; D; K_n; D_n]."""
    return 2 * n + (16 if axes == 6 else 3) + 2 * axes + n, 2 * axes * axes + 2 * n * n


def lower_inverse(low: list[list[Any]]) -> Any:
    """L⁻¹ (SX, lower triangular) of the lower triangular L given as nested lists, by forward substitution."""
    n = len(low)
    inv = cs.SX.zeros(n, n)
    for c in range(n):
        y: list[Any] = [0.0] * n
        for i in range(c, n):
            s = 1.0 if i == c else 0.0
            for p in range(c, i):
                s = s - low[i][p] * y[p]
            y[i] = s / low[i][i]
            inv[i, c] = y[i]
    return inv


def input_views(inp: FloatArray, n: int, axes: int) -> tuple[FloatArray, ...]:
    """Views of the input buffer x (see :func:`sizes`) for q, q̇, the target (4×4 row by row, or (3,)), v_d, a_d
    and q_n, each of its piece's shape."""
    value = 16 if axes == 6 else 3
    bounds = np.cumsum([0, n, n, value, axes, axes, n])
    views = [inp[a:b] for a, b in itertools.pairwise(bounds)]
    if axes == 6:
        views[2] = views[2].reshape(4, 4)  # a view still: x is contiguous
    return tuple(views)


def impedance_function(model: RobotModel, frame: str | None, axes: int, null: bool, split: bool = False) -> cs.Function:
    """The CasADi function of the module: (x, p) → ([τ; e; F], s), s = Σ x + Σ [τ; e; F] (:func:`finiteness`: one
    number that tells whether the inputs and outputs are all finite). ``split``: the damping term is left out (D
    is not read) and the first output is [τ₀; e; F₀; ė; S; G; J] (column by column), for a damping computed from
    Λ outside: τ = τ₀ + Jᵀ D ė, F = F₀ + D ė, where Λ = G Gᵀ (G = L⁻ᵀ, L the Cholesky factor of Λ⁻¹ = J M⁻¹ Jᵀ) and
    S = G⁻¹ K G⁻ᵀ = Lᵀ K L: the double diagonalisation's matrices but for the eigendecomposition of S
    (:func:`damping_function`)."""
    n = model.n
    nx, npar = sizes(n, axes)
    x, par = cs.SX.sym("x", nx), cs.SX.sym("p", npar)
    q, qd = x[:n], x[n : 2 * n]
    k = 2 * n
    tf = joint_transforms(model, q)
    pos, rot, jac, _ = frame_kinematics(model, q, qd, frame, tf)
    if axes == 6:
        pose = cs.reshape(x[k : k + 16], 4, 4).T  # row by row
        e = cs.vertcat(pose[:3, 3] - pos, rotation_error_sx(pose[:3, :3], rot))
        k += 16
    else:
        e = x[k : k + 3] - pos
        k += 3
        jac = jac[:3, :]
    v_d, a_d, q_n = x[k : k + axes], x[k + axes : k + 2 * axes], x[k + 2 * axes : k + 2 * axes + n]
    m2 = axes * axes
    stiff, damp = cs.reshape(par[:m2], axes, axes), cs.reshape(par[m2 : 2 * m2], axes, axes)
    low_m = cholesky_factor(mass_matrix(model, q, tf))
    mij = cholesky_substitute(low_m, jac.T)  # M⁻¹ Jᵀ
    low_a = cholesky_factor(jac @ mij)  # J M⁻¹ Jᵀ = Λ⁻¹
    edot = v_d - jac @ qd
    force = stiff @ e + cholesky_substitute(low_a, a_d)  # K e + Λ a_d
    if not split:
        force = force + damp @ edot
    tau = jac.T @ force + inverse_dynamics(model, q, qd, cs.SX.zeros(n), transforms=tf)
    if null:
        kn = cs.reshape(par[2 * m2 : 2 * m2 + n * n], n, n)
        dn = cs.reshape(par[2 * m2 + n * n :], n, n)
        tau_n = kn @ (q_n - q) - dn @ qd
        z = cholesky_substitute(low_a, mij.T @ tau_n)  # Λ J M⁻¹ τ_n
        tau = tau + tau_n - jac.T @ z
    if split:  # Λ = G Gᵀ with G = L⁻ᵀ (J M⁻¹ Jᵀ = L Lᵀ), and S = G⁻¹ K G⁻ᵀ = Lᵀ K L
        low = cs.SX.zeros(axes, axes)
        for i in range(axes):
            for j in range(i + 1):
                low[i, j] = low_a[i][j]
        factor = lower_inverse(low_a).T
        out = cs.vertcat(tau, e, force, edot, cs.vec(low.T @ stiff @ low), cs.vec(factor), cs.vec(jac))
    else:
        out = cs.vertcat(tau, e, force)
    return cs.Function(_NAME, [x, par], [out, finiteness(x, out)])


def finiteness(x: Any, out: Any) -> Any:
    """Σ x + Σ out (SX): finite when every input and output entry is (NaN and inf propagate into a sum; a
    finite sum beyond the range of floats reads as not finite, which sends the caller to its careful path)."""
    return cs.sum1(x) + cs.sum1(out)


def damping_function(n: int, axes: int) -> cs.Function:
    """The second stage of the split law: y → [τ; e; F], y = [τ₀; e; F₀; ė; S; G; J] (the first stage's output)
    followed by U (column by column) and K₀ of S = U K₀ Uᵀ, and ζ. With d = 2 ζ K₀^½ and Q = G U (the modes:
    Q Qᵀ = Λ and Q K₀ Qᵀ = K, the double diagonalisation of :mod:`~armctl.controllers.interaction.gains` with the
    factor G in place of Λ's Cholesky factor), D = Q diag(d) Qᵀ, D ė = Q (d ⊙ (Qᵀ ė)), F = F₀ + D ė and
    τ = τ₀ + Jᵀ D ė."""
    m, mm = axes, axes * axes
    first = n + 3 * m + 2 * mm + m * n
    y = cs.SX.sym("y", first + mm + m + 1)
    tau0, e, f0, edot = y[:n], y[n : n + m], y[n + m : n + 2 * m], y[n + 2 * m : n + 3 * m]
    k = n + 3 * m + mm  # past S
    factor, jac = cs.reshape(y[k : k + mm], m, m), cs.reshape(y[k + mm : first], m, n)
    modes, omega2, zeta = cs.reshape(y[first : first + mm], m, m), y[first + mm : first + mm + m], y[-1]
    rates = 2.0 * zeta * cs.sqrt(cs.fmax(omega2, 0.0))
    d_edot = factor @ (modes @ (rates * (modes.T @ (factor.T @ edot))))
    return cs.Function(_NAME + "_damping", [y], [cs.vertcat(tau0 + jac.T @ d_edot, e, f0 + d_edot)])


def _tag(model: RobotModel, frame: str | None, axes: int, null: bool, split: bool) -> str:
    f = model.frame(frame)
    where = hashlib.sha256(f.placement.tobytes()).hexdigest()[:12]
    return (
        f"impedance|{model.fingerprint(inertial=True, tool=False)}|v{_CODE_VERSION}|{f.name}:{f.joint}:{where}"
        f"|axes={axes}|null={null}|split={split}"
    )


class GeneratedImpedance:
    """The generated law of the module for a frame of ``dynamics``' model, bound to buffers of its own. Builds
    or loads the library (the first time for a model and frame: seconds; then milliseconds). Not thread-safe.

    Parameters
    ----------
    dynamics : Dynamics
        The controller's model (its cache folder too).
    frame : str or None
        The controlled frame.
    axes : {3, 6}
        The law's axes.
    null : bool
        With the null-space term.
    split : bool, optional
        Without the damping term, and with Λ, J and ė as outputs (see :func:`impedance_function`).
    """

    def __init__(self, dynamics: Dynamics, frame: str | None, axes: int, null: bool, split: bool = False) -> None:
        model = dynamics.model
        self.dynamics, self.frame, self.axes, self.null, self.split = dynamics, frame, axes, null, split
        cache_dir = dynamics.options.get("cache_dir")
        tag = _tag(model, frame, axes, null, split)
        make = lambda: [impedance_function(model, frame, axes, null, split)]  # noqa: E731
        what = f"the Cartesian impedance law for {model.name!r}"  # logged with its time if it is built
        fn = codegen.cached([_NAME], tag, make, cache_dir, flags=FLAGS, what=what)[_NAME]
        nx, npar = sizes(model.n, axes)
        self.n = n = model.n
        m, mm = axes, axes * axes
        size = n + 2 * m + ((m + 2 * mm + m * n) if split else 0)
        self.inp, self.par = np.zeros(nx), np.zeros(npar)
        # split: the first stage writes into the second's input, [out; U; K₀; ζ]
        self.staged = np.zeros(size + mm + m + 1) if split else np.zeros(0)
        self.out = self.staged[:size] if split else np.zeros(size)
        buf, self._run = buffer_of(fn)
        buf.set_arg(0, view(self.inp))
        buf.set_arg(1, view(self.par))
        buf.set_res(0, view(self.out))
        if split:
            stage = codegen.cached(
                [_NAME + "_damping"],
                f"impedance-damping|n={n}|axes={m}|v{_CODE_VERSION}",
                lambda: [damping_function(n, m)],
                cache_dir,
                flags=FLAGS,
            )[_NAME + "_damping"]
            self.damped = np.zeros(n + 2 * m)  # [τ; e; F] of the second stage
            buf2, self._run_damping = buffer_of(stage)
            buf2.set_arg(0, view(self.staged))
            buf2.set_res(0, view(self.damped))
            self._buf2 = buf2
            k = n + 3 * m
            #: S (m×m) of the first stage's output, symmetric
            self.scaled = self.out[k : k + mm].reshape(m, m)
            #: where U goes (written as a matrix: column by column underneath) and K₀
            self.modes = self.staged[size : size + mm].reshape(m, m).T
            self.omega2 = self.staged[size + mm : size + mm + m]
        self.check = np.zeros(1)  # s of :func:`finiteness`, at the last call
        buf.set_res(1, view(self.check))
        self._buf = buf  # keeps the binding alive
        #: views of the input buffer for q, q̇, the target, v_d, a_d, q_n (:func:`input_views`)
        self.pieces = input_views(self.inp, model.n, axes)
        #: the target tuple whose values the input buffer holds (:meth:`load_target`)
        self.target: tuple[FloatArray, ...] | None = None
        #: one evaluation of the code on the buffers: ``out`` and ``check`` from ``inp`` and ``par``
        self.evaluate = self._run

    def __reduce__(self) -> tuple[Any, ...]:
        # rebuilt (the library loads from the cache: the buffers are this process's), with the gains
        args = (self.dynamics, self.frame, self.axes, self.null, self.split)
        return (GeneratedImpedance, args, {"par": self.par.copy(), "zeta": self.staged[-1:].copy()})

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.par[...] = state["par"]
        self.staged[-1:] = state["zeta"]

    def set_damping_ratio(self, zeta: float) -> None:
        """ζ of the split law's damping (:func:`damping_function`)."""
        self.staged[-1] = zeta

    def damp(self) -> FloatArray:
        """The split law's second stage after :attr:`evaluate` (finite): S = U K₀ Uᵀ by one symmetric
        eigendecomposition, then [τ; e; F] (a new array) with the damping (:func:`damping_function`)."""
        omega2, u, info = lapack.dsyev(self.scaled)
        if info:  # pragma: no cover - the symmetric eigensolver does not fail on finite input
            raise InvalidParameterError(f"no eigendecomposition of G⁻¹ K G⁻ᵀ (LAPACK info {info})", value=self.scaled)
        self.modes[...] = u
        self.omega2[...] = omega2
        self._run_damping()
        return self.damped.copy()

    def set_gains(
        self, stiffness: FloatArray, damping: FloatArray | None, null_k: FloatArray, null_d: FloatArray
    ) -> None:
        """K, D (None: zero, for ``split``), K_n, D_n into the parameter buffer (column by column: symmetric)."""
        parts = [stiffness.ravel(), np.zeros(stiffness.size) if damping is None else damping.ravel()]
        if self.null:
            parts += [null_k.ravel(), null_d.ravel()]
        else:
            parts += [np.zeros(self.par.size - 2 * stiffness.size)]
        np.concatenate(parts, out=self.par)

    def load_target(self, target: tuple[FloatArray, FloatArray, FloatArray]) -> None:
        """Write ``target`` (value (4×4 or (3,)), velocity, acceleration) into the input buffer and keep it as
        :attr:`target`: a caller that has the same tuple again (a constant target's, of read-only arrays) need not
        write it again; its identity is not reused while it is kept."""
        self.pieces[2][...], self.pieces[3][...], self.pieces[4][...] = target
        self.target = target

    def run(
        self, q: FloatArray, qd: FloatArray, target: tuple[FloatArray, FloatArray, FloatArray], posture: FloatArray
    ) -> FloatArray:
        """[τ; e; F] (a new array) at (q, q̇) for the ``target`` (value (4×4 or (3,)), velocity, acceleration)
        and the ``posture`` (read with the null-space term only): the inputs written into :attr:`pieces` (the
        target only if it is not :attr:`target`), then :attr:`evaluate`."""
        pieces = self.pieces
        pieces[0][...] = q  # into views of the input buffer: cheaper than one concatenation of six pieces
        pieces[1][...] = qd
        if target is not self.target:
            self.load_target(target)
        if self.null:  # q_n is read by the null-space term only
            pieces[5][...] = posture
        self._run()
        return self.out.copy()
