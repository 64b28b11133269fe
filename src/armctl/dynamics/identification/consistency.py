"""Physically consistent identification: a full π that fits the data and that a RobotModel can take.

Least squares on the base parameters can return values no arm has (a negative lumped mass, an inertia
that violates the triangle inequality), and it says nothing about the parameters the data cannot see. This
estimate solves, over the full π and the Coulomb offsets δ,

    minimise    ‖Σ^{-1/2}(W [K π; δ] − y)‖² + λ ‖N_oᵀ(π − π_0)‖²
    subject to  J_i(π) ⪰ 0 (every link: a body),  k_r² I_m ≥ 0,  F_v ≥ 0,  F_c ± δ ≥ 0

with J_i the pseudo-inertia (:mod:`~armctl.dynamics.identification.pseudo_inertia`) — the convex,
semidefinite form of "mass ≥ 0 and inertia about the centre of mass satisfying the triangle
inequalities" — and N_o an orthonormal basis of the null space of K (the changes of π no torque can see):
the prior π_0 decides only what the data cannot, never the identifiable combinations.

How it is solved, and why: each J_i ⪰ 0 is written exactly as U_i U_iᵀ (U_i upper triangular) and each bounded
scalar as a square (F_v = s²), which leaves an unconstrained problem; the data term is compressed to p rows by
a QR of the weighted W (‖Σ^{-1/2}(W u − y)‖² = ‖R u − z‖² + const). What remains is a small nonlinear
least-squares problem (14 n unknowns, 13 n + n residuals) with an exact Jacobian, solved by
Levenberg–Marquardt (MINPACK, through SciPy) continued by SciPy's trust-region reflective method. The
semidefinite constraint is kept exact (a QP on proxsuite would need it linearised and iterated), no SDP solver
is needed, and IPOPT through CasADi would solve the same parametrisation with nothing to gain at this size.
Every iterate is a body, so the result always builds a valid RobotModel.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.optimize
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, readonly_fields, scalar, vector, whole_number
from armctl.dynamics.identification.least_squares import LeastSquaresEstimate, check_torque
from armctl.dynamics.identification.problem import IdentificationProblem
from armctl.dynamics.identification.pseudo_inertia import factor_of, parameters_from_factor
from armctl.errors import InvalidParameterError, ShapeError, SolverError
from armctl.model.from_parameters import model_from_parameters
from armctl.model.robot import PARAMS_PER_JOINT, RobotModel

#: allowed range of ``prior_weight`` (relative to the data's scale): from 1 up, the prior pulls against the data
#: through the nonlinear parametrisation and the solver stalls far from the fit (cost ratio 10–10³ at 1–1e6 on
#: planar arms, an overflow at 1e300)
PRIOR_WEIGHT_RANGE = (1e-12, 1.0)
#: the cost ratio's round-off floor, relative to the weighted ‖y‖²
RSS_FLOOR = 1e-12


@dataclass(frozen=True)
class ConsistentEstimate:
    """A physically consistent estimate.

    Attributes
    ----------
    pi : ndarray, shape (13 n,)
        The full parameter vector (π's layout).
    coulomb_offset : ndarray, shape (n,)
        δ [N·m] (zeros if the problem has none).
    theta : ndarray, shape (p,)
        The problem's unknowns it implies ([K π; δ]).
    model : RobotModel
        The model with these parameters (every link physical).
    residual_rms : ndarray, shape (n,)
        RMS of y − W θ per joint [N·m].
    cost_ratio : float
        Its weighted residual sum of squares over that of the unconstrained least squares, each plus a round-off
        floor of 10⁻¹² of the weighted ‖y‖² (a relative RMS residual of 10⁻⁶): ≥ 1, near 1 when the constraints
        cost nothing, and 1 rather than a ratio of round-off on noise-free data.
    converged : bool
        The solver met its tolerance, or used up its budget with the fit stalled (50 more evaluations change the
        weighted residual sum of squares by less than 10⁻⁵ relative: what still moves is the prior's choice in
        directions the data do not see).
    message : str
        Why it stopped, in words that agree with ``converged``: the solver's own message when it met its tolerance
        (or did not, with the budget spent and the fit still moving), else that the fit had settled when the
        budget ran out.
    """

    pi: FloatArray
    coulomb_offset: FloatArray
    theta: FloatArray
    model: RobotModel
    residual_rms: FloatArray
    cost_ratio: float
    converged: bool
    message: str

    def __post_init__(self) -> None:
        readonly_fields(self, ("pi", "coulomb_offset", "theta", "residual_rms"))


def check_prior_weight(prior_weight: float) -> float:
    """``prior_weight`` checked: a real number in :data:`PRIOR_WEIGHT_RANGE`."""
    lam = scalar(prior_weight, "prior_weight", positive=True)
    if not PRIOR_WEIGHT_RANGE[0] <= lam <= PRIOR_WEIGHT_RANGE[1]:
        raise InvalidParameterError(
            f"prior_weight must be in [{PRIOR_WEIGHT_RANGE[0]:g}, {PRIOR_WEIGHT_RANGE[1]:g}] "
            f"(relative to the data's scale; default 1e-6), got {prior_weight!r}",
            value=prior_weight,
        )
    return lam


def consistent_estimate(
    problem: IdentificationProblem,
    model: RobotModel,
    estimate: LeastSquaresEstimate | None = None,
    prior: ArrayLike | None = None,
    prior_weight: float = 1e-6,
    max_evaluations: int = 300,
) -> ConsistentEstimate:
    """The physically consistent estimate of a model's π from a problem (see the module).

    Parameters
    ----------
    problem : IdentificationProblem
        W θ = y.
    model : RobotModel
        The model identified (its kinematics; its parameters as the default prior).
    estimate : LeastSquaresEstimate, optional
        A least-squares estimate of the same problem, whose per-joint noise levels weight the rows (None or OLS:
        unweighted).
    prior : array_like, shape (13 n,), optional
        π_0 (default ``model.parameters()``; it need not be physical).
    prior_weight : float, optional
        λ relative to the mean squared column norm of the compressed data matrix (dimensionless, in [1e-12, 1]:
        the prior only fills in what the data cannot see; heavier, it fights the data and the solver stalls).
    max_evaluations : int, optional
        Of each of the two solver runs (LM, then trust region; ≥ 1; 50 more may be spent to tell a stalled run
        from one still descending).

    Returns
    -------
    ConsistentEstimate

    Raises
    ------
    InvalidParameterError, ShapeError
        A bad weight, budget or prior.
    """
    n, k = problem.n, PARAMS_PER_JOINT
    if model.n != n or problem.base.n_full != k * n:
        raise ShapeError(f"model has {model.n} joints, the problem {n}", value=model.n)
    pi0 = vector(model.parameters() if prior is None else prior, k * n, "prior")
    lam = check_prior_weight(prior_weight)
    budget = whole_number(max_evaluations, "max_evaluations", minimum=1)
    w, y = problem.regressor, problem.torque
    check_torque(problem)
    sigma = estimate.noise_std if estimate is not None and estimate.weighted else np.ones(n)
    wt = np.tile(1.0 / sigma, problem.samples)
    q, r = scipy.linalg.qr(w * wt[:, None], mode="economic")
    z = q.T @ (y * wt)
    rss_ls = float(((y * wt - q @ z) ** 2).sum())  # not ‖y‖² − ‖z‖²: that cancels to round-off, even < 0
    floor = RSS_FLOOR * float((y * wt) @ (y * wt))  # round-off level of the fit: 1e-6 relative RMS
    kmap = problem.base.map
    nb = problem.base.n_base
    col2 = (r[:, :nb] ** 2).sum(axis=0)
    null = scipy.linalg.orth(problem.base.null_space) if problem.base.null_space.shape[1] else np.zeros((k * n, 0))
    prior_scale = np.sqrt(lam * float(col2.mean()))
    layout = _Layout(n, problem.offsets)

    def unknowns(pi: FloatArray, delta: FloatArray) -> FloatArray:
        return np.concatenate([kmap @ pi, delta]) if problem.offsets else kmap @ pi

    def residual(x: FloatArray) -> FloatArray:
        with np.errstate(all="ignore"):  # a wild trial step may overflow: give it a huge, finite cost
            pi, delta, _ = layout.unpack(x)
            out = np.concatenate([r @ unknowns(pi, delta) - z, prior_scale * (null.T @ (pi - pi0))])
        return out if np.isfinite(out).all() else np.full(out.shape, 1e100)

    def jacobian(x: FloatArray) -> FloatArray:
        with np.errstate(all="ignore"):
            _, _, (dpi, ddelta) = layout.unpack(x)
            du = np.vstack([kmap @ dpi, ddelta]) if problem.offsets else kmap @ dpi
            out = np.vstack([r @ du, prior_scale * (null.T @ dpi)])
        return out if np.isfinite(out).all() else np.zeros(out.shape)

    x0 = layout.start(pi0)
    # Levenberg–Marquardt (MINPACK) first, quick where it works; it can also stop at its start, though (a huge
    # first step, shrunk until its xtol test ends the run: a pendulum whose prior mass was 30 % low stayed at
    # the prior, with 1e4 times the least-squares cost). SciPy's trust-region reflective method continues from
    # its result. Near a rank-deficient J_i (a link at the edge of physical, e.g. massless) both creep instead
    # of meeting their tolerance; what still moves then is the prior's choice in directions the data do not
    # see, so a run out of budget counts as converged when the fit has stalled: 50 more evaluations change the
    # weighted residual sum of squares by less than 1e-5 relative (its own sampling error is ~√(2/N), N the
    # number of torque samples: 1e-2 for 2e4 samples).
    opts = {"jac": jacobian, "xtol": 1e-10, "ftol": 1e-10, "gtol": 1e-10, "max_nfev": budget}
    nu = r.shape[0]  # the data rows of the residual (the prior's follow)
    res = scipy.optimize.least_squares(residual, x0, method="lm", **opts)
    if np.isfinite(res.x).all():
        res = scipy.optimize.least_squares(residual, res.x, method="trf", **opts)
    if not np.isfinite(res.x).all() or res.status < 0:
        raise SolverError(
            f"consistent estimate failed ({res.message}); with prior_weight={prior_weight!r} and "
            f"max_evaluations={max_evaluations!r}",
            problem=problem,
            result=res,
        )
    converged, message = res.status > 0, str(res.message)
    if not converged:
        again = scipy.optimize.least_squares(residual, res.x, method="trf", **dict(opts, max_nfev=50))
        fit, fit_again = (rss_ls + floor + float(x.fun[:nu] @ x.fun[:nu]) for x in (res, again))  # weighted RSS
        change = abs(fit - fit_again) / fit
        if again.status > 0:
            converged, message = True, f"{again.message} (within 50 evaluations past the budget of {budget})"
        elif change <= 1e-5:  # the budget ran out on a fit that no longer moves: said so, not the solver's words
            converged = True
            message = (
                f"the fit has settled: the budget of {budget} evaluations ran out, and 50 more change the weighted "
                f"residual sum of squares by {change:.2g} relative (below 1e-5)"
            )
        else:
            message = (
                f"{res.message} The fit is still moving: 50 more evaluations change the weighted residual sum of "
                f"squares by {change:.2g} relative; raise max_evaluations (now {budget})"
            )
        res = again if again.cost <= res.cost else res
    pi, delta, _ = layout.unpack(res.x)
    theta = unknowns(pi, delta)
    e = y - w @ theta
    rss = float(((e * wt) ** 2).sum())
    fitted = model_from_parameters(model, pi, delta, physical=True)
    return ConsistentEstimate(
        pi,
        delta,
        theta,
        fitted,
        np.sqrt((e.reshape(-1, n) ** 2).mean(axis=0)),
        (rss + floor) / (rss_ls + floor),
        bool(converged),
        message,
    )


class _Layout:
    """x = [factor U of each link (10 n), square roots of k_r² I_m, F_v, F_c⁺, F_c⁻ (n each)] with offsets, or
    [… , √F_c (n)] without (F_c⁺ = F_c⁻)."""

    def __init__(self, n: int, offsets: bool) -> None:
        self.n, self.offsets = n, offsets
        self.size = 10 * n + (4 if offsets else 3) * n

    def unpack(self, x: FloatArray) -> tuple[FloatArray, FloatArray, tuple[FloatArray, FloatArray]]:
        """(π, δ, (∂π/∂x, ∂δ/∂x))."""
        n, k = self.n, PARAMS_PER_JOINT
        p, jac = parameters_from_factor(x[: 10 * n].reshape(n, 10))
        s = x[10 * n :].reshape(-1, n)  # rows: rotor, viscous, Coulomb (+), [Coulomb (−)]
        sq = s**2
        pos, neg = (sq[2], sq[3]) if self.offsets else (sq[2], sq[2])
        pi = np.concatenate([p, sq[0][:, None], sq[1][:, None], (0.5 * (pos + neg))[:, None]], axis=1).ravel()
        dpi = np.zeros((n, k, self.size))
        ddelta = np.zeros((n, self.size))
        joints = np.arange(n)
        for i in range(n):
            dpi[i, :10, 10 * i : 10 * i + 10] = jac[i]
        tail = 10 * n + joints
        dpi[joints, 10, tail] = 2.0 * s[0]
        dpi[joints, 11, tail + n] = 2.0 * s[1]
        if self.offsets:
            dpi[joints, 12, tail + 2 * n] = s[2]
            dpi[joints, 12, tail + 3 * n] = s[3]
            ddelta[joints, tail + 2 * n] = s[2]
            ddelta[joints, tail + 3 * n] = -s[3]
        else:
            dpi[joints, 12, tail + 2 * n] = 2.0 * s[2]
        delta = 0.5 * (pos - neg)
        return pi, delta, (dpi.reshape(k * n, self.size), ddelta)

    def start(self, pi0: FloatArray) -> FloatArray:
        """The prior made physical (links projected onto J ⪰ 0), friction and rotor levels clipped at a small
        positive value (a square root of 0 would have no gradient)."""
        n, k = self.n, PARAMS_PER_JOINT
        p = pi0.reshape(n, k)
        links = np.concatenate([factor_of(p[i, :10]) for i in range(n)])
        levels = [np.maximum(p[:, c], 1e-4 * max(float(np.abs(p[:, c]).max()), 1e-2)) for c in (10, 11, 12)]
        if self.offsets:
            levels.append(levels[2])
        return np.concatenate([links, *np.sqrt(levels)])
