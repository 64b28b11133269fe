"""`Sinusoid`: q_d = c + a sin(2π f t + φ) per joint."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, readonly, scalar
from armctl.references._rows import row
from armctl.references.reference import Reference


@dataclass(frozen=True, eq=False, init=False)
class Sinusoid:
    """q_d = center + amplitude · sin(2π·frequency·t + phase), per joint.

    Parameters
    ----------
    center : array_like, shape (n,)
        The mean joint positions [rad or m] (a scalar: one joint).
    amplitude : array_like, shape (n,) or scalar
        [rad or m]; a scalar applies to every joint.
    frequency : array_like, shape (n,) or scalar
        [Hz]; a scalar applies to every joint.
    phase : array_like, shape (n,) or scalar, optional
        [rad] (default 0).

    Raises
    ------
    ShapeError
        center is not a vector, or another argument has neither one entry nor n.
    InvalidParameterError, NonFiniteError
        A value is not a real number, or is NaN or inf.
    """

    center: FloatArray
    amplitude: FloatArray
    frequency: FloatArray
    phase: FloatArray
    _w: FloatArray = field(init=False, repr=False)
    _aw: FloatArray = field(init=False, repr=False)
    _maww: FloatArray = field(init=False, repr=False)

    def __init__(self, center: ArrayLike, amplitude: ArrayLike, frequency: ArrayLike, phase: ArrayLike = 0.0) -> None:
        # read-only copies: the factors below are formed from them once, so the fields must not change later
        c = readonly(np.array(row(center, "center")))
        a, f, ph = (
            readonly(np.array(row(value, name, c.size, broadcast=True)))
            for name, value in (("amplitude", amplitude), ("frequency", frequency), ("phase", phase))
        )
        for name, arr in (("center", c), ("amplitude", a), ("frequency", f), ("phase", ph)):
            object.__setattr__(self, name, arr)
        # the per-call factors, formed once: ω = 2π f, a ω and −a ω² (a call is then eight vector operations)
        w = 2 * math.pi * f
        object.__setattr__(self, "_w", w)
        object.__setattr__(self, "_aw", a * w)
        object.__setattr__(self, "_maww", -a * w * w)

    def __call__(self, t: float) -> Reference:
        """The reference at time ``t`` [s] (a real finite scalar)."""
        if t.__class__ is not float or t - t != 0.0:  # t - t: NaN for NaN and ±inf
            t = scalar(t, "t")  # a real finite scalar, or raise naming t
        arg = self._w * t
        arg += self.phase
        s = np.sin(arg)
        q = self.amplitude * s
        q += self.center
        s *= self._maww
        return Reference(q, self._aw * np.cos(arg), s)
