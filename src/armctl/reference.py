"""`Reference`: a joint-space reference (q, q̇, q̈) at one instant."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FLOAT, FloatArray, readonly, real_array
from armctl.errors import InvalidParameterError, NonFiniteError, ShapeError


@dataclass(frozen=True, eq=False)  # numpy fields: compare by identity
class Reference:
    """Desired joint positions ``q`` [rad or m], velocities ``qd`` and accelerations ``qdd`` (each (n,),
    read-only). ``qd`` and ``qdd`` default to zeros (a set-point). Each must hold real finite numbers (masked
    arrays are refused: NumPy would pass on the data under the mask), q at least one."""

    q: FloatArray
    qd: FloatArray | None = None
    qdd: FloatArray | None = None

    def __post_init__(self) -> None:
        q, qd, qdd = self.q, self.qd, self.qdd
        # the usual case, built every control period by a reference generator: three float64 vectors of one
        # length with a finite sum (a sum that overflows goes the slow way, which checks entry by entry)
        if (
            q.__class__ is qd.__class__ is qdd.__class__ is np.ndarray
            and q.dtype == FLOAT
            and qd.dtype == FLOAT
            and qdd.dtype == FLOAT
            and q.ndim == 1
            and q.shape == qd.shape == qdd.shape
            and q.shape[0]
        ):
            q, qd, qdd = q.copy(), qd.copy(), qdd.copy()
            if math.isfinite(sum(q.tolist()) + sum(qd.tolist()) + sum(qdd.tolist())):
                q.setflags(write=False)  # (cheaper than through .flags)
                qd.setflags(write=False)
                qdd.setflags(write=False)
                object.__setattr__(self, "q", q)
                object.__setattr__(self, "qd", qd)
                object.__setattr__(self, "qdd", qdd)
                return
        self._checked()

    def _checked(self) -> None:
        """Convert and check the three fields entry by entry, naming what is wrong."""
        if self.q is None:
            raise InvalidParameterError(
                "Reference q must hold real numbers (q is required: the joint positions), got None", value=None
            )
        raw_q = self.q
        if raw_q.__class__ is np.ndarray and raw_q.dtype == FLOAT and raw_q.ndim <= 1:  # the usual case
            q: FloatArray | None = raw_q.reshape(-1)
        else:
            q = np.array(real_array(raw_q, "Reference q")).reshape(-1) if np.ndim(raw_q) <= 1 else None
        if q is None:
            raise ShapeError(f"Reference q must be a vector, got shape {np.shape(self.q)}", value=self.q)
        if not q.shape[0]:
            raise ShapeError(f"Reference q must hold at least one joint position, got {self.q!r}", value=self.q)
        for name in ("q", "qd", "qdd"):
            raw = getattr(self, name)
            if raw is None:
                a = np.zeros_like(q)
            elif raw.__class__ is np.ndarray and raw.dtype == FLOAT:  # the usual case: one copy, no conversion
                a = raw.copy()
            else:
                a = np.array(real_array(raw, f"Reference {name}"))
            if a.ndim == 0:  # a scalar: one joint
                a = a.reshape(1)
            if a.shape != q.shape:
                raise ShapeError(f"Reference {name} must have shape {q.shape} like q, got {np.shape(raw)}", value=raw)
            if not np.isfinite(a).all():
                raise NonFiniteError(f"Reference {name} holds NaN or inf: {a}", value=raw)
            object.__setattr__(self, name, readonly(a))

    @property
    def n(self) -> int:
        return int(self.q.shape[0])

    @classmethod
    def hold(cls, q: ArrayLike) -> Reference:
        """A set-point: q with zero velocity and acceleration (q checked as :class:`Reference` checks it)."""
        return cls(q)  # type: ignore[arg-type]
