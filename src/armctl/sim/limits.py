"""How close a run came to the plant's limits, joint by joint: :class:`LimitReport` (``res.limits``).

For joint j with effort limit τ̄_j, velocity limit q̇̄_j and position range [q_j⁻, q_j⁺], over the N samples:

* ``saturated[j]`` = #{k : |τ_kj| > τ̄_j} / N, the share of samples whose command the motor cannot give
  (clipped to ±τ̄_j when the run saturates, ``saturate=True``);
* ``torque_peak[j]`` = max_k |τ_kj| / τ̄_j (the command, before clipping: above 1 it asked for more);
* ``velocity_peak[j]`` = max_k |q̇_kj| / q̇̄_j and ``velocity_over[j]``, the share of samples with
  |q̇_kj| > (1 + :data:`VELOCITY_TOLERANCE`) q̇̄_j;
* ``position_overrun[j]`` = max_k max(q_j⁻ − q_kj, q_kj − q_j⁺, 0) [rad or m] and ``position_over[j]``, the
  share of samples outside the range.

An infinite limit is never reached (its ratios are 0). A run is *saturated* when some joint's torque sits at
its limit on more than :data:`SATURATION_SHARE` of the samples; a velocity beyond its tolerance or a position
outside its range is an *overrun*. :func:`check_limits` warns about both after a run.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from armctl._checks import FloatArray, readonly_fields
from armctl.errors import SimulationWarning

#: share of the samples above which a joint whose torque sits at its limit makes the run "saturated"
SATURATION_SHARE = 0.5
#: a joint counts as over its velocity limit beyond (1 + this) times it: a time-optimal reference runs exactly
#: at the limit, which tracking then grazes
VELOCITY_TOLERANCE = 0.01

_PER_JOINT = (
    "effort",
    "velocity",
    "lower",
    "upper",
    "saturated",
    "torque_peak",
    "velocity_peak",
    "velocity_over",
    "position_overrun",
    "position_over",
)


@dataclass(frozen=True, eq=False)
class LimitReport:
    """How close each joint of a run came to the plant's limits (arrays of length n, read-only; see the module for
    the definitions).

    Attributes
    ----------
    joint_names : tuple of str
        The plant's.
    effort, velocity : ndarray, shape (n,)
        The plant's effort [N·m] and velocity [rad/s] limits.
    lower, upper : ndarray, shape (n,)
        Its position limits [rad].
    saturated : ndarray, shape (n,)
        The share of samples at the effort limit.
    torque_peak, velocity_peak : ndarray, shape (n,)
        The peak over the limit.
    velocity_over : ndarray, shape (n,)
        The share of samples over the velocity limit.
    position_overrun : ndarray, shape (n,)
        How far outside the position range [rad].
    position_over : ndarray, shape (n,)
        The share of samples outside it.
    clipped : bool
        Whether the run clipped the command at the limits (``saturate=True``).
    samples : int
        The number N of samples the shares are taken over.
    """

    joint_names: tuple[str, ...]
    effort: FloatArray
    velocity: FloatArray
    lower: FloatArray
    upper: FloatArray
    saturated: FloatArray
    torque_peak: FloatArray
    velocity_peak: FloatArray
    velocity_over: FloatArray
    position_overrun: FloatArray
    position_over: FloatArray
    clipped: bool = True
    samples: int = 0

    def __post_init__(self) -> None:
        readonly_fields(self, _PER_JOINT)
        object.__setattr__(self, "joint_names", tuple(self.joint_names))

    @classmethod
    def of_run(
        cls,
        tau: FloatArray,
        q: FloatArray,
        qd: FloatArray,
        effort: FloatArray,
        velocity: FloatArray,
        lower: FloatArray,
        upper: FloatArray,
        joint_names: tuple[str, ...],
        clipped: bool = True,
    ) -> LimitReport:
        """The report of a run that commanded ``tau`` and moved through ``q``, ``qd``.

        Parameters
        ----------
        tau : ndarray, shape (N, n)
            The commanded torques [N·m].
        q, qd : ndarray, shape (N, n)
            The positions [rad] and velocities [rad/s].
        effort, velocity, lower, upper : ndarray, shape (n,)
            The plant's limits.
        joint_names : tuple of str
            The plant's.
        clipped : bool, optional
            Whether the run clipped the command at the limits.

        Returns
        -------
        LimitReport
        """
        n = len(effort)
        if not len(tau):
            zero = np.zeros(n)
            z = zero  # every figure of a run without samples
            return cls(joint_names, effort, velocity, lower, upper, z, z, z, z, z, z, clipped=clipped, samples=0)
        samples = len(tau)
        # per joint along the rows of (n, N) copies, by extremes and counts: NumPy's reductions then run along
        # contiguous samples, with no (N, n) temporaries (the same numbers as |τ| > F, max |τ|, … over the samples)
        tau_t, q_t, qd_t = (np.ascontiguousarray(a.T) for a in (tau, q, qd))
        effort_c, lower_c, upper_c = (np.asarray(a, dtype=float)[:, None] for a in (effort, lower, upper))
        fast = np.asarray(velocity * (1.0 + VELOCITY_TOLERANCE), dtype=float)[:, None]
        with np.errstate(invalid="ignore", divide="ignore"):  # |x| / inf = 0; inf / inf does not occur (finite x)
            q_low, q_high = q_t.min(axis=1), q_t.max(axis=1)
            return cls(
                joint_names,
                effort,
                velocity,
                lower,
                upper,
                # over the samples with a torque (a run stopped by an exception has none at its last sample: NaN)
                saturated=np.count_nonzero((tau_t > effort_c) | (tau_t < -effort_c), axis=1)
                / max(np.count_nonzero(~np.isnan(tau_t[0])), 1),
                torque_peak=np.fmax(np.fmax.reduce(tau_t, axis=1), -np.fmin.reduce(tau_t, axis=1)) / effort,
                velocity_peak=np.maximum(qd_t.max(axis=1), -qd_t.min(axis=1)) / velocity,
                velocity_over=np.count_nonzero((qd_t > fast) | (qd_t < -fast), axis=1) / samples,
                # max over the samples of max(lower − q, q − upper, 0)
                position_overrun=np.maximum(np.maximum(lower - q_low, q_high - upper), 0.0),
                position_over=np.count_nonzero((q_t < lower_c) | (q_t > upper_c), axis=1) / samples,
                clipped=clipped,
                samples=samples,
            )

    # ------------------------------------------------------------------------------------------ verdicts
    @property
    def n(self) -> int:
        return len(self.effort)

    def _name(self, j: int) -> str:
        return self.joint_names[j] if j < len(self.joint_names) else f"joint {j}"

    def saturated_joints(self, share: float = SATURATION_SHARE) -> list[int]:
        """Indices of the joints whose torque is at its limit on more than a share of the samples.

        Parameters
        ----------
        share : float, optional
            In [0, 1].

        Returns
        -------
        list of int
        """
        return [int(j) for j in np.flatnonzero(self.saturated > share)]

    @property
    def is_saturated(self) -> bool:
        """Some joint's torque sits at its limit on more than :data:`SATURATION_SHARE` of the samples."""
        return bool(self.saturated_joints())

    @property
    def overrun(self) -> bool:
        """Some joint went beyond its velocity limit (past the tolerance) or outside its position range."""
        return bool((self.velocity_over > 0).any() or (self.position_over > 0).any())

    def saturation_text(self) -> str:
        """ "" or, for a saturated run, which joints and on what share of the samples.

        Returns
        -------
        str
        """
        joints = self.saturated_joints()
        if not joints:
            return ""
        each = ", ".join(f"{self._name(j)} {self.saturated[j]:.0%} (peak {self.torque_peak[j]:.3g}×)" for j in joints)
        return f"torque at its limit on most samples: {each}"

    def overrun_texts(self) -> list[str]:
        """One line per limit overrun: which joint, how far and on what share of the samples.

        Returns
        -------
        list of str
        """
        out = []
        for j in np.flatnonzero(self.velocity_over > 0).tolist():
            out.append(
                f"{self._name(j)} over its velocity limit ({self.velocity[j]:.3g}) on {self.velocity_over[j]:.1%} "
                f"of samples, peak {self.velocity_peak[j]:.0%} of it"
            )
        for j in np.flatnonzero(self.position_over > 0).tolist():
            out.append(
                f"{self._name(j)} outside its position range [{self.lower[j]:.3g}, {self.upper[j]:.3g}] on "
                f"{self.position_over[j]:.1%} of samples, by up to {self.position_overrun[j]:.3g}"
            )
        return out

    def as_dict(self) -> dict[str, object]:
        """Plain lists and numbers (for JSON).

        Returns
        -------
        dict of str
        """
        out: dict[str, object] = {name: getattr(self, name).tolist() for name in _PER_JOINT}
        out.update(joint_names=list(self.joint_names), clipped=self.clipped, samples=self.samples)
        return out

    def __repr__(self) -> str:
        rows = [
            f"  {self._name(j):24s} sat {self.saturated[j]:6.1%}  |τ|/lim {self.torque_peak[j]:6.3g}  "
            f"|q̇|/lim {self.velocity_peak[j]:6.3g}  q beyond {self.position_overrun[j]:.3g}"
            for j in range(self.n)
        ]
        return "LimitReport(\n" + "\n".join(rows) + "\n)"


def check_limits(limits: LimitReport, stacklevel: int = 3) -> None:
    """Warn (:class:`~armctl.errors.SimulationWarning`) if the run was saturated or overran a limit."""
    sat = limits.saturation_text()
    if sat:
        how = (
            "the motors gave their limit instead of the command"
            if limits.clipped
            else "with saturate=False the plant was given torques its motors cannot produce"
        )
        warnings.warn(
            f"{sat}: {how}, so the controller's law did not hold on those samples (res.status == 'saturated', "
            "per joint in res.limits). Lower the gains, slow the reference or check the torque limits",
            SimulationWarning,
            stacklevel=stacklevel,
        )
    over = limits.overrun_texts()
    if over:
        warnings.warn(
            "the run went beyond the plant's limits: " + "; ".join(over) + " (per joint in res.limits)",
            SimulationWarning,
            stacklevel=stacklevel,
        )
