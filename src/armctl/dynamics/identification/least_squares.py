"""Ordinary and weighted least squares on the base parameters, with standard deviations.

OLS:   θ̂ = argmin ‖W θ − y‖²,      σ̂² = ‖y − W θ̂‖² / (S n − p),      cov θ̂ = σ̂² (WᵀW)⁻¹
WLS:   θ̂ = argmin ‖Σ^{-1/2}(W θ − y)‖²,   Σ = diag(σ̂_j²) for the rows of joint j,   cov θ̂ = (Wᵀ Σ⁻¹ W)⁻¹

with σ̂_j² = ‖r_j‖² / (S − p/n) the per-joint residual variance (Gautier & Poignet 2001), first of the OLS
fit, then re-estimated from the WLS residual until it settles: joints with noisier torques count less. The
standard deviations assume white residuals; residuals of filtered, decimated data are somewhat correlated,
so they are optimistic.

Before solving, the columns of W are scaled to unit norm and its singular values checked: if
σ_min/σ_max < ``rtol`` the data do not excite some combinations of parameters, and
:class:`~armctl.errors.IdentifiabilityError` names them (the right singular vectors) instead of returning a
minimum-norm answer.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import cast

import numpy as np

from armctl._checks import FloatArray, boolean, readonly, readonly_fields, scalar
from armctl.dynamics.identification.problem import IdentificationProblem
from armctl.errors import IdentifiabilityError, InvalidParameterError


@dataclass(frozen=True)
class LeastSquaresEstimate:
    """An estimate of the unknowns of an :class:`IdentificationProblem`.

    Attributes
    ----------
    theta : ndarray, shape (p,)
        Estimates (base parameters, then Coulomb offsets if any) in SI units.
    std : ndarray, shape (p,)
        Their standard deviations.
    covariance : ndarray, shape (p, p)
        Their covariance.
    noise_std : ndarray, shape (n,)
        σ̂_j, the residual torque std per joint [N·m].
    residual_rms : ndarray, shape (n,)
        RMS of y − W θ̂ per joint [N·m].
    condition_number : float
        cond of the (weighted) W.
    weighted : bool
        WLS or OLS.
    names : tuple of str
        The (p,) names of the unknowns.
    """

    theta: FloatArray
    std: FloatArray
    covariance: FloatArray
    noise_std: FloatArray
    residual_rms: FloatArray
    condition_number: float
    weighted: bool
    names: tuple[str, ...]

    def __post_init__(self) -> None:
        readonly_fields(self, ("theta", "std", "covariance", "noise_std", "residual_rms"))

    @property
    def relative_std(self) -> FloatArray:
        """σ_k / |θ_k| (inf where θ_k = 0)."""
        with np.errstate(divide="ignore"):
            return readonly(self.std / np.abs(self.theta))


def check_excitation(w: FloatArray, names: tuple[str, ...], rtol: float = 1e-7) -> FloatArray:
    """The singular values of W with unit-norm columns; raise IdentifiabilityError if some are below
    ``rtol`` times the largest, with those directions (rows, in the unknowns' units, unit norm)."""
    if w.shape[0] < w.shape[1]:
        raise IdentifiabilityError(
            f"{w.shape[0]} equations for {w.shape[1]} unknowns: record more samples", value=w.shape, directions=None
        )
    norms = np.linalg.norm(w, axis=0)
    scale = np.where(norms > 0, norms, 1.0)  # a zero column stays zero and shows as a zero singular value
    _, s, vt = np.linalg.svd(w / scale, full_matrices=False)
    weak = s <= rtol * s[0]
    if not weak.any():
        return s
    dirs = vt[weak] / scale  # back to the unknowns' own units: W d ≈ 0
    dirs = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    lines = []
    for d in dirs[:8]:
        top = np.argsort(-np.abs(d))[:3]
        lines.append("  " + " ".join(f"{d[k]:+.2f}·({names[k]})" for k in top if abs(d[k]) > 1e-3))
    more = f"\n  … and {len(dirs) - 8} more" if len(dirs) > 8 else ""
    raise IdentifiabilityError(
        f"the data do not excite {len(dirs)} of {w.shape[1]} parameter combinations (relative singular value "
        f"below {rtol:g}); the trajectory must move them, e.g. an optimised excitation "
        f"(optimize_excitation) over more joints. Unidentifiable directions (largest components):\n"
        + "\n".join(lines)
        + more,
        value=s,
        directions=readonly(dirs),
    )


def check_torque(problem: IdentificationProblem) -> None:
    """Raise IdentifiabilityError if the problem's torques are all zero: they carry no information on the
    parameters (every estimate would be zero, its standard deviation 0/0)."""
    if not np.any(problem.torque):
        raise IdentifiabilityError(
            "the torques (tau) of the data are all zero: they carry no information on the "
            "parameters; identify from the measured joint torques of the moving arm",
            value=problem.torque,
            directions=None,
        )


def excitation_rtol(rtol: float) -> float:
    """``rtol`` checked: a real number in (0, 1)."""
    v = scalar(rtol, "rtol", positive=True)
    if v >= 1.0:
        raise InvalidParameterError(
            f"rtol must be < 1 (a singular value relative to the largest; default 1e-7), got {rtol!r}", value=rtol
        )
    return v


def solve_least_squares(
    problem: IdentificationProblem, weighted: bool = True, rtol: float = 1e-7
) -> LeastSquaresEstimate:
    """OLS or WLS estimate of the problem's unknowns (see the module).

    Parameters
    ----------
    problem : IdentificationProblem
        W θ = y.
    weighted : bool, optional
        WLS (True) or OLS.
    rtol : float, optional
        Relative singular-value threshold of the excitation check, in (0, 1).

    Returns
    -------
    LeastSquaresEstimate

    Raises
    ------
    IdentifiabilityError
        Directions of θ the data do not excite, named.
    """
    if not isinstance(problem, IdentificationProblem):
        raise InvalidParameterError(
            f"problem must be an IdentificationProblem (see build_problem), got {type(problem).__name__}", value=problem
        )
    w, y, n = problem.regressor, problem.torque, problem.n
    p, rows = w.shape[1], w.shape[0]
    weighted = boolean(weighted, "weighted")
    rtol = excitation_rtol(rtol)
    check_torque(problem)
    check_excitation(w, problem.names, rtol)
    theta = np.linalg.lstsq(w, y, rcond=None)[0]
    r = (y - w @ theta).reshape(-1, n)
    s_count = r.shape[0]
    if weighted:
        # iterated: the OLS residual of a quiet joint carries the OLS error that the noisy joints cause,
        # so the variances are re-estimated from the WLS residual until they settle
        var_prev = np.zeros(n)
        # a residual variance below 1e-24 of the mean squared torque (1e-12 relative RMS) is round-off, not noise
        var_floor = max(1e-24 * float((y**2).mean()), 1e-300)
        for _ in range(5):
            var_j = (r**2).sum(axis=0) / max(s_count - p / n, 1.0)
            var_j = np.maximum(var_j, max(1e-12 * var_j.max(), var_floor))
            wt = np.tile(1.0 / np.sqrt(var_j), s_count)
            ww = w * wt[:, None]
            theta = np.linalg.lstsq(ww, y * wt, rcond=None)[0]
            r = (y - w @ theta).reshape(-1, n)
            if np.all(np.abs(var_j - var_prev) <= 1e-3 * var_j):
                break
            var_prev = var_j
        cov = np.linalg.inv(ww.T @ ww)
        cond = float(np.linalg.cond(ww))
    else:
        var = float((r**2).sum()) / max(rows - p, 1)
        cov = var * np.linalg.inv(w.T @ w)
        cond = float(np.linalg.cond(w))
    noise_std = np.sqrt((r**2).sum(axis=0) / max(s_count - p / n, 1.0))
    return LeastSquaresEstimate(
        cast(FloatArray, theta),
        np.sqrt(np.clip(np.diag(cov), 0.0, None)),
        cov,
        noise_std,
        np.sqrt((r**2).mean(axis=0)),
        cond,
        bool(weighted),
        problem.names,
    )
