"""Stiffness, damping and inertia matrices of the interaction controllers: their checks, and the damping that
makes a mass–spring–damper critically damped on every mode (double diagonalisation).

    Λ ë + D ė + K e = h,   Λ = Q Qᵀ,   K = Q K₀ Qᵀ (K₀ diagonal),   D = 2 ζ Q K₀^½ Qᵀ

With Λ = L Lᵀ (Cholesky) and L⁻¹ K L⁻ᵀ = U K₀ Uᵀ (a symmetric eigendecomposition), Q = L U; then each mode
q̃ = Qᵀ e obeys q̃̈ + 2 ζ ω q̃̇ + ω² q̃ = … with ω² the entries of K₀ (Albu-Schäffer, Ott, Frese and Hirzinger,
"Cartesian impedance control of redundant robots", ICRA 2003).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import lapack

from armctl._checks import FloatArray, real_array
from armctl.errors import InvalidParameterError, NonFiniteError, ShapeError

#: relative tolerance of the symmetry and semi-definiteness checks
SYMMETRY_TOL = 1e-9


def square(value: ArrayLike, sizes: tuple[int, ...], name: str, unit: str) -> FloatArray:
    """``value`` (a (m,) diagonal or an m×m matrix, m one of ``sizes``; a scalar if ``sizes`` has one entry) as
    an m×m float matrix, finite."""
    a = real_array(value, name)
    if a.ndim == 0 and len(sizes) == 1:
        a = np.full(sizes[0], float(a))
    if a.ndim == 0:
        raise ShapeError(
            f"{name} [{unit}] must be a ({sizes[0]},) or ({sizes[1]},) diagonal or a matrix of that size "
            f"(({sizes[0]},) rows: [translation; rotation]), not a scalar: got {value!r}",
            value=value,
        )
    if a.ndim == 1:
        a = np.diag(a)
    if a.ndim != 2 or a.shape[0] != a.shape[1] or a.shape[0] not in sizes:
        want = " or ".join(f"({m},) or ({m}, {m})" for m in sizes)
        raise ShapeError(f"{name} [{unit}] must be {want}, got shape {np.shape(value)}", value=value)
    if not np.isfinite(a).all():
        raise NonFiniteError(f"{name} holds NaN or inf: {value!r}", value=value)
    return np.array(a, dtype=float)


def symmetric_psd(value: ArrayLike, sizes: tuple[int, ...], name: str, unit: str, definite: bool = False) -> FloatArray:
    """``value`` as a symmetric positive semi-definite (``definite``: definite) matrix of one of ``sizes``;
    :class:`~armctl.errors.InvalidParameterError` naming the smallest eigenvalue otherwise."""
    a = square(value, sizes, name, unit)
    scale = max(float(np.abs(a).max()), 1e-300)
    if np.abs(a - a.T).max() > SYMMETRY_TOL * scale:
        raise InvalidParameterError(
            f"{name} [{unit}] must be symmetric; |{name} − {name}ᵀ| reaches {np.abs(a - a.T).max():.3g}: "
            f"give (A + Aᵀ)/2",
            value=value,
        )
    lo = float(np.linalg.eigvalsh(a)[0])
    if definite and not lo > 0.0:
        raise InvalidParameterError(
            f"{name} [{unit}] must be positive definite; its smallest eigenvalue is {lo:g}", value=value
        )
    if lo < -SYMMETRY_TOL * scale:
        what = "a negative damping" if "damping" in name else "not positive semi-definite"
        raise InvalidParameterError(
            f"{name} [{unit}] must be symmetric positive semi-definite ({what}: its smallest eigenvalue is "
            f"{lo:g}); give non-negative diagonal entries or a matrix Aᵀ A",
            value=value,
        )
    return a


def damping_ratio(value: float, name: str = "zeta") -> float:
    """ζ ≥ 0 as a float (a named error if negative or not finite)."""
    z = float(real_array(value, name))
    if not np.isfinite(z):
        raise NonFiniteError(f"{name} must be finite, got {value!r}", value=value)
    if z < 0.0:
        raise InvalidParameterError(f"{name} (a damping ratio) must be ≥ 0, got {value!r}", value=value)
    return z


def critical_damping(inertia: FloatArray, stiffness: FloatArray, zeta: float = 1.0) -> FloatArray:
    """The damping D = 2 ζ Q K₀^½ Qᵀ that gives each mode of Λ ë + D ė + K e = 0 the damping ratio ζ (see the
    module).

    Parameters
    ----------
    inertia : ndarray, shape (m, m)
        Λ, symmetric positive definite [kg, kg·m²].
    stiffness : ndarray, shape (m, m)
        K, symmetric positive semi-definite [N/m, N·m/rad].
    zeta : float, optional
        ζ ≥ 0; 1 (the default): critical damping.

    Returns
    -------
    ndarray, shape (m, m)
        D [N·s/m, N·m·s/rad], symmetric positive semi-definite.
    """
    low, info = lapack.dpotrf(inertia, lower=1, clean=1)  # Λ = L Lᵀ (LAPACK directly: NumPy's checks cost more)
    if info:
        raise InvalidParameterError(f"the inertia is not positive definite: {inertia}", value=inertia)
    inv, _ = lapack.dtrtri(low, lower=1)
    omega2, u, info = lapack.dsyev(inv @ stiffness @ inv.T)  # L⁻¹ K L⁻ᵀ = U K₀ Uᵀ
    if info:  # pragma: no cover - the symmetric eigensolver does not fail on finite input
        raise InvalidParameterError(f"no eigendecomposition of L⁻¹ K L⁻ᵀ (LAPACK info {info})", value=stiffness)
    qmat = low @ u
    return np.asarray((qmat * (2.0 * zeta * np.sqrt(np.maximum(omega2, 0.0)))) @ qmat.T)
