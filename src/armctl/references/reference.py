"""`Reference`: a joint-space reference (q, q̇, q̈) at one instant."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FLOAT, FloatArray, readonly, real_array
from armctl.errors import InvalidParameterError, NonFiniteError, ShapeError


@dataclass(frozen=True, eq=False, init=False)  # numpy fields: compare by identity
class Reference:
    """Desired joint positions ``q`` [rad or m], velocities ``qd`` [rad/s or m/s] and accelerations ``qdd``
    [rad/s² or m/s²] at one instant (each (n,), read-only copies). Each must hold real finite numbers (masked
    arrays are refused: NumPy would pass on the data under the mask), q at least one.

    Parameters
    ----------
    q : array_like, shape (n,)
        Joint positions (a scalar: one joint).
    qd, qdd : array_like, shape (n,), optional
        Velocities and accelerations; None (the default) gives zeros, a set-point.

    Raises
    ------
    ShapeError
        q is not a vector of at least one entry, or qd / qdd has another shape.
    InvalidParameterError, NonFiniteError
        An entry is not a real number, or is NaN or inf.
    """

    q: FloatArray
    qd: FloatArray
    qdd: FloatArray

    def __init__(self, q: ArrayLike, qd: ArrayLike | None = None, qdd: ArrayLike | None = None) -> None:
        # the usual case, built every control period by a reference generator: three float64 vectors of one
        # length with a finite sum (a sum that overflows goes to _checked, which checks entry by entry)
        if (
            type(q) is np.ndarray
            and type(qd) is np.ndarray
            and type(qdd) is np.ndarray
            and q.dtype == FLOAT
            and qd.dtype == FLOAT
            and qdd.dtype == FLOAT
            and q.ndim == 1
            and q.shape == qd.shape == qdd.shape
            and q.shape[0]
        ):
            pos, vel, acc = q.copy(), qd.copy(), qdd.copy()
            if math.isfinite(sum(pos.tolist()) + sum(vel.tolist()) + sum(acc.tolist())):
                pos.setflags(write=False)
                vel.setflags(write=False)
                acc.setflags(write=False)
                object.__setattr__(self, "q", pos)
                object.__setattr__(self, "qd", vel)
                object.__setattr__(self, "qdd", acc)
                return
        elif (  # a set-point: a float64 vector with a finite sum, zero velocity and acceleration
            qd is None and qdd is None and type(q) is np.ndarray and q.dtype == FLOAT and q.ndim == 1 and q.shape[0]
        ):
            pos = q.copy()
            if math.isfinite(sum(pos.tolist())):
                pos.setflags(write=False)
                zero = np.zeros(q.shape[0])
                zero.setflags(write=False)
                object.__setattr__(self, "q", pos)
                object.__setattr__(self, "qd", zero)
                object.__setattr__(self, "qdd", zero)
                return
        self._checked(q, qd, qdd)

    def _checked(self, raw_q: ArrayLike, raw_qd: ArrayLike | None, raw_qdd: ArrayLike | None) -> None:
        """Convert and check the three arguments entry by entry, naming what is wrong."""
        if raw_q is None:
            raise InvalidParameterError(
                "Reference q must hold real numbers (q is required: the joint positions), got None", value=None
            )
        if type(raw_q) is np.ndarray and raw_q.dtype == FLOAT and raw_q.ndim <= 1:  # the usual case
            q: FloatArray | None = raw_q.reshape(-1)
        else:
            q = np.array(real_array(raw_q, "Reference q")).reshape(-1) if np.ndim(raw_q) <= 1 else None
        if q is None:
            raise ShapeError(f"Reference q must be a vector, got shape {np.shape(raw_q)}", value=raw_q)
        if not q.shape[0]:
            raise ShapeError(f"Reference q must hold at least one joint position, got {raw_q!r}", value=raw_q)
        for name, raw in (("q", raw_q), ("qd", raw_qd), ("qdd", raw_qdd)):
            if raw is None:
                a = np.zeros_like(q)
            elif type(raw) is np.ndarray and raw.dtype == FLOAT:  # the usual case: one copy, no conversion
                a = raw.copy()
            else:
                a = np.array(real_array(raw, f"Reference {name}"))
            given = a.shape
            if a.ndim == 0:  # a scalar: one joint
                a = a.reshape(1)
            if a.shape != q.shape:
                raise ShapeError(f"Reference {name} must have shape {q.shape} like q, got {given}", value=raw)
            if not np.isfinite(a).all():
                raise NonFiniteError(f"Reference {name} holds NaN or inf: {a}", value=raw)
            object.__setattr__(self, name, readonly(a))

    @property
    def n(self) -> int:
        """The number of joints."""
        return int(self.q.shape[0])

    @classmethod
    def hold(cls, q: ArrayLike) -> Reference:
        """A set-point: ``q`` with zero velocity and acceleration.

        Parameters
        ----------
        q : array_like, shape (n,)
            Joint positions [rad or m], checked as :class:`Reference` checks them.

        Returns
        -------
        Reference
        """
        return cls(q)
