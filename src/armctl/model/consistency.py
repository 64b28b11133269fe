"""Physical consistency of dynamic parameters, through the pseudo-inertia matrix.

For one link with parameters (m, h = m·c, Ī the inertia about the joint-frame origin), the pseudo-inertia

    J = [[Σ, h], [hᵀ, m]],   Σ = ½ tr(Ī) 1 − Ī   (= ∫ r rᵀ dm)

is positive semi-definite exactly when some non-negative mass density has these parameters: m ≥ 0 and the
inertia about the centre of mass satisfies the triangle inequalities (Wensing, Kim & Slotine, RA-L 2017).
The set is a convex cone in π, so projecting J onto the PSD cone keeps estimates physical.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray
from armctl.model.robot import PARAMS_PER_JOINT


def pseudo_inertia(link10: ArrayLike) -> FloatArray:
    """4×4 pseudo-inertia of ten link parameters (m, m·c, Ixx, Ixy, Iyy, Ixz, Iyz, Izz); stacks over leading
    axes ((..., 10) → (..., 4, 4))."""
    p = np.asarray(link10, dtype=float)
    m, h = p[..., 0], p[..., 1:4]
    ixx, ixy, iyy, ixz, iyz, izz = (p[..., k] for k in range(4, 10))
    i_bar = np.stack([np.stack([ixx, ixy, ixz], -1), np.stack([ixy, iyy, iyz], -1),
                      np.stack([ixz, iyz, izz], -1)], -2)
    tr = np.trace(i_bar, axis1=-2, axis2=-1)[..., None, None]
    sigma = 0.5 * tr * np.eye(3) - i_bar
    top = np.concatenate([sigma, h[..., :, None]], -1)
    bottom = np.concatenate([h[..., None, :], m[..., None, None]], -1)
    return np.concatenate([top, bottom], -2)


def from_pseudo_inertia(j: ArrayLike) -> FloatArray:
    """Inverse of :func:`pseudo_inertia`: Ī = tr(Σ) 1 − Σ."""
    a = np.asarray(j, dtype=float)
    sigma, h, m = a[..., :3, :3], a[..., :3, 3], a[..., 3, 3]
    i_bar = np.trace(sigma, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) - sigma
    return np.concatenate([m[..., None], h, np.stack([i_bar[..., 0, 0], i_bar[..., 0, 1], i_bar[..., 1, 1],
                                                      i_bar[..., 0, 2], i_bar[..., 1, 2], i_bar[..., 2, 2]], -1)],
                          -1)


def is_physical(pi: ArrayLike, tol: float = 1e-9) -> bool:
    """Whether every link of π (13 a joint) is physically consistent and rotor/friction terms are ≥ 0."""
    p = np.asarray(pi, dtype=float).reshape(-1, PARAMS_PER_JOINT)
    ev = np.linalg.eigvalsh(pseudo_inertia(p[:, :10]))
    scale = max(float(np.abs(p[:, :10]).max()), 1.0)
    return bool(ev.min() >= -tol * scale and (p[:, 10:] >= -tol).all())


def project_physical(pi: ArrayLike, min_eig: float = 0.0) -> FloatArray:
    """π with each link's pseudo-inertia projected onto {J ⪰ min_eig·1} (nearest in Frobenius norm of J) and
    rotor inertia and friction clipped at 0."""
    p = np.asarray(pi, dtype=float).reshape(-1, PARAMS_PER_JOINT).copy()
    ev, vec = np.linalg.eigh(pseudo_inertia(p[:, :10]))
    if (ev >= min_eig).all() and (p[:, 10:] >= 0).all():
        return p.reshape(-1)
    clipped = np.maximum(ev, min_eig)
    p[:, :10] = from_pseudo_inertia(np.einsum("kij,kj,klj->kil", vec, clipped, vec))
    np.maximum(p[:, 10:], 0.0, out=p[:, 10:])
    return p.reshape(-1)
