"""The integral term of PID-type controllers: `ErrorIntegral` (∫e dt at the control rate) and `PIDGains`."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, Gain


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


class PIDGains:
    """Mixin of the controllers with K_p, K_d and an optional K_i: checks the gains (scalar, vector or matrix;
    symmetric positive definite), keeps their cheap forms and the error integral. The gains may be reassigned
    between calls (``ctrl.kp = 400.0``): they are checked again and take effect at the next call."""

    n: int

    kp = Gain("K_p (n×n).")
    kd = Gain("K_d (n×n).")
    ki = Gain("K_i (n×n), or None: no integral term.", optional=True)
    # what the Gain descriptors keep: the compact forms and the matrices
    _kp: FloatArray
    _kd: FloatArray
    _ki: FloatArray | None
    _kp_matrix: FloatArray
    _kd_matrix: FloatArray
    _ki_matrix: FloatArray | None

    def _set_gains(self, kp: ArrayLike, kd: ArrayLike, ki: ArrayLike | None) -> None:
        self._integral = ErrorIntegral(self.n)
        self._ki = None
        self.kp, self.kd, self.ki = kp, kd, ki

    def _gains_changed(self) -> None:
        if not hasattr(self, "_kd"):  # during _set_gains
            return
        # K_p e + K_d ė as one product with the stacked reference and state: F·[q_d; q̇_d; q; q̇], F = [K_p, K_d,
        # −K_p, −K_d] (one concatenation and one product, where the term by term form takes six array operations)
        kp, kd = self._kp_matrix, self._kd_matrix
        self._feedback = np.hstack((kp, kd, -kp, -kd))
        # without an integral the law keeps no state, and a NaN/inf in q_j or q̇_j reaches τ through K_p e or
        # K_d ė (K ≻ 0: a positive diagonal entry multiplies it; in computed torque through v_j and M_jj > 0)
        self._checks_result = self._ki is None and self._own_law()  # type: ignore[attr-defined]  # Controller's, the other base

    def reset(self) -> None:
        super().reset()  # type: ignore[misc]  # the Controller's, next in the MRO
        self._integral.reset()
