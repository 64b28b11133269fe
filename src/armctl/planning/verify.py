"""Dense verification of a trajectory against its limits.

A time scaling imposes its limits at gridpoints only; between them, and wherever a solver cut a corner, the
trajectory may exceed them. :func:`check_trajectory` resamples it densely (by default 10 samples per stage of the
grid, plus the end), recomputes q̇, q̈ and the torque τ = ``dyn.inverse_dynamics(q, q̇, q̈)`` at every sample, and
reports per limit the worst *utilisation* |v − mid| / half-range (|v|/L for symmetric bounds ±L: 1 at the
bound, above 1 a violation). Where ṡ = 0 (the two ends), the friction is taken as its limit from inside the
motion, sgn q̇_j = sgn q'_j, as the planner does.

A rest-to-rest trajectory also rests at its start pose before 0 and at its end pose after T (q̇ = q̈ = 0). At
t = 0 and T the samples in motion still carry the first stage's acceleration and the last stage's braking, so
the two rest states are checked as well (:func:`rest_samples`): a trajectory whose end pose the arm cannot
hold does not pass. At rest friction is not counted, neither for nor against: the arm must be held by the
actuators against gravity alone (stiction may help a real arm, but its level is too uncertain to plan on).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armctl._checks import FloatArray, readonly, whole_number
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError, ShapeError
from armctl.planning._batch import friction_torques, rigid_torques
from armctl.planning.limits import Bounds, JointLimits
from armctl.planning.timing import GridTiming
from armctl.planning.trajectory import Samples, Trajectory


@dataclass(frozen=True)
class LimitReport:
    """The worst sample for one limit.

    Attributes
    ----------
    kind : str
        The limit (``"velocity"``, ``"acceleration"``, ``"torque"``).
    ratio : float
        The utilisation there (≤ 1: within).
    joint : int
        The joint (0-based).
    t : float
        The time [s].
    s : float
        The path parameter.
    value, bound : float
        The value and the bound on its side, in ``unit``.
    unit : str
        The unit of the value.
    rest : str or None
        ``"start"`` or ``"end"`` when the worst sample is the rest state at that pose (before t = 0 / after T),
        else None.
    """

    kind: str
    ratio: float
    joint: int
    t: float
    s: float
    value: float
    bound: float
    unit: str
    rest: str | None = None

    @property
    def excess(self) -> float:
        """The normalised violation max(0, ratio − 1)."""
        return max(0.0, self.ratio - 1.0)

    def __str__(self) -> str:
        state = f"exceeds its bound by {100 * self.excess:.3g} %" if self.excess > 0 else "within"
        when = (
            f"t = {self.t:.4g} s"
            if self.rest is None
            else f"rest at the {self.rest} pose ({'t < 0' if self.rest == 'start' else f't > {self.t:.4g} s'})"
        )
        return (
            f"{self.kind}: worst {100 * self.ratio:.4g} % of the range at joint {self.joint}, {when} "
            f"(s = {self.s:.4g}): {self.value:.5g} {self.unit} vs bound {self.bound:.5g} — {state}"
        )


@dataclass(frozen=True)
class LimitCheck:
    """The verification of one trajectory.

    Attributes
    ----------
    samples : int
        How many samples were checked.
    reports : dict of str to LimitReport
        The worst sample of each limit, by kind.
    """

    samples: int
    reports: dict[str, LimitReport]

    @property
    def worst_excess(self) -> float:
        """The largest normalised violation over all limits (0 if none is exceeded)."""
        return max((r.excess for r in self.reports.values()), default=0.0)

    def worst(self) -> LimitReport | None:
        """The report with the largest utilisation.

        Returns
        -------
        LimitReport or None
            None when nothing was checked.
        """
        return max(self.reports.values(), key=lambda r: r.ratio, default=None)

    def ok(self, tol: float = 0.0) -> bool:
        """Whether every limit holds within a tolerance.

        Parameters
        ----------
        tol : float, optional
            The normalised tolerance (0.01: 1 % of a limit).

        Returns
        -------
        bool
        """
        return self.worst_excess <= tol

    def __str__(self) -> str:
        return f"{self.samples} samples; " + "; ".join(str(r) for r in self.reports.values())


def sample_times(traj: Trajectory, oversample: int = 10) -> FloatArray:
    """Times to check: ``oversample`` per stage for a TOPP-RA timing (evenly in time within each stage, the
    gridpoints included), else ``oversample`` × 100 + 1 evenly spaced; always both ends."""
    oversample = whole_number(oversample, "oversample", 1)
    timing = traj.timing
    if isinstance(timing, GridTiming):
        t0, dt = timing.t[:-1], np.diff(timing.t)
        frac = np.arange(oversample) / oversample
        return np.append((t0[:, None] + dt[:, None] * frac[None, :]).reshape(-1), timing.t[-1])
    return np.linspace(0.0, traj.duration, 100 * oversample + 1)


def rest_samples(traj: Trajectory) -> Samples:
    """The two rest states of ``traj``: at the start pose (s = 0, reported at t = 0, held for t < 0) and at the
    end pose (s = 1, t = T, held for t > T), with ṡ = s̈ = 0, hence q̇ = q̈ = 0. Their path tangent is set to
    zero, so that no Coulomb friction is given a direction: the torque at rest is gravity alone."""
    s = np.array([0.0, 1.0])
    q, _, ddq = traj.path.derivatives(s)
    zero, still = np.zeros(2), np.zeros_like(q)
    t = np.array([0.0, traj.duration])
    return Samples(*(readonly(np.asarray(a)) for a in (t, s, zero, zero, q, still, still, still, ddq)))


def _joined(a: Samples, b: Samples) -> Samples:
    names = ("t", "s", "sd", "sdd", "q", "qd", "qdd", "dq", "ddq")
    return Samples(*(readonly(np.concatenate((getattr(a, k), getattr(b, k)))) for k in names))


def sample_torques(dyn: Dynamics, smp: Samples) -> FloatArray:
    """τ = inverse_dynamics(q, q̇, q̈) at every sample (m, n): the rigid-body part in one batch
    (:func:`~armctl.planning._batch.rigid_torques`) plus the friction; at rest (ṡ = 0) the Coulomb friction is
    that of the motion about to start or just ended, sgn q̇ = sgn q'."""
    tau = rigid_torques(dyn, smp.q, smp.qd, smp.qdd)
    if dyn.model.has_friction:
        tau += friction_torques(dyn, smp.qd, smp.dq)
    return tau


