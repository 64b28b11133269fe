"""Rotation error: the rotation vector of R_ref Rᵀ (world axes), log: SO(3) → ℝ³.

    θ = arccos((tr E − 1)/2),   log E = θ / (2 sin θ) · (E₃₂ − E₂₃, E₁₃ − E₃₁, E₂₁ − E₁₂)

evaluated on Python floats (a 3×3 is too small for NumPy calls to pay off); near θ = 0 the factor is its
series ½ + θ²/12, near θ = π (where the formula loses accuracy) Pinocchio's ``log3`` takes over.
"""

from __future__ import annotations

import math

import pinocchio as pin

from armctl._checks import FloatArray

_NEAR_PI = math.pi - 1e-3


def rotation_error(rot_ref: FloatArray, rot: FloatArray) -> list[float]:
    """log(R_ref Rᵀ) [rad] as a list of 3 floats."""
    E = rot_ref.dot(rot.T)
    (a, b, c), (d, e, f), (g, h, i) = E.tolist()
    cos = 0.5 * (a + e + i - 1.0)
    cos = 1.0 if cos > 1.0 else -1.0 if cos < -1.0 else cos
    theta = math.acos(cos)
    if theta > _NEAR_PI:
        return pin.log3(E).tolist()  # type: ignore[no-any-return]
    k = 0.5 + theta * theta / 12.0 if theta < 1e-4 else 0.5 * theta / math.sin(theta)
    return [k * (h - f), k * (c - g), k * (d - b)]
