"""Dense verification of a trajectory against its limits.

A time scaling imposes its limits at gridpoints only; between them, and wherever a solver cut a corner, the
trajectory may exceed them. :func:`check_trajectory` resamples it densely (by default 10 samples per stage of the
grid, plus the end), recomputes q̇, q̈ and the torque τ = ``dyn.inverse_dynamics(q, q̇, q̈)`` at every sample, and
reports per limit the worst *utilisation* |v − mid| / half-range (|v|/L for symmetric bounds ±L: 1 at the
bound, above 1 a violation). Where ṡ = 0 (the two ends), the friction is taken as its limit from inside the
motion, sgn q̇_j = sgn q'_j, as the planner does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armctl._checks import FloatArray, readonly
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError
from armctl.planning._batch import friction_torques, rigid_torques
from armctl.planning.limits import Bounds, JointLimits
from armctl.planning.timing import GridTiming
from armctl.planning.trajectory import Samples, Trajectory


@dataclass(frozen=True)
class LimitReport:
    """The worst sample for one limit: ``ratio`` = utilisation there (≤ 1: within), at ``joint``, time ``t``
    [s] and path parameter ``s``; ``value`` and the ``bound`` on its side, in ``unit``."""

    kind: str
    ratio: float
    joint: int
    t: float
    s: float
    value: float
    bound: float
    unit: str

    @property
    def excess(self) -> float:
        """The normalised violation max(0, ratio − 1)."""
        return max(0.0, self.ratio - 1.0)

    def __str__(self) -> str:
        state = f"exceeds its bound by {100 * self.excess:.3g} %" if self.excess > 0 else "within"
        return (f"{self.kind}: worst {100 * self.ratio:.4g} % of the range at joint {self.joint}, t = {self.t:.4g} s "
                f"(s = {self.s:.4g}): {self.value:.5g} {self.unit} vs bound {self.bound:.5g} — {state}")


@dataclass(frozen=True)
class LimitCheck:
    """The verification of one trajectory: ``reports`` by limit kind, over ``samples`` samples."""

    samples: int
    reports: dict[str, LimitReport]

    @property
    def worst_excess(self) -> float:
        """The largest normalised violation over all limits (0 if none is exceeded)."""
        return max((r.excess for r in self.reports.values()), default=0.0)

    def worst(self) -> LimitReport | None:
        """The report with the largest utilisation."""
        return max(self.reports.values(), key=lambda r: r.ratio, default=None)

    def ok(self, tol: float = 0.0) -> bool:
        """Whether every limit holds within the normalised tolerance ``tol``."""
        return self.worst_excess <= tol

    def __str__(self) -> str:
        return f"{self.samples} samples; " + "; ".join(str(r) for r in self.reports.values())


def sample_times(traj: Trajectory, oversample: int = 10) -> FloatArray:
    """Times to check: ``oversample`` per stage for a TOPP-RA timing (evenly in time within each stage, the
    gridpoints included), else ``oversample`` × 100 + 1 evenly spaced; always both ends."""
    if oversample < 1:
        raise InvalidParameterError(f"oversample must be >= 1, got {oversample}", value=oversample)
    timing = traj.timing
    if isinstance(timing, GridTiming):
        t0, dt = timing.t[:-1], np.diff(timing.t)
        frac = np.arange(oversample) / oversample
        return np.append((t0[:, None] + dt[:, None] * frac[None, :]).reshape(-1), timing.t[-1])
    return np.linspace(0.0, traj.duration, 100 * oversample + 1)


def sample_torques(dyn: Dynamics, smp: Samples) -> FloatArray:
    """τ = inverse_dynamics(q, q̇, q̈) at every sample (m, n): the rigid-body part in one batch
    (:func:`~armctl.planning._batch.rigid_torques`) plus the friction; at rest (ṡ = 0) the Coulomb friction is
    that of the motion about to start or just ended, sgn q̇ = sgn q'."""
    tau = rigid_torques(dyn, smp.q, smp.qd, smp.qdd)
    if dyn.model.has_friction:
        tau += friction_torques(dyn, smp.qd, smp.dq)
    return tau


def _report(kind: str, bounds: Bounds, values: FloatArray, smp: Samples) -> LimitReport:
    util = bounds.utilisation(values)
    k, j = np.unravel_index(int(np.argmax(util)), util.shape)
    v = float(values[k, j])
    mid = 0.5 * (bounds.upper[j] + bounds.lower[j])
    bound = float(bounds.upper[j] if v >= mid else bounds.lower[j])
    return LimitReport(kind, float(util[k, j]), int(j), float(smp.t[k]), float(smp.s[k]), v, bound, bounds.unit)


def check_trajectory(dyn: Dynamics, traj: Trajectory, limits: JointLimits, oversample: int = 10,
                     samples: Samples | None = None) -> LimitCheck:
    """Check ``traj`` densely against the planned ``limits`` (torque bounds with their margin applied) and
    report the worst utilisation of each. ``samples``: use these instead of :func:`sample_times`."""
    smp = samples if samples is not None else traj.sample(sample_times(traj, oversample))
    reports: dict[str, LimitReport] = {}
    for kind, b in limits.planned().items():
        if kind == "velocity":
            values = smp.qd
        elif kind == "acceleration":
            values = smp.qdd
        else:
            values = sample_torques(dyn, smp)
        reports[kind] = _report(kind, b, readonly(values), smp)
    return LimitCheck(len(smp), reports)
