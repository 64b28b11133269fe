"""The integral term of PID-type controllers: `ErrorIntegral` (∫e dt at the control rate) and `PIDGains`."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray
from armctl.controllers.gains import GainSet, gain


class ErrorIntegral:
    """The integral of an error, by the rectangle rule over the time between successive calls (the first
    call only starts the clock). A call at an earlier time than the last (a new run without ``reset``, whose
    clock starts again at 0) restarts the clock: no interval of negative length is added."""

    def __init__(self, n: int) -> None:
        self.n = n
        self.reset()

    def reset(self) -> None:
        self.value = np.zeros(self.n)
        self._t: float | None = None

    def update(self, t: float, e: FloatArray) -> FloatArray:
        """Add e·(t − t_previous) and return the integral."""
        if self._t is not None and t > self._t:
            self.value += e * (t - self._t)
        self._t = t
        return self.value


class PIDGains(GainSet):
    """Mixin of the controllers with K_p, K_d and an optional K_i: checks the gains (scalar, vector or matrix;
    symmetric positive definite), keeps their cheap forms and the error integral. The gains may be reassigned
    between calls (``ctrl.kp = 400.0``): they are checked again and take effect at the next call."""

    n: int
    gain_names: ClassVar[dict[str, bool]] = {"kp": False, "kd": False, "ki": True}
    kp = gain("kp", "K_p (n×n).")
    kd = gain("kd", "K_d (n×n).")
    ki = gain("ki", "K_i (n×n), or None: no integral term.")
    # what set_gains keeps: the compact forms and the matrices
    _kp: FloatArray
    _kd: FloatArray
    _ki: FloatArray | None
    _kp_matrix: FloatArray
    _kd_matrix: FloatArray
    _ki_matrix: FloatArray | None

    def _start(self, kp: ArrayLike, kd: ArrayLike, ki: ArrayLike | None) -> None:
        """The error integral and the gains, for the constructor."""
        self._integral = ErrorIntegral(self.n)
        self.set_gains(kp=kp, kd=kd, ki=ki)

    def _derive(self) -> None:
        # K_p e + K_d ė as one product with the stacked reference and state: F·[q_d; q̇_d; q; q̇], F = [K_p, K_d,
        # −K_p, −K_d] (one concatenation and one product, where the term by term form takes six array operations)
        kp, kd = self._kp_matrix, self._kd_matrix
        self._feedback = np.hstack((kp, kd, -kp, -kd))
        # with an integral the law keeps state: its inputs are checked first whatever its class declares
        self._checks_result = self._ki is None and type(self).result_check  # type: ignore[attr-defined]

    def reset(self) -> None:
        super().reset()  # type: ignore[misc]  # the Controller's, next in the MRO
        self._integral.reset()
