"""`TimeScalingProblem`: the time-optimal path scaling problem in TOPP-RA's canonical form, built from the dynamics.

Along a path q(s), with x = ṡ² ≥ 0 and u = s̈ (so x' = dx/ds = 2u), the inverse dynamics
τ = M q̈ + C(q, q̇) q̇ + g + F_v q̇ + F_c(sgn q̇) become

    τ(s) = a(s) u + b(s) x + c(s) + F_v q'(s) √x + F_c(sgn q'(s)),
    a = M q',   b = M q'' + C(q, q') q',   c = g(q),

obtained from three inverse-dynamics evaluations per gridpoint: c = ID(q, 0, 0), a = ID(q, 0, q') − c,
b = ID(q, q', q'') − c − friction (C is quadratic in q̇, hence C(q, q'ṡ) q'ṡ = C(q, q') q' x).

Friction, exactly where it can be and conservatively where it cannot:

* Coulomb: q̇_j = q'_j ṡ with ṡ ≥ 0, so sgn q̇_j = sgn q'_j is known along the path and the Coulomb torque is a
  known function of s — exact. Where q'_j changes sign (joint j reverses) the torque jumps; the gridpoints on
  either side of a reversal are held to both one-sided values (max for the upper bound, min for the lower).
  Where ṡ = 0 (the ends of a rest-to-rest motion) the friction is taken as its limit from inside the motion.
* Viscous: F_v q'_j √x is not linear in x. On the side where it helps (it adds torque in the direction of
  q'_j, so it helps the bound it pushes away from) it is dropped (√x ≥ 0); on the side where it hurts, √x is
  replaced by a line above it, α + β x with 4αβ ≥ 1: the tangent at a reference x₀ > 0 (√x₀/2 + x/(2√x₀),
  exact at x₀), or, where toppra finds no timing with it, a steeper one that leaves more torque for slow
  motion (:meth:`TimeScalingProblem.linearized`). x₀ comes from a previous pass (see
  :func:`~armctl.planning.topp.solve_problem`). Every pass over-estimates the viscous torque: never optimistic.

Every constraint is stored as a row  a_r u + b_r x + c_r + w_r √x ≤ g_r  (w_r ≥ 0) at every gridpoint
(acceleration rows: a = ±q', b = ±q'', c = w = 0), plus 0 ≤ x ≤ x_max(s) from the velocity limits
lower_j ≤ q'_j ṡ ≤ upper_j, tightened so that they hold on whole stages, not only at gridpoints
(:func:`velocity_bound`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, readonly
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError, NonFiniteError, ShapeError
from armctl.planning._batch import rigid_torques
from armctl.planning.limits import JointLimits
from armctl.planning.path import Path

X_CAP = 1e8  # largest path velocity² considered (toppra's Seidel solver bounds x by 1e8 as well)
DISCRETIZATIONS = ("interpolation", "collocation")


@dataclass(frozen=True)
class RowLabel:
    """What a constraint row bounds.

    Attributes
    ----------
    kind : str
        ``"torque"`` or ``"acceleration"``.
    joint : int
        The joint index.
    side : str
        ``"upper"`` or ``"lower"``.
    """

    kind: str
    joint: int
    side: str


@dataclass(frozen=True, eq=False)
class TimeScalingProblem:
    """The discretised problem: rows a u + b x + c + w √x ≤ g at gridpoints ``s`` (N+1,), 0 ≤ x ≤ ``x_max``.

    Attributes
    ----------
    dyn : Dynamics
        The arm.
    path : Path
        The path.
    limits : JointLimits
        The limits.
    s : ndarray, shape (N+1,)
        The gridpoints.
    q, dq, ddq : ndarray, shape (N+1, n)
        The path and its derivatives at the gridpoints.
    a, b, c, w : ndarray, shape (N+1, m)
        The rows' coefficients.
    g : ndarray, shape (m,)
        The rows' bounds.
    x_max : ndarray, shape (N+1,)
        The bound on x = ṡ² at each gridpoint.
    gravity : ndarray, shape (N+1, n)
        g(q(s)) [N·m].
    coulomb : ndarray, shape (N+1, n, 2)
        The Coulomb torque on the (lower, upper) side [N·m].
    labels : tuple of RowLabel
        ``labels[r]`` names row r.
    discretization : str
        ``"interpolation"`` (each stage also imposes its rows at s_{i+1} with x_{i+1} = x_i + 2Δ_i u_i, TOPP-RA's
        more accurate scheme) or ``"collocation"`` (at s_i only: the stage's constant u can exceed a limit by its
        end by an amount proportional to the stage width, so the dense check needs far finer grids — on the Panda
        test path 1600 stages still leave 3.9 % against 0.0005 %).

    Arrays are read-only.
    """

    dyn: Dynamics
    path: Path
    limits: JointLimits
    s: FloatArray
    q: FloatArray
    dq: FloatArray
    ddq: FloatArray
    a: FloatArray
    b: FloatArray
    c: FloatArray
    w: FloatArray
    g: FloatArray
    x_max: FloatArray
    gravity: FloatArray
    coulomb: FloatArray
    labels: tuple[RowLabel, ...]
    discretization: str = "interpolation"

    @property
    def grid(self) -> int:
        """N, the number of stages (intervals)."""
        return int(self.s.shape[0] - 1)

    @property
    def has_viscous(self) -> bool:
        return bool(self.w.any())

    def linearized(self, x0: ArrayLike | None, keep: float | None = None) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(a, b, c) of the rows with w √x replaced by a line α + β x ≥ √x (4αβ ≥ 1), or dropped.

        The line is the tangent at x₀ > 0, α = √x₀/2, β = 1/(2√x₀), exact at x₀ — unless ``keep`` is given and the
        intercept w α would take more than that fraction of the row's slack at rest, g − c: then α = keep (g − c)/w and
        β = 1/(4α), a steeper line that still over-estimates √x everywhere and leaves slow motion feasible where the
        tangent's intercept would not (the fallback of :func:`~armctl.planning.topp.solve_problem`). Where the path must
        pass a pose it could not hold at rest, carried by its momentum, the steep line forbids the speed it needs: the
        tangent comes first.

        Parameters
        ----------
        x0 : array_like, shape (N+1,), or None
            Where the tangents touch (None: drop the w √x term).
        keep : float, optional
            The largest fraction of the slack at rest the intercept may take.

        Returns
        -------
        tuple of ndarray
            (a, b, c), each (N+1, m).
        """
        if x0 is None or not self.has_viscous:
            return self.a, self.b, self.c
        alpha = 0.5 * np.sqrt(np.asarray(x0, dtype=float))[:, None] * np.ones_like(self.w)
        if keep is not None:
            slack = self.g - self.c
            with np.errstate(divide="ignore", invalid="ignore"):
                cap = np.where((self.w > 0) & (slack > 0), keep * slack / self.w, np.inf)
            alpha = np.minimum(alpha, cap)
        return self.a, self.b + self.w / (4.0 * alpha), self.c + self.w * alpha


