"""The regressor methods of :class:`~armctl.dynamics.base.Dynamics`: Y(q, q̇, q̈) with Y π = τ, the Slotine–Li
passivity regressor and torque (two evaluations by polarisation), the Coulomb column, the base parameters.

They are written once, on the primitives every backend provides (``_rigid_regressor``, ``_rigid_torque``,
``_friction``) and the input checks of the base class, which mixes them in.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FLOAT as _FLOAT
from armctl._checks import FloatArray

_SQRT_HALF = math.sqrt(0.5)


class RegressorMethods:
    """Mixed into :class:`~armctl.dynamics.base.Dynamics` (see the module)."""

    if TYPE_CHECKING:  # provided by Dynamics and its backends
        n: int
        _regressor_probe: FloatArray | None
        _has_asymmetry: bool
        _has_friction: bool
        _fc_ratio: FloatArray
        _fc_offset: FloatArray
        _zeros: FloatArray
        _halves: FloatArray
        _diag_idx: Any

        def _rigid_regressor(
            self, q: FloatArray, qd: FloatArray, qdd: FloatArray, friction: tuple[FloatArray, FloatArray] | None = None
        ) -> FloatArray: ...
        def _rigid_torque(self, q: FloatArray, qd: FloatArray, qdd: FloatArray) -> FloatArray: ...
        def _friction(self, qd: FloatArray, viscous_at: FloatArray | None = None) -> FloatArray: ...
        def _inputs(self, names: tuple[str, ...], *args: Any) -> tuple[FloatArray, ...]: ...
        def _finite(self, x: Any, name: str) -> FloatArray: ...
        def _checked4(self, a: Any, b: Any, c: Any, d: Any) -> bool: ...

    def regressor(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> FloatArray:
        """Y(q, q̇, q̈) (n × 13n) with Y π = inverse_dynamics(q, q̇, q̈), friction included.

        Columns per joint follow :data:`armctl.model.robot.PARAMETER_NAMES`; the friction columns are q̇_i and
        the Coulomb column κ_i(q̇_i) of :meth:`coulomb_column`: sgn(q̇_i) for a symmetric Coulomb friction, and
        for an asymmetric one (F_c⁺ ≠ F_c⁻, whose mean is π's Coulomb entry) F_c⁺/F̄_c for q̇_i > 0 and −F_c⁻/F̄_c
        for q̇_i < 0, so that Y π = τ exactly for every model. The Coulomb column then carries this model's ratio
        of the two levels, which an estimate of π (adaptation, identification) scales but does not change;
        identification that estimates the asymmetry as well uses sgn(q̇_i) and a column of its own
        (:mod:`armctl.dynamics.identification.problem`).
        """
        try:  # _inputs' fast path, inlined
            if (
                q.ndim == qd.ndim == qdd.ndim == 1  # type: ignore[union-attr]  (Pinocchio checks the lengths)
                and q.dtype is qd.dtype is qdd.dtype is _FLOAT
            ):  # type: ignore[union-attr]  (as in _call)
                probe = self._regressor_probe
                if probe is not None:  # the result shows any non-finite input
                    y = self._rigid_regressor(q, qd, qdd, (qd, qd))  # type: ignore[arg-type]
                    if math.isfinite(sum(probe.tolist())):
                        return y
                elif math.isfinite(sum(q.tolist()) + sum(qd.tolist()) + sum(qdd.tolist())):  # type: ignore[union-attr]
                    return self._rigid_regressor(q, qd, qdd, (qd, qd))  # type: ignore[arg-type]
        except Exception:  # not arrays, or a length Pinocchio refuses: the checks below name the input
            pass
        q, qd, qdd = self._inputs(("q", "qd", "qdd"), q, qd, qdd)
        return self._rigid_regressor(q, qd, qdd, (qd, qd))

    def base_parameters(self, samples: int | None = None, seed: int = 0) -> Any:
        """The base (identifiable) parameters of this model: a minimal set θ = K π with Y π = Y_b θ, found
        numerically (pivoted QR of the regressor stacked at random states); see
        :func:`armctl.dynamics.identification.find_base_parameters` for the options and the result."""
        from armctl.dynamics.identification import find_base_parameters

        return find_base_parameters(self, samples=samples, seed=seed)

    def coulomb_offset(self, qd: ArrayLike) -> FloatArray:
        """The asymmetric part of the Coulomb friction torque: δ = ½(F_c⁺ − F_c⁻) for every moving joint, 0 at
        rest (the friction's Coulomb part is F̄_c sgn q̇ + δ |sgn q̇|)."""
        return self._coulomb_offset(self._finite(qd, "qd"))

    def _coulomb_offset(self, qd: FloatArray) -> FloatArray:
        return self._fc_offset * np.abs(np.sign(qd))  # (cheaper than q̇ != 0)

    def coulomb_column(self, qd: ArrayLike) -> FloatArray:
        """κ(q̇) (n,): the regressor's Coulomb column entries, κ_i = sgn q̇_i (1 + ρ_i sgn q̇_i) with
        ρ_i = ½(F_c⁺ − F_c⁻)/F̄_c (0 without Coulomb friction), so F̄_c κ_i = F_c⁺ for q̇_i > 0, −F_c⁻ for
        q̇_i < 0, 0 at rest; sgn q̇_i for a symmetric friction."""
        return self._coulomb_column(self._finite(qd, "qd"))

    def _coulomb_column(self, qd: FloatArray, out: FloatArray | None = None) -> FloatArray:
        """κ(q̇), into ``out`` if given (the Pinocchio backend's strided workspace view)."""
        s = np.sign(qd, out=out)
        if self._has_asymmetry:
            s += self._fc_ratio * s * s
        return s

    def passivity_regressor(self, q: ArrayLike, qd: ArrayLike, qd_r: ArrayLike, qdd_r: ArrayLike) -> FloatArray:
        """Y(q, q̇, q̇_r, q̈_r) with Y π = M q̈_r + C(q, q̇) q̇_r + g + F_v q̇_r + τ_c(q̇) — the Slotine–Li form
        (τ_c: the Coulomb friction at the measured q̇, F_c⁺ or −F_c⁻; its column is :meth:`coulomb_column`'s).

        C(q, q̇) q̇_r is the symmetric bilinear form B(q̇, q̇_r) of the velocity terms h(v) = C(q, v) v (the
        Christoffel choice makes it symmetric), so by polarisation B(a, b) = ¼[h(a + b) − h(a − b)], and
        with R(q, v, a) = M a + h(v) + g:

            Y = 2 R(q, (q̇ + q̇_r)/√8, q̈_r/2) − R(q, (q̇ − q̇_r)/2, 0)

        — two regressor evaluations. (The Pinocchio backend uses the equivalent R(q, q̇_r + s/2, q̈_r) − h₀(s/2),
        s = q̇ − q̇_r, with h₀ evaluated on a gravity-free twin of the model: a single subtraction.) Both need
        only a = q̇_r + s/2 and w = s/2, since (q̇ + q̇_r)/√8 = a/√2 and (q̇ − q̇_r)/2 = w. Viscous
        friction is taken at q̇_r (it then adds F_v s to the closed loop's damping); Coulomb friction at the
        measured q̇.
        """
        probe = self._regressor_probe
        if probe is not None:  # the result shows any non-finite input: check only what it would not show
            try:
                if (
                    q.dtype is qd.dtype is qd_r.dtype is qdd_r.dtype is _FLOAT  # type: ignore[union-attr]
                    and q.ndim == qd.ndim == qd_r.ndim == qdd_r.ndim == 1  # type: ignore[union-attr]
                    and len(qd) == len(qd_r) == self.n
                ):  # (q̇ − q̇_r would broadcast)
                    y = self._passivity_regressor(q, qd, qd_r, qdd_r, *self._polarisation(qd, qd_r))
                    if math.isfinite(sum(probe.tolist())):
                        return y
            except Exception:  # as in regressor
                pass
        return self._passivity_call(self._passivity_regressor, q, qd, qd_r, qdd_r)

    def passivity_torque(self, q: ArrayLike, qd: ArrayLike, qd_r: ArrayLike, qdd_r: ArrayLike) -> FloatArray:
        """M q̈_r + C(q, q̇) q̇_r + g + F_v q̇_r + τ_c(q̇) (= passivity_regressor(...) @ π), from two
        inverse-dynamics evaluations by the same polarisation as :meth:`passivity_regressor`."""
        return self._passivity_call(self._passivity_torque, q, qd, qd_r, qdd_r)

    def _passivity_call(self, primitive: Any, q: Any, qd: Any, qd_r: Any, qdd_r: Any) -> FloatArray:
        """``primitive(q, q̇, q̇_r, q̈_r, a, w)`` on the inputs as given when they already are finite float64
        (n,) arrays (:meth:`_checked4`), else on checked copies (named errors)."""
        if not self._checked4(q, qd, qd_r, qdd_r):
            q, qd, qd_r, qdd_r = self._inputs(("q", "qd", "qd_r", "qdd_r"), q, qd, qd_r, qdd_r)
        return primitive(q, qd, qd_r, qdd_r, *self._polarisation(qd, qd_r))  # type: ignore[no-any-return]

    # The primitives behind the two methods above, on checked inputs and with the polarisation's velocities
    # a = q̇_r + s/2 and w = s/2, s = q̇ − q̇_r (the Slotine–Li controllers form them in the same product as the
    # rest of their law, armctl.controllers.passivity.sliding_map, and call these directly). copy=False may
    # return a workspace that the next regressor call overwrites.
    def _passivity_regressor(
        self,
        q: FloatArray,
        qd: FloatArray,
        qd_r: FloatArray,
        qdd_r: FloatArray,
        a: FloatArray,
        w: FloatArray,
        copy: bool = True,
    ) -> FloatArray:
        y = self._rigid_regressor(q, a * _SQRT_HALF, 0.5 * qdd_r)
        y *= 2.0
        y -= self._rigid_regressor(q, w, self._zeros)
        y.put(self._diag_idx[self.n :], np.concatenate((qd_r, self._coulomb_column(qd))))
        return y

    def _passivity_torque(
        self, q: FloatArray, qd: FloatArray, qd_r: FloatArray, qdd_r: FloatArray, a: FloatArray, w: FloatArray
    ) -> FloatArray:
        tau = self._rigid_torque(q, a * _SQRT_HALF, 0.5 * qdd_r)
        tau *= 2.0
        tau -= self._rigid_torque(q, w, self._zeros)
        return self._add_passivity_friction(tau, qd, qd_r)

    def _polarisation(self, qd: FloatArray, qd_r: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(a, w) = (q̇_r + s/2, s/2) with s = q̇ − q̇_r: the velocities of the passivity primitives."""
        w = qd - qd_r
        w *= self._halves  # an array factor: half the cost of a Python float's
        return qd_r + w, w

    def _add_passivity_friction(self, tau: FloatArray, qd: FloatArray, qd_r: FloatArray) -> FloatArray:
        """τ + F_v q̇_r + τ_c(q̇) (F_c⁺ or −F_c⁻), in place."""
        if self._has_friction:
            tau += self._friction(qd, qd_r)
        return tau