def _report(kind: str, bounds: Bounds, values: FloatArray, smp: Samples, moving: int) -> LimitReport:
    """The worst of the samples; those from row ``moving`` on are the rest states (start, end)."""
    util = bounds.utilisation(values)
    k, j = np.unravel_index(int(np.argmax(util)), util.shape)
    v = float(values[k, j])
    mid = 0.5 * (bounds.upper[j] + bounds.lower[j])
    bound = float(bounds.upper[j] if v >= mid else bounds.lower[j])
    rest = None if k < moving else ("start" if k == moving else "end")
    return LimitReport(kind, float(util[k, j]), int(j), float(smp.t[k]), float(smp.s[k]), v, bound, bounds.unit, rest)


def check_trajectory(
    dyn: Dynamics, traj: Trajectory, limits: JointLimits, oversample: int = 10, samples: Samples | None = None
) -> LimitCheck:
    """Check a trajectory densely against the planned limits and report the worst utilisation of each.

    The rest states at both ends (:func:`rest_samples`) are always checked too.

    Parameters
    ----------
    dyn : Dynamics
        The arm (its inverse dynamics give the torques).
    traj : Trajectory
        The trajectory.
    limits : JointLimits
        The limits (the torque bounds with their margin applied).
    oversample : int, optional
        Samples per stage of a grid timing.
    samples : Samples, optional
        Use these instead of :func:`sample_times`.

    Returns
    -------
    LimitCheck
    """
    if not isinstance(dyn, Dynamics):
        raise InvalidParameterError(f"dyn must be an armctl.Dynamics, got {type(dyn).__name__}", value=dyn)
    if not isinstance(traj, Trajectory):
        raise InvalidParameterError(
            f"traj must be an armctl.planning.Trajectory, got {type(traj).__name__}", value=traj
        )
    if not isinstance(limits, JointLimits):
        raise InvalidParameterError(
            f"limits must be an armctl.planning.JointLimits, got {limits!r}; build one with "
            "armctl.planning.joint_limits(dyn.model, vel_limit=..., acc_limit=..., "
            "torque_limit=...) ('model' there uses the model's limits)",
            value=limits,
        )
    if samples is not None and not isinstance(samples, Samples):
        raise InvalidParameterError(
            f"samples must be None or armctl.planning.Samples (from traj.sample), got {type(samples).__name__}",
            value=samples,
        )
    if traj.n != dyn.n:
        raise ShapeError(f"the trajectory has {traj.n} joints, the arm {dyn.n}", value=traj)
    for kind, b in limits.planned().items():
        if b.lower.shape != (dyn.n,):
            raise ShapeError(
                f"the {kind} limits are for {b.lower.shape[0]} joints, the arm has {dyn.n}; build them "
                "with joint_limits(dyn.model, ...)",
                value=limits,
            )
    moving = samples if samples is not None else traj.sample(sample_times(traj, oversample))
    smp = _joined(moving, rest_samples(traj))
    reports: dict[str, LimitReport] = {}
    for kind, b in limits.planned().items():
        if kind == "velocity":
            values = smp.qd
        elif kind == "acceleration":
            values = smp.qdd
        else:
            values = sample_torques(dyn, smp)
        reports[kind] = _report(kind, b, readonly(values), smp, len(moving))
    return LimitCheck(len(smp), reports)
