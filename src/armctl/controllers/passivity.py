"""Passivity-based tracking control (Slotine–Li)."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray
from armctl.codegen import Fallback, compile_mode
from armctl.controllers.base import Controller
from armctl.controllers.gains import GainSet, gain
from armctl.dynamics.base import Dynamics
from armctl.references import Reference

#: what ``compile="auto"`` runs where the Slotine–Li laws' generated code cannot be built
FALLBACK = Fallback(
    "the Slotine–Li laws' generated code", "the NumPy path (Pinocchio's terms)", "two to three times slower"
)


def sliding_map(lam: FloatArray, kd: FloatArray) -> FloatArray:
    """P (6n × 5n) with P·[q_d; q̇_d; q̈_d; q; q̇] = [q̇_r; q̈_r; s; K_D s; a; w] for the full gains Λ and K_D,
    where (Slotine–Li) q̃ = q − q_d, q̇_r = q̇_d − Λq̃, q̈_r = q̈_d − Λ(q̇ − q̇_d), s = q̇ − q̇_r, and a = q̇_r + s/2,
    w = s/2 are the velocities of the dynamics' passivity primitives: every vector of the law from one
    concatenation and one product (the term by term form takes ten array operations)."""
    n = lam.shape[0]
    eye, zero = np.eye(n), np.zeros((n, n))
    qd_r = np.hstack((lam, eye, zero, -lam, zero))
    s = np.hstack((-lam, -eye, zero, lam, eye))
    return np.vstack((qd_r, np.hstack((zero, lam, eye, zero, -lam)), s, kd.dot(s), qd_r + 0.5 * s, 0.5 * s))


def sliding(q: FloatArray, qd: FloatArray, ref: Reference, p: FloatArray) -> tuple[FloatArray, ...]:
    """(q̇_r, q̈_r, s, K_D s, a, w), the rows of one product with P = :func:`sliding_map`: contiguous (n,) views."""
    r = p.dot(np.concatenate((ref.q, ref.qd, ref.qdd, q, qd))).reshape(6, -1)
    return r[0], r[1], r[2], r[3], r[4], r[5]


class SlidingGains(GainSet):
    """Mixin of the Slotine–Li controllers: the gains Λ and K_D, and the map P = :func:`sliding_map` made from
    them (anew whenever one is reassigned); and the compile policy of their generated law
    (:mod:`armctl.controllers.slotine_li_generated`)."""

    n: int
    dynamics: Dynamics
    gain_names: ClassVar[dict[str, bool]] = {"lam": False, "kd": False}
    lam = gain("lam", "Λ (n×n); may be reassigned between calls (checked again).")
    kd = gain("kd", "K_D (n×n); may be reassigned between calls (checked again).")
    _lam_matrix: FloatArray  # (set_gains keeps the matrices, and their compact forms in _lam, _kd)
    _kd_matrix: FloatArray
    #: the compiled functions of the generated law (None: the NumPy path), and the law bound to buffers of this
    #: object's own for the kernel it was made for: made again at the next step on another kernel (another thread)
    _functions: Any = None
    _law: Any = None
    _law_for: Any = None

    def _derive(self) -> None:
        self._sliding = sliding_map(self._lam_matrix, self._kd_matrix)
        if self._law is not None:  # new gains into the bound law's own arrays, in place
            self._law.set_gains(self._lam_matrix, self._kd_matrix)

    def _start_compile(self, compile: bool | str) -> None:
        """Read ``compile`` and build or load the generated law under the compile policy (see ``compile``)."""
        self.compile = compile_mode(compile)
        self._functions = self._generated_functions()

    def _generated_functions(self) -> Any:
        mode = self.compile
        if mode is False:
            return None
        from armctl.dynamics.pinocchio_backend import PinocchioDynamics

        # "auto" where the generated model is the dynamics' own (Pinocchio's: rotors without gyroscopic coupling)
        if mode == "auto" and not isinstance(self.dynamics, PinocchioDynamics):
            return None
        from armctl.controllers import slotine_li_generated  # CasADi, imported on use

        dyn = self.dynamics
        make = lambda: slotine_li_generated.library(dyn.model, dyn.options.get("cache_dir"))  # noqa: E731
        return FALLBACK.attempt(make, mode, stacklevel=4)

    @property
    def uses_generated_code(self) -> bool:
        """Whether the law runs as generated C code (see ``compile``)."""
        return self._functions is not None

    def _bound_law(self, kind: str) -> Any:
        """The generated law ``kind`` (``"PassivityLaw"`` or ``"AdaptiveLaw"``) bound for this thread's kernel."""
        kernel = self.dynamics.kernel
        if kernel is not self._law_for:
            from armctl.controllers import slotine_li_generated

            make = getattr(slotine_li_generated, kind)
            self._law = make(self._functions, self.dynamics, self._lam_matrix, self._kd_matrix)
            self._law_for = kernel
        return self._law

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        for name in ("_functions", "_law", "_law_for"):  # compiled code of this process: loaded again
            state.pop(name, None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._functions = self._generated_functions()


class PassivityBased(SlidingGains, Controller):
    """τ = M(q) q̈_r + C(q, q̇) q̇_r + g(q) + F_v q̇_r + F_c sgn(q̇) − K_D s  (Slotine & Li 1987).

    The closed loop M ṡ + C s + (K_D + F_v) s = 0 is passive: with Ṁ − 2C skew-symmetric, V = ½ sᵀM s
    decreases as −sᵀ(K_D + F_v)s, so s → 0 and q̃ → 0 through the filter q̃̇ = −Λq̃ + s. Unlike computed torque
    it does not cancel the dynamics into a double integrator, which keeps it robust to model error at the
    same gains. The model terms come from two inverse-dynamics evaluations (``Dynamics.passivity_torque``); with
    ``compile`` (by default ``"auto"``) the whole law is one call of generated C code
    (:mod:`armctl.controllers.slotine_li_generated`), with the same τ.

    ``last_log`` (recorded by :func:`armctl.simulate` into ``res.logs``) holds the terms of τ = model − damping
    [N·m]: ``"model"`` M q̈_r + C q̇_r + g + F_v q̇_r + F_c sgn(q̇), ``"damping"`` K_D s, and the sliding variable
    ``"s"`` [rad/s]. The logged arrays are those the law computed, not copies: read them before the next call.

    Parameters
    ----------
    dynamics : Dynamics
        The controller's model.
    lam : array_like
        Λ [1/s]: a scalar, an (n,) diagonal or an n×n symmetric positive definite matrix.
    kd : array_like
        K_D [N·m·s/rad], likewise.
    compile : bool or "auto", optional
        Run the law as one call of generated C code: ``"auto"`` (default) on a ``"pinocchio"``-backed Dynamics
        wherever a C compiler builds it (once per arm structure, about a second, then cached on disk; without a
        compiler the NumPy path, with one :class:`~armctl.errors.PerformanceWarning`); True insists (on any
        backend: the generated model is the ``"pinocchio"`` backend's, rotors as reflected inertia); False keeps
        the NumPy path. Both give the same τ and logs. :attr:`uses_generated_code` tells which runs.

    Raises
    ------
    InvalidParameterError, ShapeError, NonFiniteError
        A gain that is not symmetric positive definite, of the wrong size, or not finite; ``compile`` not True,
        False or ``"auto"``.
    BackendError
        ``compile=True`` and the generated code cannot be built (no C compiler, a failing one).
    """

    dynamics: Dynamics  # given to __init__, never None

    def __init__(self, dynamics: Dynamics, lam: ArrayLike, kd: ArrayLike, *, compile: bool | str = "auto") -> None:
        super().__init__(dynamics)
        self.set_gains(lam=lam, kd=kd)
        self._start_compile(compile)

    #: stateless; a NaN/inf in q_j or q̇_j reaches s_j = q̃̇_j + (Λq̃)_j and τ through −K_D s (K_D ≻ 0)
    result_check = True

    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        if self._functions is not None:  # the rows τ, model, K_D s, s from one call of the generated law
            law = self._law if self._law_for is self.dynamics.kernel else self._bound_law("PassivityLaw")
            r = law(q, qd, ref)
            self.last_log = {"model": r[1], "damping": r[2], "s": r[3]}
            return r[0]
        qd_r, qdd_r, s, kd_s, a, w = sliding(q, qd, ref, self._sliding)
        model = self.dynamics.kernel.passivity_torque(q, qd, qd_r, qdd_r, a, w)
        self.last_log = {"model": model, "damping": kd_s, "s": s}
        return model - kd_s
