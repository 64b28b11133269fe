"""Physical consistency of a link's ten inertial parameters, through its pseudo-inertia matrix.

For a body with density ρ, the pseudo-inertia (Wensing, Kim & Slotine 2017)

    J = ∫ [x; 1][x; 1]ᵀ ρ dV = [ Σ  h ]      Σ = ½ tr(I_O) 𝟙 − I_O   (second moment about the origin)
                               [ hᵀ m ]      h = m c,   I_O = tr(Σ) 𝟙 − Σ

is linear in the parameters, and J ⪰ 0 is exactly the condition for (m, h, I_O) to come from some body:
m ≥ 0 and the inertia about the centre of mass positive semi-definite with principal moments satisfying the
triangle inequalities (J ⪰ 0 ⇔ Σ_C = Σ − h hᵀ/m ⪰ 0, and Σ_C ⪰ 0 ⇔ I_C's triangle inequalities).

Positive semi-definite J are parametrised without constraints by a Cholesky-type factor: J = U Uᵀ with U
upper triangular (4×4, ten entries x). Every x gives a body, every body (J ⪰ 0, singular ones included,
e.g. a massless link) has such an x, and m = U₃₃², h = U₃₃ U[:3, 3]. The map is not one to one (signs), but
for a convex cost over J ⪰ 0 a factorisation of full size has no spurious local minima (Burer & Monteiro
2005), which is what the consistent estimate relies on.
"""

from __future__ import annotations

import numpy as np

from armctl._checks import FloatArray
from armctl.model.consistency import from_pseudo_inertia, pseudo_inertia

# positions in U (4×4, upper triangular) of x[0..9]
_ENTRIES = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2), (0, 3), (1, 3), (2, 3), (3, 3))
_ROWS = np.array([r for r, _ in _ENTRIES])
_COLS = np.array([c for _, c in _ENTRIES])


def _linear_map() -> FloatArray:
    """A (10 × 16) with p = A vec(J) (row-major vec) for symmetric J."""
    a = np.zeros((10, 16))
    for k in range(16):
        e = np.zeros(16)
        e[k] = 1.0
        j = e.reshape(4, 4)
        a[:, k] = from_pseudo_inertia(0.5 * (j + j.T))
    return a


_A = _linear_map()


def parameters_from_factor(x: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(p, ∂p/∂x) for L links at once: x (L, 10) → the parameters (L, 10) of J = U Uᵀ and their Jacobians
    (L, 10, 10). With ∂J/∂U_rc = E_rc Uᵀ + U E_cr."""
    x = np.atleast_2d(x)
    u = np.zeros((x.shape[0], 4, 4))
    u[:, _ROWS, _COLS] = x
    j = u @ u.transpose(0, 2, 1)
    p = j.reshape(-1, 16) @ _A.T
    dj = np.zeros((x.shape[0], 10, 4, 4))
    for k, (r, c) in enumerate(_ENTRIES):
        dj[:, k, r, :] = u[:, :, c]  # (E_rc Uᵀ)[r, b] = U[b, c]
    dj = dj + dj.transpose(0, 1, 3, 2)
    jac = (dj.reshape(x.shape[0], 10, 16) @ _A.T).transpose(0, 2, 1)
    return p, jac


def factor_of(p: FloatArray, floor: float = 1e-9) -> FloatArray:
    """x (10,) with J(x) the positive semi-definite matrix nearest J(p), its eigenvalues raised to at least
    ``floor``·max(tr J, 1e-3) so that the factor is unique (the start of a consistent fit from a possibly
    inconsistent π)."""
    j = pseudo_inertia(np.asarray(p, dtype=float))
    w, v = np.linalg.eigh(0.5 * (j + j.T))
    w = np.maximum(w, floor * max(float(np.trace(j)), 1e-3))
    j = (v * w) @ v.T
    flip = np.eye(4)[::-1]
    u = flip @ np.linalg.cholesky(flip @ j @ flip) @ flip  # upper triangular, J = U Uᵀ
    return u[_ROWS, _COLS]


def is_consistent(p: FloatArray, tol: float = 1e-9) -> bool:
    """True if one link's ten parameters come from a body: J ⪰ −tol·max(|J|)."""
    j = pseudo_inertia(np.asarray(p, dtype=float))
    return bool(np.linalg.eigvalsh(j)[0] >= -tol * max(float(np.abs(j).max()), 1e-300))
