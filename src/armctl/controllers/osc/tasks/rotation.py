"""Rotation error: the rotation vector of R_ref Rᵀ (world axes), log: SO(3) → ℝ³.

    θ = arccos((tr E − 1)/2),   log E = θ / (2 sin θ) · (E₃₂ − E₂₃, E₁₃ − E₃₁, E₂₁ − E₁₂)

computed by Pinocchio's ``log3`` (which handles θ near 0 by a series and θ near π, where the formula above
loses accuracy, from the symmetric part of E); it returns an array, which the tasks' stacked vectors take without
a conversion.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from armctl._checks import FloatArray


def rotation_error(rot_ref: FloatArray, rot: FloatArray) -> FloatArray:
    """log(R_ref Rᵀ) [rad], (3,)."""
    return pin.log3(rot_ref.dot(rot.T))


def rotation_error_sx(rot_ref: Any, rot: Any) -> Any:
    """log(R_ref Rᵀ) in CasADi SX (3,), for generated code: the branches of Pinocchio's ``log3`` written out
    (``casadi.if_else``), so that the generated value is :func:`rotation_error`'s to rounding. E = R_ref Rᵀ is
    first made orthonormal (columns 1 and 2 normalised, then column 3 = c₁ × c₂ and column 1 = c₂ × c₃); with
    θ = arccos((tr E − 1)/2):

    * θ well inside (0, π): θ / sin θ · ½ (E₃₂ − E₂₃, E₁₃ − E₃₁, E₂₁ − E₁₂);
    * θ below ε^(1/3) (ε the machine epsilon): the series 1 + ‖a‖²/6 + 3‖a‖⁴/40 in place of θ / sin θ;
    * θ within ε^(1/3) of π, where that formula loses accuracy: θ times the axis from the symmetric part of E
      (its largest diagonal entry's column).
    """
    import casadi as cs

    eps = float(np.finfo(float).eps)
    prec = eps ** (1.0 / 3.0)
    e = rot_ref @ rot.T
    c0 = e[:, 0] / cs.norm_2(e[:, 0])
    c1 = e[:, 1] / cs.norm_2(e[:, 1])
    c2 = cs.cross(c0, c1)
    c0 = cs.cross(c1, c2)
    r = cs.horzcat(c0, c1, c2)
    tr = r[0, 0] + r[1, 1] + r[2, 2]
    cos_value = (tr - 1.0) / 2.0
    val = [2.0 * r[i, i] - tr + 1.0 for i in range(3)]
    thetas, axes = [], []
    for i0 in range(3):  # the axis from column i0 of the symmetric part (Pinocchio's compute_theta_axis)
        i1, i2 = (i0 + 1) % 3, (i0 + 2) % 3
        s = cs.sqrt(val[i0] + eps + eps * eps) * cs.if_else(r[i2, i1] >= r[i1, i2], 1.0, -1.0)
        axis: list[Any] = [None, None, None]
        axis[i0] = s / 2.0
        axis[i1] = 1.0 / (2.0 * s) * (r[i1, i0] + r[i0, i1])
        axis[i2] = 1.0 / (2.0 * s) * (r[i2, i0] + r[i0, i2])
        w = 1.0 / (2.0 * s) * (r[i2, i1] - r[i1, i2])
        vec = cs.vertcat(*axis)
        norm = cs.norm_2(vec)
        thetas.append(2.0 * cs.atan2(norm, w))
        axes.append(vec / norm)

    def largest(items: list[Any]) -> Any:
        return cs.if_else(
            val[0] >= val[1],
            cs.if_else(val[0] >= val[2], items[0], items[2]),
            cs.if_else(val[1] >= val[2], items[1], items[2]),
        )

    theta_singular = largest(thetas)
    axis_singular = largest(axes)
    acos_expansion = cs.sqrt(2.0 * (1.0 - cos_value) + eps * eps)
    theta = cs.if_else(
        tr <= 3.0 - prec,
        cs.if_else(tr >= -1.0 + prec, cs.acos(cos_value), np.pi - acos_expansion),
        acos_expansion,
    )
    anti = 0.5 * cs.vertcat(r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1])
    n2 = cs.dot(anti, anti)
    t = cs.if_else(theta >= prec, theta / cs.sin(theta), 1.0 + n2 / 6.0 + n2 * n2 * 3.0 / 40.0)
    return cs.if_else(cos_value >= -1.0 + prec, t * anti, theta_singular * axis_singular)
