"""Targets of frame tasks: constant (``set_target``) or a trajectory, a callable of time (``set_trajectory``)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from armctl._checks import FloatArray, matrix, vector
from armctl.errors import InvalidParameterError

#: A trajectory maps t [s] to (value, velocity, acceleration); velocity and acceleration may be None (zero).
Trajectory = Callable[[float], tuple[Any, Any, Any]]


class TargetHolder:
    """Holds a target (value, velocity, acceleration) of a frame task: ``value`` a vector of ``size`` or a
    matrix of ``shape`` (a rotation or a pose), velocity and acceleration vectors of ``rate`` entries."""

    def __init__(self, owner: str, value_shape: tuple[int, ...], rate: int) -> None:
        self.owner = owner
        self.value_shape = value_shape
        self.rate = rate
        self._constant: tuple[FloatArray, FloatArray, FloatArray] | None = None
        self._trajectory: Trajectory | None = None

    def _check(self, value: Any, velocity: Any, acceleration: Any) -> tuple[FloatArray, FloatArray, FloatArray]:
        shape = self.value_shape
        try:  # fast path: float arrays of the right shapes, all finite (one sum, NaN/inf propagate into it)
            if (value.shape == shape and velocity.shape == acceleration.shape == (self.rate,)
                    and value.dtype == velocity.dtype == acceleration.dtype == np.float64
                    and math.isfinite(sum(value.ravel().tolist()) + sum(velocity.tolist())
                                      + sum(acceleration.tolist()))):
                return value, velocity, acceleration
        except AttributeError:
            pass
        val = (vector(value, shape[0], f"{self.owner}: target") if len(shape) == 1
               else matrix(value, shape, f"{self.owner}: target"))  # type: ignore[arg-type]
        vel = np.zeros(self.rate) if velocity is None else vector(velocity, self.rate, f"{self.owner}: velocity")
        acc = (np.zeros(self.rate) if acceleration is None
               else vector(acceleration, self.rate, f"{self.owner}: acceleration"))
        return val, vel, acc

    def set(self, value: Any, velocity: Any = None, acceleration: Any = None) -> None:
        self._constant = self._check(value, velocity, acceleration)
        self._trajectory = None

    def follow(self, fn: Trajectory) -> None:
        if not callable(fn):
            raise InvalidParameterError(f"{self.owner}: a trajectory must be callable t -> (value, velocity, "
                                        f"acceleration), got {type(fn).__name__}", value=fn)
        self._trajectory = fn
        self._constant = None

    @property
    def is_set(self) -> bool:
        return self._constant is not None or self._trajectory is not None

    def at(self, t: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The target at time t [s]."""
        if self._trajectory is not None:
            out = self._trajectory(t)
            if not isinstance(out, tuple) or len(out) != 3:
                raise InvalidParameterError(f"{self.owner}: the trajectory must return (value, velocity, "
                                            f"acceleration), got {out!r}", value=out)
            return self._check(*out)
        if self._constant is None:
            raise InvalidParameterError(f"{self.owner} has no target: call set_target(...) or "
                                        "set_trajectory(fn) first")
        return self._constant
