"""`ErrorIntegral`: ∫e dt accumulated at the control rate, for the controllers with an integral term."""

from __future__ import annotations

import numpy as np

from armctl._checks import FloatArray


class ErrorIntegral:
    """The integral of an error, by the rectangle rule over the time between successive calls (the first
    call only starts the clock)."""

    def __init__(self, n: int) -> None:
        self.n = n
        self.reset()

    def reset(self) -> None:
        self.value = np.zeros(self.n)
        self._t: float | None = None

    def update(self, t: float, e: FloatArray) -> FloatArray:
        """Add e·(t − t_previous) and return the integral."""
        if self._t is not None:
            self.value += e * (t - self._t)
        self._t = t
        return self.value
