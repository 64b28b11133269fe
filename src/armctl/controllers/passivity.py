"""Passivity-based tracking control (Slotine–Li)."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray
from armctl.controllers.base import Controller
from armctl.controllers.gains import GainSet, gain
from armctl.dynamics.base import Dynamics
from armctl.references import Reference


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
    them (anew whenever one is reassigned)."""

    n: int
    gain_names: ClassVar[dict[str, bool]] = {"lam": False, "kd": False}
    lam = gain("lam", "Λ (n×n); may be reassigned between calls (checked again).")
    kd = gain("kd", "K_D (n×n); may be reassigned between calls (checked again).")
    _lam_matrix: FloatArray  # (set_gains keeps the matrices, and their compact forms in _lam, _kd)
    _kd_matrix: FloatArray

    def _derive(self) -> None:
        self._sliding = sliding_map(self._lam_matrix, self._kd_matrix)


class PassivityBased(SlidingGains, Controller):
    """τ = M(q) q̈_r + C(q, q̇) q̇_r + g(q) + F_v q̇_r + F_c sgn(q̇) − K_D s  (Slotine & Li 1987).

    The closed loop M ṡ + C s + (K_D + F_v) s = 0 is passive: with Ṁ − 2C skew-symmetric, V = ½ sᵀM s
    decreases as −sᵀ(K_D + F_v)s, so s → 0 and q̃ → 0 through the filter q̃̇ = −Λq̃ + s. Unlike computed torque
    it does not cancel the dynamics into a double integrator, which keeps it robust to model error at the
    same gains. The model terms come from two inverse-dynamics evaluations (``Dynamics.passivity_torque``).

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

    Raises
    ------
    InvalidParameterError, ShapeError, NonFiniteError
        A gain that is not symmetric positive definite, of the wrong size, or not finite.
    """

    dynamics: Dynamics  # given to __init__, never None

    def __init__(self, dynamics: Dynamics, lam: ArrayLike, kd: ArrayLike) -> None:
        super().__init__(dynamics)
        self.set_gains(lam=lam, kd=kd)

    #: stateless; a NaN/inf in q_j or q̇_j reaches s_j = q̃̇_j + (Λq̃)_j and τ through −K_D s (K_D ≻ 0)
    result_check = True

    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        qd_r, qdd_r, s, kd_s, a, w = sliding(q, qd, ref, self._sliding)
        model = self.dynamics.kernel.passivity_torque(q, qd, qd_r, qdd_r, a, w)
        self.last_log = {"model": model, "damping": kd_s, "s": s}
        return model - kd_s
