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

from armctl._checks import FLOAT, FloatArray
from armctl.errors import NonFiniteError, ShapeError
from armctl.model.parts import real_values
from armctl.model.robot import PARAMS_PER_JOINT


def _floats(x: ArrayLike, name: str) -> FloatArray:
    """``x`` as a float array: a float64 array as it is (the adaptive law's estimate, every control period),
    anything else through the real-number check (text, None, complex and booleans refused)."""
    a = np.asarray(x)
    return a if a.dtype == FLOAT else real_values(x, name)


def _pseudo_inertia_by_definition(p: FloatArray) -> FloatArray:
    """J of ten link parameters (..., 10) → (..., 4, 4), term by term as defined above."""
    m, h = p[..., 0], p[..., 1:4]
    ixx, ixy, iyy, ixz, iyz, izz = (p[..., k] for k in range(4, 10))
    i_bar = np.stack([np.stack([ixx, ixy, ixz], -1), np.stack([ixy, iyy, iyz], -1), np.stack([ixz, iyz, izz], -1)], -2)
    tr = np.trace(i_bar, axis1=-2, axis2=-1)[..., None, None]
    sigma = 0.5 * tr * np.eye(3) - i_bar
    top = np.concatenate([sigma, h[..., :, None]], -1)
    bottom = np.concatenate([h[..., None, :], m[..., None, None]], -1)
    return np.concatenate([top, bottom], -2)


def _parameters_by_definition(a: FloatArray) -> FloatArray:
    """The ten link parameters of pseudo-inertias (..., 4, 4): Ī = tr(Σ) 1 − Σ, term by term."""
    sigma, h, m = a[..., :3, :3], a[..., :3, 3], a[..., 3, 3]
    i_bar = np.trace(sigma, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) - sigma
    return np.concatenate(
        [
            m[..., None],
            h,
            np.stack(
                [
                    i_bar[..., 0, 0],
                    i_bar[..., 0, 1],
                    i_bar[..., 1, 1],
                    i_bar[..., 0, 2],
                    i_bar[..., 1, 2],
                    i_bar[..., 2, 2],
                ],
                -1,
            ),
        ],
        -1,
    )


# Both maps are linear: as matrices (vec J = row-major J), made once from the definitions, they cost one
# product instead of a dozen small array operations (the adaptive law's projection runs every control period)
_TO_J = _pseudo_inertia_by_definition(np.eye(10)).reshape(10, 16)  # vec J = p @ _TO_J
_FROM_J = _parameters_by_definition(np.eye(16).reshape(16, 4, 4))  # p = vec J @ _FROM_J


def pseudo_inertia(link10: ArrayLike) -> FloatArray:
    """4×4 pseudo-inertia of ten link parameters (m, m·c, Ixx, Ixy, Iyy, Ixz, Iyz, Izz); stacks over leading
    axes ((..., 10) → (..., 4, 4))."""
    p = _floats(link10, "link parameters")
    if p.shape[-1:] != (10,):
        raise ShapeError(f"link parameters must have 10 entries in the last axis, got shape {p.shape}", value=link10)
    return p.dot(_TO_J).reshape((*p.shape[:-1], 4, 4))


def from_pseudo_inertia(j: ArrayLike) -> FloatArray:
    """Inverse of :func:`pseudo_inertia`: Ī = tr(Σ) 1 − Σ (Σ, h, m read from the upper triangle and the last
    column of J, as the definition does)."""
    a = _floats(j, "pseudo-inertias")
    if a.shape[-2:] != (4, 4):
        raise ShapeError(f"pseudo-inertias must be 4×4 in the last two axes, got shape {a.shape}", value=j)
    return a.reshape((*a.shape[:-2], 16)).dot(_FROM_J)


def is_physical(pi: ArrayLike, tol: float = 1e-9) -> bool:
    """Whether every link of π (13 a joint) is physically consistent and rotor/friction terms are ≥ 0."""
    p = _floats(pi, "pi").reshape(-1, PARAMS_PER_JOINT)
    if not np.isfinite(p).all():
        return False
    ev = np.linalg.eigvalsh(pseudo_inertia(p[:, :10]))
    scale = max(float(np.abs(p[:, :10]).max()), 1.0)
    return bool(ev.min() >= -tol * scale and (p[:, 10:] >= -tol).all())


def project_physical(pi: ArrayLike, min_eig: float = 0.0) -> FloatArray:
    """π with each link's pseudo-inertia projected onto {J ⪰ min_eig·1} (nearest in Frobenius norm of J) and
    rotor inertia and friction clipped at 0. Raises NonFiniteError if π holds NaN or inf."""
    return projection(pi, min_eig)[0]


def projection(pi: ArrayLike, min_eig: float = 0.0, likely_inside: bool = True) -> tuple[FloatArray, bool]:
    """(:func:`project_physical` of π, whether it changed π). ``likely_inside``: first try a Cholesky factor of
    every J − min_eig·1, a third of the cost of the eigendecomposition, which is then skipped when π is
    already physical; pass False when π is likely outside or on the boundary of the set (where Cholesky fails
    and only adds its cost), e.g. when the previous estimate of an adaptive law needed projecting. The two
    agree to rounding: on the boundary one may accept a π the other moves by ~1e-15."""
    p = _floats(pi, "pi").reshape(-1, PARAMS_PER_JOINT).copy()
    if not np.isfinite(p).all():
        raise NonFiniteError(f"the parameters hold NaN or inf: {p.reshape(-1)!r}", value=pi)
    j = pseudo_inertia(p[:, :10])
    if likely_inside and (p[:, 10:] >= 0).all():
        try:
            np.linalg.cholesky(j - min_eig * np.eye(4) if min_eig else j)
            return p.reshape(-1), False
        except np.linalg.LinAlgError:  # not positive definite: on the boundary of the cone or outside
            pass
    ev, vec = np.linalg.eigh(j)
    if (ev >= min_eig).all() and (p[:, 10:] >= 0).all():
        return p.reshape(-1), False
    # V max(Λ, min_eig) Vᵀ per link
    p[:, :10] = from_pseudo_inertia((vec * np.maximum(ev, min_eig)[:, None, :]) @ vec.transpose(0, 2, 1))
    np.maximum(p[:, 10:], 0.0, out=p[:, 10:])
    return p.reshape(-1), True
