"""Targets of frame tasks: constant (``set_target``) or a trajectory, a callable of time (``set_trajectory``)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from armctl._checks import FLOAT, FloatArray, matrix, vector
from armctl.errors import InvalidParameterError

#: A trajectory maps t [s] to (value, velocity, acceleration); velocity and acceleration may be None (zero).
Trajectory = Callable[[float], tuple[Any, Any, Any]]

#: largest |(R Rᵀ − I)_ij| of a rotation target: rounding in the 4th decimal (0.7071) passes, a scaled or
#: skewed matrix does not
ROTATION_TOL = 1e-4


def rotation_gram(a: Any, b: Any, c: Any, d: Any, e: Any, f: Any, g: Any, h: Any, i: Any) -> tuple[Any, ...]:
    """The upper triangle of R Rᵀ − I (diagonal first) for R = [[a, b, c], [d, e, f], [g, h, i]]: on floats (the
    Python check) or on CasADi symbols (its generated counterpart, :mod:`~armctl.controllers.osc.target_code`)."""
    return (
        a * a + b * b + c * c - 1.0,
        d * d + e * e + f * f - 1.0,
        g * g + h * h + i * i - 1.0,
        a * d + b * e + c * f,
        a * g + b * h + c * i,
        d * g + e * h + f * i,
    )


def rotation_det(a: Any, b: Any, c: Any, d: Any, e: Any, f: Any, g: Any, h: Any, i: Any) -> Any:
    """det R for R = [[a, b, c], [d, e, f], [g, h, i]], on floats or CasADi symbols (as :func:`rotation_gram`)."""
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)


def rotation_defect(entries: list[float], shape: tuple[int, ...]) -> str | None:
    """Why the row-major ``entries`` of a 3×3 rotation or 4×4 pose are not one (None if they are): R Rᵀ = I
    to :data:`ROTATION_TOL`, det R = +1 (not a reflection), a pose's last row [0, 0, 0, 1]. On Python floats:
    a 3×3 is too small for NumPy calls to pay off."""
    if shape == (4, 4):
        if entries[12:] != [0.0, 0.0, 0.0, 1.0]:
            return f"the last row of a pose must be [0, 0, 0, 1], got {entries[12:]}"
        a, b, c, _, d, e, f, _, g, h, i = entries[:11]
    else:
        a, b, c, d, e, f, g, h, i = entries
    gram = rotation_gram(a, b, c, d, e, f, g, h, i)
    tol = ROTATION_TOL
    if not (
        -tol <= gram[0] <= tol
        and -tol <= gram[1] <= tol
        and -tol <= gram[2] <= tol  # chained tests:
        and -tol <= gram[3] <= tol
        and -tol <= gram[4] <= tol
        and -tol <= gram[5] <= tol
    ):  # no calls
        worst = max(abs(x) for x in gram)
        return f"its rotation is not orthonormal: |R Rᵀ − I| reaches {worst:.3g} (tolerance {ROTATION_TOL:g})"
    if rotation_det(a, b, c, d, e, f, g, h, i) < 0.0:
        return "its rotation is a reflection (det R = −1)"
    return None


class TargetHolder:
    """Holds a target (value, velocity, acceleration) of a frame task: ``value`` a vector of ``size`` or a
    matrix of ``shape`` (a rotation or a pose), velocity and acceleration vectors of ``rate`` entries."""

    def __init__(self, owner: str, value_shape: tuple[int, ...], rate: int) -> None:
        self.owner = owner
        self.value_shape = value_shape
        self.rate = rate
        self._constant: tuple[FloatArray, FloatArray, FloatArray] | None = None
        self._trajectory: Trajectory | None = None
        #: a trajectory's last time read and its checked output: read once per control step, whoever asks (the
        #: QP's rows, the step's log)
        self._read: tuple[float, tuple[FloatArray, FloatArray, FloatArray]] | None = None

    def _check(self, value: Any, velocity: Any, acceleration: Any) -> tuple[FloatArray, FloatArray, FloatArray]:
        shape = self.value_shape
        try:  # float arrays of the right shapes, all finite (one sum: NaN/inf propagate into it), are taken as given
            if (
                value.dtype == FLOAT
                and velocity.dtype == FLOAT
                and acceleration.dtype == FLOAT
                and value.shape == shape
                and velocity.shape == acceleration.shape == (self.rate,)
            ):
                entries = value.ravel().tolist()
                if math.isfinite(sum(entries) + sum(velocity.tolist()) + sum(acceleration.tolist())) and (
                    len(shape) == 1 or rotation_defect(entries, shape) is None
                ):
                    return value, velocity, acceleration
        except (AttributeError, TypeError):  # not arrays; an np.matrix (whose tolist is nested); object entries
            pass
        if len(shape) == 1:
            val = vector(value, shape[0], f"{self.owner}: target")
        else:
            val = matrix(value, shape, f"{self.owner}: target")
            why = rotation_defect(val.ravel().tolist(), shape)
            if why is not None:
                kind = "pose" if shape == (4, 4) else "rotation"
                hint = (
                    ""
                    if why.startswith("the last row")
                    else "; orthonormalise it (e.g. pinocchio.Quaternion(R).normalized().matrix())"
                )
                raise InvalidParameterError(f"{self.owner}: the target is not a {kind} — {why}{hint}", value=value)
        vel = np.zeros(self.rate) if velocity is None else vector(velocity, self.rate, f"{self.owner}: velocity")
        acc = (
            np.zeros(self.rate)
            if acceleration is None
            else vector(acceleration, self.rate, f"{self.owner}: acceleration")
        )
        return val, vel, acc

    def set(self, value: Any, velocity: Any = None, acceleration: Any = None) -> None:
        self._constant = self._check(value, velocity, acceleration)
        self._trajectory = None
        self._read = None

    def follow(self, fn: Trajectory) -> None:
        if not callable(fn):
            raise InvalidParameterError(
                f"{self.owner}: a trajectory must be callable t -> (value, velocity, "
                f"acceleration), got {type(fn).__name__}",
                value=fn,
            )
        self._trajectory = fn
        self._constant = None
        self._read = None

    @property
    def is_set(self) -> bool:
        return self._constant is not None or self._trajectory is not None

    def _call(self, fn: Trajectory, t: float) -> tuple[Any, Any, Any]:
        out = fn(t)
        if not isinstance(out, tuple) or len(out) != 3:
            raise InvalidParameterError(
                f"{self.owner}: the trajectory must return (value, velocity, acceleration), got {out!r}", value=out
            )
        return out

    def at(self, t: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The target at time t [s]."""
        if self._trajectory is not None:
            read = self._read
            if read is not None and read[0] == t:
                return read[1]
            checked = self._check(*self._call(self._trajectory, t))
            self._read = (t, checked)
            return checked
        if self._constant is None:
            raise InvalidParameterError(f"{self.owner} has no target: call set_target(...) or set_trajectory(fn) first")
        return self._constant

    def shaped(self, t: float) -> tuple[tuple[FloatArray, FloatArray, FloatArray], bool]:
        """The target at time t [s] for a reader that tests the values itself: a trajectory's new output of float
        arrays of the right shapes as it is, with False (its values not yet checked: pass it to :meth:`confirm`
        before anything else reads the target), or else the checked target (:meth:`at`), with True.

        The generated QP data of :mod:`~armctl.controllers.osc.generated` tests the values in its own code (the
        conditions of :meth:`at`'s check, see :func:`~armctl.controllers.osc.target_code.target_verdict`): a
        target it passes is a valid one, and one it does not pass gets :meth:`at`'s check, with its named error.
        """
        fn = self._trajectory
        if fn is None:
            constant = self._constant
            return (constant, True) if constant is not None else (self.at(t), True)  # at: no target, raises
        read = self._read
        if read is not None and read[0] == t:
            return read[1], True
        out = self._call(fn, t)
        value, velocity, acceleration = out
        if (
            type(value) is np.ndarray
            and type(velocity) is np.ndarray
            and type(acceleration) is np.ndarray
            and value.dtype == FLOAT
            and velocity.dtype == FLOAT
            and acceleration.dtype == FLOAT
            and value.shape == self.value_shape
            and velocity.shape == acceleration.shape == (self.rate,)
        ):
            return out, False
        checked = self._check(value, velocity, acceleration)
        self._read = (t, checked)
        return checked, True

    def confirm(self, t: float, out: tuple[FloatArray, FloatArray, FloatArray], valid: bool) -> None:
        """Take ``out``, what :meth:`shaped` gave unchecked at time t [s], as the target at t: as it is if the
        reader's test found it ``valid``, else after :meth:`at`'s check (which raises its named error if it is not
        a valid target).

        Raises
        ------
        InvalidParameterError, NonFiniteError
            ``valid`` is False and ``out`` is not a valid target.
        """
        self._read = (t, out if valid else self._check(*out))
