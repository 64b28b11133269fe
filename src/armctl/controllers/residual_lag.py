"""The residual's first-order lag in discrete time: how the momentum observer turns the period's mean external
torque d_k into its estimate r_k.

Continuous, ṙ = K_O (τ_ext − r). Sampled with period h:

* ``"exact"``: the lag under a held input, r_k = γ r_{k−1} + (1 − γ) d_k with γ = exp(−K_O h) ∈ (0, 1), stable
  for every gain; its step response is exactly 1 − exp(−K_O t) at the samples.
* ``"euler"``: the textbook's forward-Euler sum r = K_O (∫(τ + β − r) dt − p + p₀), r_k = (1 − K_O h) r_{k−1} +
  K_O h d_k. Its pole γ = 1 − K_O h is inside the unit circle only for 0 < K_O h < 2 (and positive, so that the
  residual does not alternate in sign, for K_O h ≤ 1): a gain K_O ≥ 2/h is discretely unstable, and refused.
"""

from __future__ import annotations

import numpy as np

from armctl._checks import FloatArray
from armctl.errors import InvalidParameterError

#: the discretizations of the residual's lag
DISCRETIZATIONS = ("exact", "euler")


def lag_pole(gain: FloatArray, h: float, discretization: str) -> FloatArray:
    """γ per joint for the gains K_O [1/s] and the period h [s].

    Parameters
    ----------
    gain : ndarray, shape (n,)
        K_O [1/s].
    h : float
        The period [s].
    discretization : {"exact", "euler"}
        The form.

    Returns
    -------
    ndarray, shape (n,)
    """
    return np.exp(-gain * h) if discretization == "exact" else 1.0 - gain * h


def check_lag_gain(gain: FloatArray, h: float, discretization: str) -> None:
    """Raise if the ``"euler"`` form is unstable for these gains and this period (K_O h ≥ 2).

    Parameters
    ----------
    gain, h, discretization
        As for :func:`lag_pole`.

    Raises
    ------
    InvalidParameterError
        The bound is violated: the error names the largest gain the period allows.
    """
    k = float(gain.max())
    if discretization == "euler" and k * h >= 2.0:
        raise InvalidParameterError(
            f"observer gain K_O = {k:g} 1/s is too large for the period h = {h:g} s: the forward-Euler residual "
            f"r_k = (1 − K_O h) r_(k−1) + K_O h d_k is unstable for K_O h >= 2; use K_O < {2.0 / h:g} 1/s "
            f"(<= {1.0 / h:g} not to ring), or discretization='exact'",
            value=k,
        )
