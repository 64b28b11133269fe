"""`Trajectory`: a path traversed with a timing law, q(t) = q(s(t)), evaluated as a :class:`~armctl.Reference`.

q̇ = q'(s) ṡ,    q̈ = q'(s) s̈ + q''(s) ṡ².
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, readonly, real_array, scalar, whole_number
from armctl.errors import InvalidParameterError
from armctl.planning.path import Path
from armctl.planning.timing import Timing
from armctl.references import Reference

if TYPE_CHECKING:
    from armctl.planning.verify import LimitCheck


@dataclass(frozen=True, eq=False)
class Samples:
    """A trajectory sampled at m times.

    Attributes
    ----------
    t : ndarray, shape (m,)
        The times [s].
    s, sd, sdd : ndarray, shape (m,)
        The path parameter s, ṡ [1/s] and s̈ [1/s²].
    q, qd, qdd : ndarray, shape (m, n)
        Joint positions, velocities and accelerations.
    dq, ddq : ndarray, shape (m, n)
        The path's derivatives q'(s), q''(s).
    """

    t: FloatArray
    s: FloatArray
    sd: FloatArray
    sdd: FloatArray
    q: FloatArray
    qd: FloatArray
    qdd: FloatArray
    dq: FloatArray
    ddq: FloatArray

    def __len__(self) -> int:
        return int(self.t.shape[0])


class Trajectory:
    """A path traversed with a timing. ``traj(t)`` is the :class:`~armctl.Reference` at time t [s] (at rest at
    the start before 0 and at the end after ``duration``); ``traj.sample(...)`` evaluates many times at once.

    Parameters
    ----------
    path : Path
        The geometric path q(s).
    timing : Timing
        The timing law s(t).
    check : LimitCheck, optional
        The dense verification of the limits, when the trajectory comes from :func:`~armctl.planning.time_optimal`
        or :func:`~armctl.planning.uniform_time_scaling`.
    info : dict, optional
        How it was computed (grid, passes, solve time, …).
    """

    def __init__(
        self, path: Path, timing: Timing, check: LimitCheck | None = None, info: dict[str, Any] | None = None
    ) -> None:
        if not isinstance(path, Path):
            raise InvalidParameterError(f"path must be an armctl.planning.Path, got {type(path).__name__}", value=path)
        if not isinstance(timing, Timing):
            raise InvalidParameterError(
                f"timing must be an armctl.planning.Timing, got {type(timing).__name__}", value=timing
            )
        self.path = path
        self.timing = timing
        self.check = check
        self.info = dict(info or {})

    @property
    def n(self) -> int:
        return self.path.n

    @property
    def duration(self) -> float:
        """T [s]."""
        return self.timing.duration

    def __repr__(self) -> str:
        return f"Trajectory(n={self.n}, duration={self.duration:.4g} s, path={self.path!r})"

    def __call__(self, t: float) -> Reference:
        s, sd, sdd = self.timing.at(t)  # checks t (a real finite scalar)
        q, dq, ddq = self.path.at(s)
        return Reference(q, dq * sd, dq * sdd + ddq * (sd * sd))

    def sample(self, t: ArrayLike | None = None, *, dt: float | None = None, num: int | None = None) -> Samples:
        """The trajectory at many times; give exactly one of the three.

        Parameters
        ----------
        t : array_like, shape (m,), optional
            The times [s].
        dt : float, optional
            Every ``dt`` [s] on [0, T], T included.
        num : int, optional
            ``num`` evenly spaced times from 0 to T.

        Returns
        -------
        Samples

        Raises
        ------
        InvalidParameterError
            None or more than one of them given, or a bad value.
        """
        if sum(x is not None for x in (t, dt, num)) != 1:
            raise InvalidParameterError("give exactly one of t, dt or num", value=(t, dt, num))
        T = self.duration
        if dt is not None:
            step = scalar(dt, "dt", positive=True)
            tt = np.arange(0.0, T, step)
            tt = np.append(tt, T) if tt[-1] < T else tt
        elif num is not None:
            tt = np.linspace(0.0, T, whole_number(num, "num", 2))
        else:
            tt = np.array(real_array(t, "t")).reshape(-1)
        s, sd, sdd = self.timing.evaluate(tt)
        q, dq, ddq = self.path.derivatives(s)
        qd = dq * sd[:, None]
        qdd = dq * sdd[:, None] + ddq * (sd * sd)[:, None]
        return Samples(*(readonly(np.asarray(a)) for a in (tt, s, sd, sdd, q, qd, qdd, dq, ddq)))