def gridpoints(grid: int | ArrayLike) -> FloatArray:
    """The gridpoints: N + 1 evenly spaced ones on [0, 1] for an integer N ≥ 2, or an explicit increasing array
    from 0 to 1."""
    if isinstance(grid, (int, np.integer)) and not isinstance(grid, bool):
        if grid < 2:
            raise InvalidParameterError(f"grid must be >= 2 intervals, got {grid}", value=grid)
        return np.linspace(0.0, 1.0, int(grid) + 1)
    try:
        s = np.asarray(grid, dtype=float)
    except (TypeError, ValueError):
        raise InvalidParameterError(
            f"grid must be an integer N >= 2 or an array of gridpoints from 0 to 1, got {grid!r}", value=grid
        ) from None
    if s.ndim != 1 or s.shape[0] < 3:
        raise ShapeError(f"grid must be an integer N >= 2 or an array of >= 3 gridpoints, got {grid!r}", value=grid)
    if not np.isfinite(s).all():
        raise NonFiniteError("grid holds NaN or inf", value=grid)
    if s[0] != 0.0 or s[-1] != 1.0 or (np.diff(s) <= 0).any():
        raise InvalidParameterError("gridpoints must increase strictly from 0 to 1", value=grid)
    return s


def _rigid_coefficients(
    dyn: Dynamics, q: FloatArray, dq: FloatArray, ddq: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """a = M q', b = M q'' + C(q, q') q', c = g at every row of q (the rigid-body part, no friction), from
    one batch of 3 (N+1) inverse-dynamics evaluations."""
    m = q.shape[0]
    zero = np.zeros_like(q)
    tau = rigid_torques(
        dyn, np.concatenate((q, q, q)), np.concatenate((zero, zero, dq)), np.concatenate((zero, dq, ddq))
    )
    c = tau[:m]
    return tau[m : 2 * m] - c, tau[2 * m :] - c, c


def friction_parameters(dyn: Dynamics) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(F_v, F_c⁺, F_c⁻) of the joints, (n,) each [N·m·s/rad, N·m, N·m]."""
    fr = [j.friction for j in dyn.model.joints]
    return (np.array([f.viscous for f in fr]), np.array([f.coulomb for f in fr]), np.array([f.coulomb_neg for f in fr]))


def coulomb_sides(dq: FloatArray, fc_pos: FloatArray, fc_neg: FloatArray) -> FloatArray:
    """(N+1, n, 2): the least and the largest Coulomb torque at each gridpoint over the signs of q'_j at it
    and at its two neighbours (both values near a reversal, the exact one elsewhere)."""
    scale = np.abs(dq).max(axis=0, keepdims=True)
    sign = np.where(np.abs(dq) > 1e-12 * np.maximum(scale, 1e-300), np.sign(dq), 0.0)
    f = np.where(sign > 0, fc_pos, np.where(sign < 0, -fc_neg, 0.0))
    lo, hi = f.copy(), f.copy()
    for dst, src in ((slice(1, None), slice(None, -1)), (slice(None, -1), slice(1, None))):  # previous, next
        lo[dst] = np.minimum(lo[dst], f[src])
        hi[dst] = np.maximum(hi[dst], f[src])
    return np.stack([lo, hi], axis=-1)


def velocity_bound(path: Path, s: FloatArray, limits: JointLimits, per_stage: int = 8) -> FloatArray:
    """x_max at each gridpoint such that the velocity limits hold on the whole of both adjacent stages.

    For one s, lower_j ≤ q'_j ṡ ≤ upper_j gives ṡ ≤ upper_j / q'_j (q'_j > 0) or lower_j / q'_j (q'_j < 0):
    x ≤ X(s) = min_j ṡ_max,j². Within a stage TOPP-RA's x = ṡ² is linear in s, so bounding it at the two ends
    by X(s_i), X(s_{i+1}) lets it exceed X in between where X sags below its chord (toppra's velocity
    constraint does this: several % on curved paths). Here each stage's end bounds are lowered by that sag σ
    (the largest chord − X over the stage, sampled ``per_stage`` times) — an O(Δ²) tightening — or, where that
    gives less, both set to the least X over the stage; a gridpoint takes the lower of its two stages' bounds.
    """
    N = s.shape[0] - 1
    if limits.velocity is None:
        return np.full(N + 1, X_CAP)
    frac = np.arange(per_stage + 1) / per_stage
    dense = s[:-1, None] + np.diff(s)[:, None] * frac[None, :]  # (N, per_stage + 1), both ends included
    dq = path(dense.reshape(-1), 1)
    lo, hi = limits.velocity.lower, limits.velocity.upper
    with np.errstate(divide="ignore", invalid="ignore"):
        sd = np.where(dq > 0, hi / dq, np.where(dq < 0, lo / dq, np.inf))
    X = np.minimum(np.min(sd, axis=1) ** 2, X_CAP).reshape(N, per_stage + 1)
    chord = X[:, :1] + (X[:, -1:] - X[:, :1]) * frac[None, :]
    sag = np.maximum((chord - X).max(axis=1), 0.0)
    start, end = X[:, 0] - sag, X[:, -1] - sag
    least = X.min(axis=1)
    use_min = start + end < 2.0 * least
    start, end = np.where(use_min, least, start), np.where(use_min, least, end)
    x_max = np.empty(N + 1)
    x_max[0], x_max[-1] = start[0], end[-1]
    x_max[1:-1] = np.minimum(end[:-1], start[1:])
    return np.maximum(x_max, 0.0)


#: a path speed ‖q'(s)‖ at most this fraction of its largest is a stop
STATIONARY = 1e-9


def stationary_point(path: Path, s: FloatArray, per_stage: int = 8) -> float | None:
    """The first s ∈ (0, 1) where the path stops, ‖q'(s)‖ ≤ :data:`STATIONARY` · max ‖q'‖, or None — between
    the gridpoints ``s`` as well as at them (a stop between two gridpoints leaves the scaling as ill-posed as
    one on a gridpoint, and toppra then reports the path uncontrollable nearby). The speed is sampled
    ``per_stage`` times per stage; each interior local minimum below 1 % of the largest speed is refined by
    Gauss–Newton on ‖q'‖² (q' ≈ q'(s₀) + q''(s₀)(s − s₀)), which lands on a stop to rounding. The ends may
    be stops (a path clamped at rest)."""
    frac = np.arange(per_stage) / per_stage
    dense = np.append((s[:-1, None] + np.diff(s)[:, None] * frac[None, :]).ravel(), s[-1])
    speed = np.linalg.norm(path(dense, 1), axis=1)
    top = float(speed.max())
    inner = speed[1:-1]
    lows = np.flatnonzero((inner <= speed[:-2]) & (inner <= speed[2:]) & (inner <= 1e-2 * top)) + 1
    for i in lows:
        lo, hi, x = float(dense[i - 1]), float(dense[i + 1]), float(dense[i])
        for _ in range(30):
            d1, d2 = path(x, 1), path(x, 2)
            curv = float(d2 @ d2)
            if curv == 0.0:
                break
            x_new = min(max(x - float(d1 @ d2) / curv, lo), hi)
            if x_new == x:
                break
            x = x_new
        if 0.0 < x < 1.0 and float(np.linalg.norm(path(x, 1))) <= STATIONARY * top:
            return x
    return None


def build_problem(
    dyn: Dynamics, path: Path, limits: JointLimits, grid: int | ArrayLike = 100, discretization: str = "interpolation"
) -> TimeScalingProblem:
    """The :class:`TimeScalingProblem` of a path under limits (see the module docstring).

    Parameters
    ----------
    dyn, path, limits
        The arm (:class:`~armctl.dynamics.base.Dynamics`), its path (:class:`~armctl.planning.path.Path`) and the
        limits on it (:class:`~armctl.planning.limits.JointLimits`).
    grid : int or array_like, optional
        The number N of stages (evenly spaced in s), or the gridpoints (increasing from 0 to 1).
    discretization : {"interpolation", "collocation"}, optional
        See :class:`TimeScalingProblem`.

    Returns
    -------
    TimeScalingProblem

    Raises
    ------
    InvalidParameterError, NonFiniteError
        A bad grid or discretization; path coefficients that are not finite.
    """
    if discretization not in DISCRETIZATIONS:
        raise InvalidParameterError(
            f"discretization must be one of {DISCRETIZATIONS}, got {discretization!r}", value=discretization
        )
    s = gridpoints(grid)
    q, dq, ddq = path.derivatives(s)
    still = stationary_point(path, s)
    if still is not None:
        raise InvalidParameterError(
            f"the path is stationary (q'(s) = 0) at s = {still:.4g}: there the path "
            "velocity is unbounded and the scaling ill-posed; remove "
            "the stop from the path or split the path there",
            value=still,
        )
    n = dyn.n
    rows_a, rows_b, rows_c, rows_w, rows_g, labels = [], [], [], [], [], []
    gravity = np.zeros_like(q)
    coul = np.zeros((*q.shape, 2))
    if limits.acceleration is not None:
        for side, sg, lim in (("upper", 1.0, limits.acceleration.upper), ("lower", -1.0, -limits.acceleration.lower)):
            rows_a.append(sg * dq)
            rows_b.append(sg * ddq)
            rows_c.append(np.zeros_like(dq))
            rows_w.append(np.zeros_like(dq))
            rows_g.append(lim)
            labels += [RowLabel("acceleration", j, side) for j in range(n)]
    tau = limits.planned_torque
    if tau is not None:
        a, b, gravity = _rigid_coefficients(dyn, q, dq, ddq)
        fv, fc_pos, fc_neg = friction_parameters(dyn)
        coul = coulomb_sides(dq, fc_pos, fc_neg)
        v = fv * dq  # viscous torque per unit ṡ
        rows_a += [a, -a]
        rows_b += [b, -b]
        rows_c += [gravity + coul[..., 1], -(gravity + coul[..., 0])]
        rows_w += [np.maximum(v, 0.0), np.maximum(-v, 0.0)]
        rows_g += [tau.upper, -tau.lower]
        labels += [RowLabel("torque", j, side) for side in ("upper", "lower") for j in range(n)]
    m = len(labels)
    cat = (lambda xs: np.concatenate(xs, axis=1)) if m else (lambda xs: np.zeros((s.shape[0], 0)))
    arrays = [cat(rows_a), cat(rows_b), cat(rows_c), cat(rows_w)]
    g = np.concatenate(rows_g) if m else np.zeros(0)
    for name, arr in zip("abcw", arrays, strict=True):
        if not np.isfinite(arr).all():
            raise NonFiniteError(
                f"the dynamics gave non-finite path coefficients {name}(s); check the model", value=arr
            )
    coef_a, coef_b, coef_c, coef_w = arrays
    return TimeScalingProblem(
        dyn,
        path,
        limits,
        readonly(s),
        readonly(q),
        readonly(dq),
        readonly(ddq),
        readonly(coef_a),
        readonly(coef_b),
        readonly(coef_c),
        readonly(coef_w),
        readonly(g),
        readonly(velocity_bound(path, s, limits)),
        readonly(gravity),
        readonly(coul),
        tuple(labels),
        discretization,
    )
