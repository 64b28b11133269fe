"""Rotation error: the rotation vector of R_ref Rᵀ (world axes), log: SO(3) → ℝ³.

    θ = arccos((tr E − 1)/2),   log E = θ / (2 sin θ) · (E₃₂ − E₂₃, E₁₃ − E₃₁, E₂₁ − E₁₂)

computed by Pinocchio's ``log3`` (which handles θ near 0 by a series and θ near π, where the formula above
loses accuracy, from the symmetric part of E). Measured cheaper than the formula on Python floats, and it
returns an array, which the tasks' stacked vectors take without a conversion.
"""

from __future__ import annotations

import pinocchio as pin

from armctl._checks import FloatArray


def rotation_error(rot_ref: FloatArray, rot: FloatArray) -> FloatArray:
    """log(R_ref Rᵀ) [rad], (3,)."""
    return pin.log3(rot_ref.dot(rot.T))
