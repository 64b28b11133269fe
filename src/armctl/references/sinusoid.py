"""`Sinusoid`: q_d = c + a sin(2π f t + φ) per joint."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, readonly, scalar
from armctl.references._rows import row
from armctl.references.reference import Reference

_PER_JOINT = ("amplitude", "frequency", "phase")


@dataclass(frozen=True, eq=False)
class Sinusoid:
    """q_d = center + amplitude · sin(2π·frequency·t + phase), per joint (amplitude [rad], frequency [Hz])."""

    center: ArrayLike
    amplitude: ArrayLike
    frequency: ArrayLike
    phase: ArrayLike = 0.0

    _w: FloatArray = field(init=False, repr=False)
    _aw: FloatArray = field(init=False, repr=False)
    _maww: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        # read-only copies: the factors below are formed from them once, so the fields must not change later
        c = readonly(np.array(row(self.center, "center")))
        a, f, phase = (readonly(np.array(row(getattr(self, k), k, c.size, broadcast=True))) for k in _PER_JOINT)
        for name, value in zip(("center", *_PER_JOINT), (c, a, f, phase), strict=True):
            object.__setattr__(self, name, value)
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
