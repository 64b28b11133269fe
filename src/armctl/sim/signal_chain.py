"""`SignalChain`: how a raw signal becomes a measurement — noise, a first-order filter, a delay.

Each control period the chain takes the true value x_k and returns what a controller reads:

    x̃_k = x_k + σ ⊙ w_k,                 w_k ~ N(0, I)           (sensor noise)
    y_k = y_{k−1} + α (x̃_k − y_{k−1}),   α = 1 − exp(−2π f_c Δt_c)  (first-order low-pass at f_c; y_0 = x̃_0)
    m_k = y_{k−d}                         (m_k = y_0 for k < d)    (d control periods of delay)

The low-pass is the exact zero-order-hold discretisation of ẏ = 2π f_c (x̃ − y). :func:`armctl.simulate` runs one
chain per signal a controller reads (:class:`~armctl.sim.options.Sensing`); in your own loop, a chain is how you
test a controller against the sensor you will have.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, nonnegative_vector, scalar, vector, whole_number
from armctl.errors import InvalidParameterError


class SignalChain:
    """Noise, an optional first-order low-pass filter and a delay, applied to one signal sample by sample.

    Parameters
    ----------
    dim : int
        The signal's length (6 for a wrench, n for joint torques).
    control_dt : float
        The sampling period Δt_c [s].
    noise : float or (dim,) array_like
        Standard deviation σ of the Gaussian noise, in the signal's units (0: none).
    delay : int
        d: the chain returns the value of d samples earlier (the first one before that).
    cutoff : float, optional
        The filter's cut-off frequency f_c [Hz] (None: no filter).
    seed : int or sequence of int, optional
        Seed of the noise (None: a fresh one).

    Raises
    ------
    InvalidParameterError
        A negative noise, delay or a cut-off that is not positive.
    ShapeError
        ``noise`` or a sample of another length than ``dim``.
    """

    def __init__(
        self,
        dim: int,
        control_dt: float,
        noise: ArrayLike = 0.0,
        delay: int = 0,
        cutoff: float | None = None,
        seed: int | Sequence[int] | None = None,
    ) -> None:
        self.dim = whole_number(dim, "dim", 1)
        self.control_dt = scalar(control_dt, "control_dt", positive=True)
        self.noise = nonnegative_vector(noise, self.dim, "noise (a standard deviation)")
        self.delay = whole_number(delay, "delay (control periods)", 0)
        if cutoff is not None and (not isinstance(cutoff, int | float) or not cutoff > 0 or math.isinf(cutoff)):
            raise InvalidParameterError(
                f"cutoff must be a positive, finite frequency [Hz] or None (no filter), got {cutoff!r}", value=cutoff
            )
        self.cutoff = None if cutoff is None else float(cutoff)
        #: the filter's gain α per sample (1: no filter)
        self.alpha = 1.0 if self.cutoff is None else 1.0 - math.exp(-2.0 * math.pi * self.cutoff * self.control_dt)
        self.seed = seed
        self.reset()

    def reset(self) -> None:
        """Start over: no filter state, no delayed samples, the noise from its seed again."""
        self._rng = np.random.default_rng(self.seed) if self.noise.any() else None
        self._y: FloatArray | None = None
        self._past: deque[FloatArray] = deque(maxlen=self.delay + 1)

    def __call__(self, x: ArrayLike) -> FloatArray:
        """The measurement at this sample of the true value ``x`` (dim,)."""
        value = vector(x, self.dim, "the signal")
        if self._rng is not None:
            value = value + self.noise * self._rng.standard_normal(self.dim)
        y = self._y
        y = value.copy() if y is None or self.alpha == 1.0 else y + self.alpha * (value - y)
        self._y = y
        past = self._past
        past.append(y)
        return past[0]

    def __repr__(self) -> str:
        return (
            f"SignalChain(dim={self.dim}, control_dt={self.control_dt:g}, noise={self.noise.tolist()}, "
            f"delay={self.delay}, cutoff={self.cutoff})"
        )
