"""`Quintic`: a minimum-jerk point-to-point move (zero velocity and acceleration at both ends)."""

from __future__ import annotations

from dataclasses import dataclass, field

from numpy.typing import ArrayLike

from armctl._checks import FloatArray, scalar
from armctl.references._rows import row
from armctl.references.reference import Reference


def minimum_jerk(t: float, t0: float, duration: float) -> tuple[float, float, float]:
    """The minimum-jerk profile at time ``t`` [s] of a move starting at ``t0`` [s] and lasting ``duration`` [s]:
    (σ̂, σ̂', σ̂'') with σ̂ = σ³(10 − 15σ + 6σ²), σ = clip((t − t0)/T, 0, 1), and its first two time derivatives
    [1/s, 1/s²], which are exactly 0 at both ends and outside the move. A move from a to b is a + (b − a) σ̂.
    """
    s = min(max((t - t0) / duration, 0.0), 1.0)
    return (
        s**3 * (10 - 15 * s + 6 * s * s),
        30 * s * s * (1 - s) ** 2 / duration,
        60 * s * (1 - s) * (1 - 2 * s) / duration**2,
    )


@dataclass(frozen=True, eq=False, init=False)
class Quintic:
    """Minimum-jerk move from ``q0`` to ``q1`` in ``duration`` [s] starting at ``t0``, holding before and after:
    q_d = q0 + (q1 − q0)(10σ³ − 15σ⁴ + 6σ⁵), σ = (t − t0)/T.

    Parameters
    ----------
    q0, q1 : array_like, shape (n,)
        Start and end joint positions [rad or m] (a scalar: one joint), real and finite.
    duration : float
        T [s], > 0.
    t0 : float, optional
        Start time [s] (default 0).

    Raises
    ------
    ShapeError
        q0 is not a vector of at least one entry, or q1 has another length.
    InvalidParameterError, NonFiniteError
        A value is not a real number, is NaN or inf, or duration is not positive.
    """

    q0: FloatArray
    q1: FloatArray
    duration: float
    t0: float
    _d: FloatArray = field(init=False, repr=False)

    def __init__(self, q0: ArrayLike, q1: ArrayLike, duration: float, t0: float = 0.0) -> None:
        start = row(q0, "q0")
        end = row(q1, "q1", start.size)
        object.__setattr__(self, "q0", start)
        object.__setattr__(self, "q1", end)
        object.__setattr__(self, "duration", scalar(duration, "duration", positive=True))
        object.__setattr__(self, "t0", scalar(t0, "t0"))
        object.__setattr__(self, "_d", end - start)

    def __call__(self, t: float) -> Reference:
        """The reference at time ``t`` [s] (a real finite scalar)."""
        if t.__class__ is not float or t - t != 0.0:  # t - t: NaN for NaN and ±inf
            t = scalar(t, "t")  # a real finite scalar, or raise naming t
        p, v, a = minimum_jerk(t, self.t0, self.duration)
        return Reference(self.q0 + p * self._d, v * self._d, a * self._d)
