"""The regressor methods of :class:`~armctl.dynamics.base.Dynamics`: Y(q, q̇, q̈) with Y π = τ, the Slotine–Li
passivity regressor and torque (two evaluations by polarisation), the Coulomb column, the base parameters.

They check their inputs and evaluate on the kernel (:class:`~armctl.dynamics.kernel.Kernel`), whose
``regressor``, ``passivity_regressor`` and ``passivity_torque`` are the unchecked primitives.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from numpy.typing import ArrayLike

from armctl._checks import FloatArray, all_finite, float_vectors

if TYPE_CHECKING:
    from armctl.dynamics.friction_terms import FrictionTerms

_PASSIVITY_NAMES = ("q", "qd", "qd_r", "qdd_r")


class RegressorMethods:
    """Mixed into :class:`~armctl.dynamics.base.Dynamics` (see the module)."""

    if TYPE_CHECKING:  # provided by Dynamics
        n: int
        friction: FrictionTerms

        _local: Any  # .kernel: this thread's Kernel
        _propagates: bool
        _shape: tuple[int]

        def _vector(self, x: Any, name: str) -> FloatArray: ...
        def _evaluate(self, fn: Callable[..., Any], names: tuple[str, ...], *args: Any) -> Any: ...

    def regressor(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> FloatArray:
        """Y(q, q̇, q̈) (n × 13n) with Y π = inverse_dynamics(q, q̇, q̈), friction included.

        Columns per joint follow :data:`armctl.model.robot.PARAMETER_NAMES`; the friction columns are q̇_i and
        the Coulomb column κ_i(q̇_i) of :meth:`coulomb_column`: sgn(q̇_i) for a symmetric Coulomb friction, and
        for an asymmetric one (F_c⁺ ≠ F_c⁻, whose mean is π's Coulomb entry) F_c⁺/F̄_c for q̇_i > 0 and −F_c⁻/F̄_c
        for q̇_i < 0, so that Y π = τ exactly for every model. The Coulomb column then carries this model's ratio
        of the two levels, which an estimate of π (adaptation, identification) scales but does not change;
        identification that estimates the asymmetry as well uses sgn(q̇_i) and a column of its own
        (:mod:`armctl.dynamics.identification.problem`).

        Parameters
        ----------
        q, qd, qdd : (n,) array_like
            Joint positions, velocities and accelerations [rad, rad/s, rad/s²; m, m/s, m/s² for prismatic].

        Returns
        -------
        ndarray, shape (n, 13 n)
            The regressor Y.
        """
        k = self._local.kernel
        if self._propagates and float_vectors(q, qd, qdd):
            try:  # the kernel refuses a wrong length: then the careful path names it
                y = k.regressor(q, qd, qdd, (qd, qd))
                if all_finite(y):
                    return y
            except ValueError:
                pass
        return self._evaluate(lambda a, b, c: k.regressor(a, b, c, (b, b)), ("q", "qd", "qdd"), q, qd, qdd)

    def base_parameters(self, samples: int | None = None, seed: int = 0) -> Any:
        """The base (identifiable) parameters of this model: a minimal set θ = K π with Y π = Y_b θ, found
        numerically (pivoted QR of the regressor stacked at random states; see
        :func:`armctl.dynamics.identification.find_base_parameters`).

        Parameters
        ----------
        samples : int, optional
            The number of random states (default max(30, 4n)).
        seed : int, optional
            Their seed.

        Returns
        -------
        BaseParameters
        """
        from armctl.dynamics.identification import find_base_parameters

        return find_base_parameters(self, samples=samples, seed=seed)  # type: ignore[arg-type]  # self: a Dynamics

    def coulomb_offset(self, qd: ArrayLike) -> FloatArray:
        """The asymmetric part of the Coulomb friction torque: δ = ½(F_c⁺ − F_c⁻) for every moving joint, 0 at
        rest (the friction's Coulomb part is F̄_c sgn q̇ + δ |sgn q̇|).

        Parameters
        ----------
        qd : (n,) array_like
            As for :meth:`friction_torque`.

        Returns
        -------
        ndarray, shape (n,)
            δ [N·m or N].
        """
        return self.friction.coulomb_asymmetry(self._vector(qd, "qd"))

    def coulomb_column(self, qd: ArrayLike) -> FloatArray:
        """κ(q̇) (n,): the regressor's Coulomb column entries, κ_i = sgn q̇_i (1 + ρ_i sgn q̇_i) with
        ρ_i = ½(F_c⁺ − F_c⁻)/F̄_c (0 without Coulomb friction), so F̄_c κ_i = F_c⁺ for q̇_i > 0, −F_c⁻ for
        q̇_i < 0, 0 at rest; sgn q̇_i for a symmetric friction.

        Parameters
        ----------
        qd : (n,) array_like
            As for :meth:`friction_torque`.

        Returns
        -------
        ndarray, shape (n,)
            κ(q̇).
        """
        return self.friction.coulomb_column(self._vector(qd, "qd"))

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

        Parameters
        ----------
        q, qd : (n,) array_like
            Joint positions [rad or m] and velocities [rad/s or m/s].
        qd_r, qdd_r : (n,) array_like
            Reference velocity q̇_r and acceleration q̈_r [rad/s, rad/s²].

        Returns
        -------
        ndarray, shape (n, 13 n)
            Y(q, q̇, q̇_r, q̈_r).
        """
        k = self._local.kernel

        def primitive(q: FloatArray, qd: FloatArray, qd_r: FloatArray, qdd_r: FloatArray) -> FloatArray:
            return k.passivity_regressor(q, qd, qd_r, qdd_r, *k.polarisation(qd, qd_r))

        # q̇ − q̇_r would broadcast: their lengths are compared here, the kernel checks the others
        if self._propagates and float_vectors(q, qd, qd_r, qdd_r) and len(qd) == len(qd_r) == self.n:  # type: ignore[arg-type]  # vectors
            try:
                y = primitive(q, qd, qd_r, qdd_r)  # type: ignore[arg-type]  # float_vectors checked them
            except ValueError:
                y = None
            if y is not None and all_finite(y):
                return y
        return self._evaluate(primitive, _PASSIVITY_NAMES, q, qd, qd_r, qdd_r)

    def passivity_torque(self, q: ArrayLike, qd: ArrayLike, qd_r: ArrayLike, qdd_r: ArrayLike) -> FloatArray:
        """M q̈_r + C(q, q̇) q̇_r + g + F_v q̇_r + τ_c(q̇) (= passivity_regressor(...) @ π) [N·m or N], from two
        inverse-dynamics evaluations by the same polarisation as :meth:`passivity_regressor`.

        Parameters
        ----------
        q, qd, qd_r, qdd_r : (n,) array_like
            As for :meth:`passivity_regressor`.

        Returns
        -------
        ndarray, shape (n,)
            [N·m or N].
        """
        k = self._local.kernel

        def primitive(q: FloatArray, qd: FloatArray, qd_r: FloatArray, qdd_r: FloatArray) -> FloatArray:
            return k.passivity_torque(q, qd, qd_r, qdd_r, *k.polarisation(qd, qd_r))

        return self._evaluate(primitive, _PASSIVITY_NAMES, q, qd, qd_r, qdd_r)
