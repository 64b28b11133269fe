"""The optimum of a QP on its equality rows alone, in NumPy: what the generated code of
:mod:`~armctl.controllers.osc.generated_optimum` computes, for the levels of a contact step that the NumPy path
solves (:mod:`~armctl.controllers.osc.contact_qp`).

For min ½ yᵀH y + gᵀy subject to A y = b alone (H positive definite), by the Schur complement of H:

    y₀ = −H⁻¹g,   W = H⁻¹Aᵀ,   λ = (A W)⁻¹(A y₀ − b),   y* = y₀ − W λ

(one Cholesky factorisation of H for y₀ and every column of W, one of A W). With no inequality row active, y*
is the QP's optimum exactly when the residuals A y* − b and H y* + g + Aᵀλ vanish and every inequality row
holds at y*: :func:`~armctl.controllers.osc.optimality.equality_optimum_ok` decides.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import lapack

from armctl._checks import FloatArray


def equality_optimum(
    H: FloatArray, g: FloatArray, A: FloatArray, b: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray] | None:
    """(y*, λ, A y* − b, H y* + g + Aᵀλ) of min ½ yᵀH y + gᵀy s.t. A y = b (module docstring), or None if H or
    A H⁻¹Aᵀ is not numerically positive definite (rows of A that depend on each other).

    Parameters
    ----------
    H : ndarray, shape (n, n)
        The Hessian, symmetric positive definite.
    g : ndarray, shape (n,)
        The gradient at y = 0.
    A : ndarray, shape (k, n)
        The equality rows (k = 0: the unconstrained minimum −H⁻¹g).
    b : ndarray, shape (k,)
        Their right-hand side.

    Returns
    -------
    tuple of ndarray, or None
        y* (n,), λ (k,), A y* − b (k,) and H y* + g + Aᵀλ (n,).
    """
    c, info = lapack.dpotrf(H, lower=1, clean=1)
    if info != 0:
        return None
    k = b.shape[0]
    if not k:  # the unconstrained minimum
        y, info = lapack.dpotrs(c, g, lower=1)
        np.negative(y, out=y)
        return y, np.zeros(0), np.zeros(0), H.dot(y) + g
    rhs = np.empty((H.shape[0], k + 1))
    rhs[:, 0] = g
    rhs[:, 1:] = A.T
    sol, info = lapack.dpotrs(c, rhs, lower=1)
    if info != 0:
        return None
    y = -sol[:, 0]
    w = sol[:, 1:]
    r = A.dot(y)
    r -= b
    _, lam, info = lapack.dposv(A.dot(w), r)
    if info != 0:
        return None
    y -= w.dot(lam)
    eq = A.dot(y)
    eq -= b
    stat = H.dot(y)
    stat += g
    stat += lam.dot(A)
    return y, lam, eq, stat
