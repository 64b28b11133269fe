"""`FrictionTerms`: the joint friction of a model as the dynamics evaluate it (no stiction: that is the simulator's).

    τ_f(q̇) = F_v q̇ + F̄_c sgn q̇ + δ |sgn q̇|,   F̄_c = ½(F_c⁺ + F_c⁻),  δ = ½(F_c⁺ − F_c⁻)

so that τ_f = F_v q̇ + F_c⁺ for q̇ > 0 and F_v q̇ − F_c⁻ for q̇ < 0, and only the viscous part at rest.
"""

from __future__ import annotations

import numpy as np

from armctl._checks import FloatArray
from armctl.model.robot import RobotModel


class FrictionTerms:
    """The constant friction coefficients of ``model``'s joints and the torques they give.

    Attributes
    ----------
    viscous : (n,) array
        F_v [N·m·s/rad or N·s/m].
    coulomb_mean, coulomb_offset : (n,) arrays
        F̄_c and δ [N·m or N].
    ratio : (n,) array
        ρ = δ / F̄_c (0 without Coulomb friction; |ρ| ≤ 1): the regressor's Coulomb column is
        κ(q̇) = sgn q̇ (1 + ρ sgn q̇), so that F̄_c κ is F_c⁺ or −F_c⁻.
    has_viscous, has_coulomb, has_asymmetry, any : bool
        Which terms are non-zero (``any``: viscous or Coulomb).
    """

    def __init__(self, model: RobotModel) -> None:
        fr = [j.friction for j in model.joints]
        self.n = model.n
        self.viscous = np.array([f.viscous for f in fr], dtype=float)
        pos = np.array([f.coulomb for f in fr], dtype=float)
        neg = np.array([f.coulomb_neg for f in fr], dtype=float)
        self.coulomb_mean = 0.5 * (pos + neg)
        self.coulomb_offset = 0.5 * (pos - neg)
        self.has_viscous = bool(self.viscous.any())
        self.has_coulomb = bool(self.coulomb_mean.any())
        self.has_asymmetry = bool(self.coulomb_offset.any())
        self.any = self.has_viscous or self.has_coulomb
        self.ratio = np.divide(
            self.coulomb_offset, self.coulomb_mean, out=np.zeros(self.n), where=self.coulomb_mean > 0
        )
        # τ_f = [diag F_v, diag F̄_c (, diag δ)]·[v; sgn q̇ (; |sgn q̇|)]: one product
        blocks = [np.diag(self.viscous), np.diag(self.coulomb_mean)]
        if self.has_asymmetry:
            blocks.append(np.diag(self.coulomb_offset))
        self._map = np.hstack(blocks)

    def torque(self, qd: FloatArray, viscous_at: FloatArray | None = None) -> FloatArray:
        """τ_f(q̇) [N·m], a new array; with ``viscous_at`` the viscous part is F_v·``viscous_at`` instead of F_v q̇
        (the Slotine–Li law takes it at q̇_r)."""
        v = qd if viscous_at is None else viscous_at
        if not self.has_coulomb:
            return self.viscous * v
        sign = np.sign(qd)
        if self.has_asymmetry:
            return self._map.dot(np.concatenate((v, sign, np.abs(sign))))
        return self._map.dot(np.concatenate((v, sign)))

    def coulomb_column(self, qd: FloatArray, out: FloatArray | None = None) -> FloatArray:
        """κ(q̇) = sgn q̇ (1 + ρ sgn q̇), into ``out`` if given."""
        s = np.sign(qd, out=out)
        if self.has_asymmetry:
            s += self.ratio * s * s
        return s

    def coulomb_asymmetry(self, qd: FloatArray) -> FloatArray:
        """δ |sgn q̇|: the asymmetric part of the Coulomb torque (0 at rest)."""
        return self.coulomb_offset * np.abs(np.sign(qd))
