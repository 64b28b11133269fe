"""Optimal excitation: the Fourier coefficients that minimise the condition number of the base regressor.

    minimise    cond(W_b(x)),   W_b = [Y_b(q(t_k), q̇(t_k), q̈(t_k))]_{k=1..S}   (S samples over one period)
    subject to  q_min ≤ q(t_j) ≤ q_max,  |q̇(t_j)| ≤ q̇_max,  |q̈(t_j)| ≤ q̈_max     on a grid t_j

over x = (q0, a, b) of a :class:`~armctl.dynamics.identification.excitation.FourierExcitation`. Every
constraint is linear in x (q, q̇, q̈ are linear in the coefficients), so the grid constraints are one
matrix built once; the objective is smooth almost everywhere and is minimised by SLSQP with finite-
difference gradients, starting from the best of a few random feasible trajectories. The result is checked
on a denser grid and scaled into the limits if it overshoots between grid points.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.optimize
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, real_array, scalar, whole_number
from armctl.dynamics.base import Dynamics
from armctl.dynamics.identification.base_parameters import (
    BaseParameters,
    find_base_parameters,
    identification_regressor,
)
from armctl.dynamics.identification.excitation import FourierExcitation
from armctl.errors import IdentifiabilityError, InvalidParameterError, ShapeError


@dataclass(frozen=True)
class ExcitationDesign:
    """Result of :func:`optimize_excitation`.

    Attributes
    ----------
    trajectory : FourierExcitation
        The optimised excitation.
    condition_number : float
        cond(W_b) of the result, on the ``samples`` states used by the optimiser.
    initial_condition_number : float
        That of the best random start.
    evaluations : int
        The number of objective evaluations.
    message : str
        The optimiser's.
    """

    trajectory: FourierExcitation
    condition_number: float
    initial_condition_number: float
    evaluations: int
    message: str


def stacked_base_regressor(
    dynamics: Dynamics, base: BaseParameters, q: FloatArray, qd: FloatArray, qdd: FloatArray
) -> FloatArray:
    """W_b (S n × r): the base regressor Y_b stacked over S samples of (q, q̇, q̈), each (S, n)."""
    cols = list(base.independent)
    return np.vstack([identification_regressor(dynamics, q[k], qd[k], qdd[k])[:, cols] for k in range(q.shape[0])])


def condition_number(w: FloatArray) -> float:
    """cond(W) = σ_max/σ_min = sqrt(λ_max/λ_min) of WᵀW: the r × r eigenproblem is far cheaper than an SVD
    of the tall W and accurate to ~1e-8 relative for cond(W) up to 1e4 (inf if W is rank-deficient)."""
    ev = np.linalg.eigvalsh(w.T @ w)
    return math.sqrt(ev[-1] / ev[0]) if ev[0] > 1e-15 * ev[-1] else math.inf


def _limit(value: ArrayLike | None, model_value: FloatArray, name: str) -> FloatArray:
    n = model_value.shape[0]
    if value is None:
        out = np.array(model_value, dtype=float)
    else:
        v = real_array(value, name)
        if np.isnan(v).any():
            raise InvalidParameterError(f"{name} holds NaN: {value!r}", value=value)
        if v.ndim > 1 or (v.ndim == 1 and v.shape != (n,)):
            raise ShapeError(f"{name} must be a scalar or a ({n},) vector, got shape {v.shape}", value=value)
        out = np.minimum(np.broadcast_to(v, (n,)), model_value)
    if not (np.isfinite(out).all() and (out > 0).all()):
        raise InvalidParameterError(
            f"{name} must be finite and > 0 for every joint, got {out}; the model gives "
            f"none for some joints, so pass one",
            value=value,
        )
    return out


def optimize_excitation(
    dynamics: Dynamics,
    base: BaseParameters | None = None,
    *,
    acceleration_limit: ArrayLike,
    velocity_limit: ArrayLike | None = None,
    period: float = 10.0,
    harmonics: int = 5,
    position_margin: float = 0.05,
    samples: int = 60,
    grid: int = 100,
    starts: int = 8,
    maxiter: int = 40,
    seed: int = 0,
) -> ExcitationDesign:
    """An excitation trajectory within the joint limits with a small cond(W_b).

    Parameters
    ----------
    dynamics : Dynamics
        The arm.
    base : BaseParameters, optional
        Its base parameters (default: found numerically).
    acceleration_limit : array_like
        q̈_max [rad/s²] (scalar or (n,)); a model carries none.
    velocity_limit : array_like, optional
        q̇_max [rad/s] (default: the model's; if given, the smaller of the two).
    period : float, optional
        T_f [s].
    harmonics : int, optional
        The number N of harmonics of each joint's Fourier series.
    position_margin : float, optional
        Kept from each position limit [rad].
    samples : int, optional
        States S per period in the objective.
    grid : int, optional
        Constraint points per period.
    starts : int, optional
        Random starts (the best one is optimised).
    maxiter : int, optional
        SLSQP iterations (0: the best random start).
    seed : int, optional
        Seed of the random starts.

    Returns
    -------
    ExcitationDesign

    Raises
    ------
    IdentifiabilityError
        Even the best design leaves cond(W_b) infinite (limits or a period that leave almost no motion, too few
        samples).
    """
    model = dynamics.model
    n = dynamics.n
    base = base if base is not None else find_base_parameters(dynamics)
    period = scalar(period, "period", positive=True)
    margin = scalar(position_margin, "position_margin", nonnegative=True)
    nh = whole_number(harmonics, "harmonics", minimum=1)
    samples, grid = whole_number(samples, "samples", minimum=1), whole_number(grid, "grid", minimum=1)
    starts, maxiter = whole_number(starts, "starts", minimum=1), whole_number(maxiter, "maxiter")
    seed = whole_number(seed, "seed")
    if samples * n < base.n_base or grid < 4 * nh:
        raise InvalidParameterError(
            f"need samples·n >= {base.n_base} base parameters and grid >= 4·harmonics; got "
            f"harmonics={harmonics}, samples={samples}, grid={grid} (n = {n})",
            value=(harmonics, samples, grid),
        )
    vmax = _limit(velocity_limit, model.velocity_limit, "velocity_limit")
    amax = _limit(acceleration_limit, np.full(n, np.inf), "acceleration_limit")
    lo = np.where(np.isfinite(model.lower), model.lower + margin, -np.inf)
    hi = np.where(np.isfinite(model.upper), model.upper - margin, np.inf)
    if np.any(hi - lo <= 0):
        raise InvalidParameterError(
            f"position_margin={margin} leaves no range for some joints (limits {model.lower} .. {model.upper})",
            value=position_margin,
        )
    bounded = np.isfinite(lo) & np.isfinite(hi)
    center = np.where(bounded, 0.5 * (np.where(bounded, lo, 0.0) + np.where(bounded, hi, 0.0)), 0.0)
    omega = 2.0 * math.pi / period
    t_obj = np.linspace(0.0, period, int(samples), endpoint=False)
    basis = _Basis(omega, nh, np.linspace(0.0, period, int(grid), endpoint=False))

    def unpack(x: FloatArray) -> FourierExcitation:
        return FourierExcitation(x[:n], x[n : n + n * nh].reshape(n, nh), x[n + n * nh :].reshape(n, nh), period)

    evaluations = 0

    def objective(x: FloatArray) -> float:
        nonlocal evaluations
        evaluations += 1
        q, qd, qdd = unpack(x).evaluate(t_obj)
        return math.log(min(condition_number(stacked_base_regressor(dynamics, base, q, qd, qdd)), 1e15))

    a_ub, b_ub = basis.constraints(n, lo, hi, vmax, amax)
    rng = np.random.default_rng(seed)
    candidates = [_random_start(rng, center, lo, hi, vmax, amax, omega, nh, period) for _ in range(int(starts))]
    values = [objective(x) for x in candidates]
    x0 = candidates[int(np.argmin(values))]
    initial = math.exp(min(values))
    res = scipy.optimize.minimize(
        objective,
        x0,
        method="SLSQP",
        constraints=[{"type": "ineq", "fun": lambda x: b_ub - a_ub @ x, "jac": lambda x: -a_ub}],
        options={"maxiter": int(maxiter), "ftol": 1e-4},
    )
    x = res.x if np.all(a_ub @ res.x <= b_ub + 1e-6) and res.fun <= math.log(initial) else x0
    trajectory = _fit_into(unpack(x), lo, hi, vmax, amax)
    q, qd, qdd = trajectory.evaluate(t_obj)
    cond = condition_number(stacked_base_regressor(dynamics, base, q, qd, qdd))
    if not math.isfinite(cond):
        _, _, vpeak, apeak = trajectory.extremes()
        raise IdentifiabilityError(
            f"no excitation with a finite condition number found: the best design moves at most "
            f"{vpeak.max():.3g} rad/s and {apeak.max():.3g} rad/s² over its {samples} samples (limits "
            f"velocity_limit={vmax.tolist()}, acceleration_limit={amax.tolist()}, period={period:g} s, "
            f"harmonics={nh}); raise acceleration_limit / velocity_limit, use a period of seconds, or more "
            f"samples, harmonics and starts",
            value=cond,
        )
    return ExcitationDesign(trajectory, cond, initial, evaluations, str(res.message))


class _Basis:
    """q, q̇, q̈ on a time grid as linear maps of x = (q0, a, b) (one joint's block; joints are alike)."""

    def __init__(self, omega: float, harmonics: int, t: FloatArray) -> None:
        wl = omega * np.arange(1, harmonics + 1)
        ph = np.outer(t, wl)
        s, c = np.sin(ph), np.cos(ph)
        self.pos = np.hstack([s / wl, -c / wl])  # (G, 2N) acting on (a_i, b_i)
        self.vel = np.hstack([c, s])
        self.acc = np.hstack([-s * wl, c * wl])
        self.nh = harmonics

    def constraints(
        self, n: int, lo: FloatArray, hi: FloatArray, vmax: FloatArray, amax: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """A x ≤ b for every grid point and joint."""
        g, nh = self.pos.shape[0], self.nh
        rows, rhs = [], []
        for i in range(n):
            cols = np.r_[n + i * nh : n + (i + 1) * nh, n + n * nh + i * nh : n + n * nh + (i + 1) * nh]
            for mat, bound, with_q0 in (
                (self.pos, hi[i], True),
                (self.vel, vmax[i], False),
                (self.acc, amax[i], False),
            ):
                for sign, lim in ((1.0, bound), (-1.0, -lo[i] if with_q0 else bound)):
                    if not np.isfinite(lim):
                        continue
                    block = np.zeros((g, n + 2 * n * nh))
                    block[:, cols] = sign * mat
                    if with_q0:
                        block[:, i] = sign
                    rows.append(block)
                    rhs.append(np.full(g, lim))
        return np.vstack(rows), np.concatenate(rhs)


def _random_start(
    rng: np.random.Generator,
    center: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    vmax: FloatArray,
    amax: FloatArray,
    omega: float,
    nh: int,
    period: float,
) -> FloatArray:
    """Random coefficients (decaying with the harmonic), scaled to use 90% of the tightest limit."""
    n = center.shape[0]
    decay = 1.0 / np.arange(1, nh + 1)
    traj = FourierExcitation(center, rng.standard_normal((n, nh)) * decay, rng.standard_normal((n, nh)) * decay, period)
    traj = _fit_into(traj, lo, hi, vmax, amax, fill=0.9)
    return np.concatenate([traj.q0, traj.a.ravel(), traj.b.ravel()])


def _fit_into(
    traj: FourierExcitation, lo: FloatArray, hi: FloatArray, vmax: FloatArray, amax: FloatArray, fill: float = 1.0
) -> FourierExcitation:
    """Scale each joint's motion about q0 (clipped into the range) so that it uses at most ``fill`` of its
    tightest limit (positions, velocities, accelerations, on a dense grid); never scales up. Between grid
    points a band-limited signal can exceed its sampled maximum by up to ~(ω_max Δt)²/8 of it (ω_max the top
    harmonic): the scale leaves (ω_max Δt)² of room for that, so the limits hold everywhere."""
    q0 = np.clip(traj.q0, lo, hi)
    traj = FourierExcitation(q0, traj.a, traj.b, traj.period)
    samples = 4000
    t = np.linspace(0.0, traj.period, samples, endpoint=False)
    fill = fill * (1.0 - (2 * np.pi * traj.harmonics / samples) ** 2)
    q, qd, qdd = traj.evaluate(t)
    dev_up = np.maximum((q - q0).max(axis=0), 1e-300)
    dev_dn = np.maximum((q0 - q).max(axis=0), 1e-300)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratios = np.vstack(
            [(hi - q0) / dev_up, (q0 - lo) / dev_dn, vmax / np.abs(qd).max(axis=0), amax / np.abs(qdd).max(axis=0)]
        )
    ratios = np.where(np.isnan(ratios), np.inf, ratios)
    return traj.scaled(np.minimum(1.0, fill * ratios.min(axis=0)))
