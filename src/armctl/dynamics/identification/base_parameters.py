"""Base (identifiable) parameters of an arm, found numerically.

Not every entry of π (13 per joint) changes the joint torques: some columns of the regressor Y are zero
(a link's mass on a joint that turns about the vertical) and others are linear combinations of the rest
(a link's inertia about its joint axis lumps with the next link's mass times the squared link length). The
*base parameters* θ are a minimal set of linear combinations of π with

    Y(q, q̇, q̈) π = Y_b(q, q̇, q̈) θ,    θ = K π = π_b + β π_d    for every (q, q̇, q̈),

where Y_b = Y[:, b] are the independent columns, π_b and π_d the parameters of the independent and
dependent columns, and β the constant matrix with Y[:, d] = Y_b β.

They are found from the regressor stacked at random states, W = [Y(x_1); …; Y(x_S)] (Gautier 1990): its
numerical rank r is that of QR decomposition with column pivoting, W = Q R Pᵀ (the |R_kk| above
``tol·|R_00|``); the independent columns are then taken greedily in π's order, each kept if it is independent
of those kept before it (the textbook lumping: a link's inertia about its axis keeps its name and absorbs the
next link's mass times the squared length), falling back to the first r pivoted columns if that does not give
r of them; β is the least-squares solution of W_b β = W_d.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import cast

import numpy as np
import scipy.linalg

from armctl._checks import FloatArray, readonly, readonly_fields, scalar, whole_number
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError
from armctl.model.robot import PARAMS_PER_JOINT

_BETA_ZERO = 1e-10  # entries of β below this (relative to the largest) are round-off
#: allowed range of the rank tolerance (relative to the largest pivot |R_00|). The numerical rank sits in a wide
#: gap: round-off pivots are ~1e-16, genuine ones ≥ ~3e-2 for the planar 2R, Puma 560 and Panda (SI units). Below
#: 1e-14 round-off would count as independent; above 1e-3, identifiable parameters with small columns (a short
#: wrist link) would be dropped silently, leaving base parameters that no longer reproduce the torques.
TOL_RANGE = (1e-14, 1e-3)


def identification_regressor(dynamics: Dynamics, q: FloatArray, qd: FloatArray, qdd: FloatArray) -> FloatArray:
    """``dynamics.regressor`` with sgn(q̇_i) as every joint's Coulomb column. Identification estimates the
    mean Coulomb level and (with offsets, see :mod:`~armctl.dynamics.identification.problem`) the asymmetry as
    unknowns of their own, so it must not take the ratio of the two levels from the model, which the
    regressor's Coulomb column of an asymmetric friction carries (:meth:`~armctl.Dynamics.coulomb_column`)."""
    y = dynamics.regressor(q, qd, qdd)
    if dynamics.friction.has_asymmetry:
        joints = np.arange(dynamics.n)
        y[joints, PARAMS_PER_JOINT * joints + PARAMS_PER_JOINT - 1] = np.sign(qd)
    return y


@dataclass(frozen=True)
class BaseParameters:
    """The base parameters of an arm: which columns of Y are independent and how the others lump in.

    Attributes
    ----------
    independent : tuple of int
        Indices b into π of the r independent columns (θ_k is π_b[k] plus its lumped terms).
    dependent : tuple of int
        Indices d of the other 13n − r columns.
    beta : ndarray, shape (r, 13n − r)
        Y[:, d] = Y[:, b] β.
    names : tuple of str
        The (13n,) names of π's entries (``'m[2]'``, …).
    tol : float
        The relative rank tolerance used.
    """

    independent: tuple[int, ...]
    dependent: tuple[int, ...]
    beta: FloatArray
    names: tuple[str, ...]
    tol: float

    def __post_init__(self) -> None:
        readonly_fields(self, ("beta",))

    @property
    def n_full(self) -> int:
        """Number of entries of π (13 n)."""
        return len(self.names)

    @property
    def n_base(self) -> int:
        """Number r of base parameters."""
        return len(self.independent)

    @property
    def map(self) -> FloatArray:
        """K (r × 13n) with θ = K π: identity on the independent columns, β on the dependent ones."""
        k = np.zeros((self.n_base, self.n_full))
        k[:, list(self.independent)] = np.eye(self.n_base)
        k[:, list(self.dependent)] = self.beta
        return readonly(k)

    @property
    def null_space(self) -> FloatArray:
        """(13n, 13n − r) basis N of the parameter changes that no torque can see: K N = 0, Y N = 0."""
        out = np.zeros((self.n_full, len(self.dependent)))
        out[list(self.independent), :] = -self.beta
        out[list(self.dependent), :] = np.eye(len(self.dependent))
        return readonly(out)

    def project(self, pi: FloatArray) -> FloatArray:
        """θ = K π: the base parameters of a full parameter vector.

        Parameters
        ----------
        pi : ndarray, shape (13 n,)
            π, in the layout of :meth:`RobotModel.parameters <armctl.model.RobotModel.parameters>`.

        Returns
        -------
        ndarray, shape (r,)
        """
        p = np.asarray(pi, dtype=float)
        if p.shape != (self.n_full,):
            raise InvalidParameterError(f"π must have shape ({self.n_full},), got {p.shape}", value=pi)
        return self.map @ p

    def columns(self, y: FloatArray) -> FloatArray:
        """Y_b: the independent columns of a regressor.

        Parameters
        ----------
        y : ndarray, shape (..., 13 n)
            A regressor Y.

        Returns
        -------
        ndarray, shape (..., r)
        """
        return np.asarray(y)[..., list(self.independent)]

    def base_names(self, digits: int = 4) -> tuple[str, ...]:
        """A readable name for each base parameter, e.g. ``'Izz[1] + 0.1866 m[2] + Im_reflected[1]'``.

        Parameters
        ----------
        digits : int, optional
            Significant digits of the lumping coefficients.

        Returns
        -------
        tuple of str
        """
        out = []
        for row, k in enumerate(self.independent):
            terms = [self.names[k]]
            for col, d in enumerate(self.dependent):
                c = float(self.beta[row, col])
                if c == 0.0:
                    continue
                mag = f"{abs(c):.{digits}g}"
                coef = "" if mag == "1" else f"{mag} "
                terms.append(f"{'+' if c > 0 else '-'} {coef}{self.names[d]}")
            out.append(" ".join(terms))
        return tuple(out)


def random_states(dynamics: Dynamics, samples: int, rng: np.random.Generator) -> FloatArray:
    """(samples, 3, n) random (q, q̇, q̈): q uniform within the joint limits (±π where a limit is infinite),
    q̇ and q̈ standard normal [rad/s, rad/s²]."""
    m = dynamics.model
    lo = np.where(np.isfinite(m.lower), m.lower, -np.pi)
    hi = np.where(np.isfinite(m.upper), m.upper, np.pi)
    n = dynamics.n
    q = lo + (hi - lo) * rng.random((samples, n))
    return np.stack([q, rng.standard_normal((samples, n)), rng.standard_normal((samples, n))], axis=1)


def find_base_parameters(
    dynamics: Dynamics, samples: int | None = None, seed: int = 0, tol: float = 1e-8
) -> BaseParameters:
    """The base parameters of an arm, by pivoted QR of the regressor stacked at random states.

    The result depends only on the kinematics (and on which columns exist), not on the inertial values of the
    model.

    Parameters
    ----------
    dynamics : Dynamics
        The arm.
    samples : int, optional
        The number of random states S (default max(30, 4n)); the stacked W is (S n × 13n).
    seed : int, optional
        The seed of the random states (a whole number ≥ 0).
    tol : float, optional
        The relative rank tolerance on |R_kk| / |R_00|, in [1e-14, 1e-3] (see :data:`TOL_RANGE`; the default 1e-8
        sits in the middle of the gap).

    Returns
    -------
    BaseParameters

    Raises
    ------
    InvalidParameterError
        A bad number of samples, seed or tolerance.
    """
    n, p = dynamics.n, PARAMS_PER_JOINT * dynamics.n
    s = whole_number(samples, "samples", minimum=1) if samples is not None else max(30, 4 * n)
    if s * n < p:
        raise InvalidParameterError(
            f"samples={s} gives {s * n} rows for {p} columns; use at least {-(-p // n)} samples", value=samples
        )
    tol = scalar(tol, "tol", positive=True)
    if not TOL_RANGE[0] <= tol <= TOL_RANGE[1]:
        raise InvalidParameterError(
            f"tol must be in [{TOL_RANGE[0]:g}, {TOL_RANGE[1]:g}] (relative to the largest "
            f"pivot: smaller counts round-off as independent, larger drops identifiable "
            f"parameters; default 1e-8), got {tol!r}",
            value=tol,
        )
    rng = np.random.default_rng(whole_number(seed, "seed"))
    w = np.vstack([identification_regressor(dynamics, *x) for x in random_states(dynamics, s, rng)])
    _, r, perm = scipy.linalg.qr(w, mode="economic", pivoting=True)
    diag = np.abs(np.diag(r))
    rank = int(np.count_nonzero(diag > tol * max(diag[0], 1e-300)))
    independent = _first_independent(w, rank, tol)
    if independent is None:  # the greedy choice disagrees with the rank: keep the pivoted choice
        independent = tuple(sorted(int(i) for i in perm[:rank]))
    dependent = tuple(k for k in range(p) if k not in independent)
    wb, wd = w[:, list(independent)], w[:, list(dependent)]
    beta = np.linalg.lstsq(wb, wd, rcond=None)[0] if dependent else np.zeros((rank, 0))
    beta[np.abs(beta) < _BETA_ZERO * max(1.0, float(np.abs(beta).max(initial=0.0)))] = 0.0
    return BaseParameters(independent, dependent, cast(FloatArray, beta), dynamics.model.parameter_names(), tol)


def _first_independent(w: FloatArray, rank: int, tol: float) -> tuple[int, ...] | None:
    """The first ``rank`` columns of ``w``, in order, each independent of those kept before it (Gram–Schmidt
    with re-orthogonalisation on unit-norm columns), or None if that does not give exactly ``rank`` columns.

    Taking columns in π's order gives the textbook lumping (a link's inertia about its axis keeps its name
    and absorbs the next link's mass), where pivoting would pick whichever column is largest."""
    norms = np.linalg.norm(w, axis=0)
    basis = np.zeros((w.shape[0], 0))
    kept: list[int] = []
    for k in range(w.shape[1]):
        if norms[k] <= tol * norms.max():
            continue
        v = w[:, k] / norms[k]
        for _ in range(2):
            v = v - basis @ (basis.T @ v)
        if np.linalg.norm(v) > np.sqrt(tol):
            basis = np.column_stack([basis, v / np.linalg.norm(v)])
            kept.append(k)
    return tuple(kept) if len(kept) == rank else None
