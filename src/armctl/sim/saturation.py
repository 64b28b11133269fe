"""`Saturation`: the torque a plant holds over a control period, from the controller's τ_k.

τ_k is checked to be finite, then held as

    sat(τ_k)_i = max(min(τ_k,i, τ̄_i), −τ̄_i)      (``saturate``; τ_k itself otherwise)

with τ̄ the model's effort limits (an infinite τ̄_i leaves joint i as it is), and recorded as the run's applied torque
(``SimResult.tau_applied``). A τ_k that is not finite is held by no engine: the loop stops the run at sample k as
diverged.

Every engine holds τ_k through this rule (:meth:`Engine.advance_period
<armctl.sim.engine.Engine.advance_period>`): the Python and MuJoCo engines call :meth:`Saturation.hold`; the generated
engine runs its C transcription, ``step_period.c``'s ``armctl_hold``, inside the same call as the period it holds the
torque over. A change to one is a change to the other (tests/sim/test_period.py compares them on torques within,
at and beyond the limits, infinite and NaN ones, and infinite limits).
"""

from __future__ import annotations

import math
import operator

import numpy as np

from armctl._checks import FloatArray


class Saturation:
    """The rule that turns τ_k into the torque held (see the module), writing it into row k of ``applied``.

    Parameters
    ----------
    applied : (samples, n) ndarray
        The run's applied torques [N·m or N] (the record's ``tau_applied``), written row by row.
    limit : (n,) ndarray
        The effort limits τ̄ [N·m or N] (inf: none).
    saturate : bool
        Clip at τ̄ (False: τ_k is held as it is, however large).
    """

    def __init__(self, applied: FloatArray, limit: FloatArray, saturate: bool) -> None:
        self.applied = applied
        self.limit = np.array(limit, dtype=float)
        self.saturate = bool(saturate)
        #: clipping can change a torque (saturate, and some limit is finite)
        self.clips = self.saturate and bool(np.isfinite(self.limit).any())
        self._limits = self.limit.tolist()
        self._lowest = min(self._limits, default=math.inf)  # |τ| below it needs no clipping
        self._upper, self._lower = self.limit, -self.limit

    def hold(self, k: int, tau: FloatArray) -> FloatArray | None:
        """The torque held at sample k, sat(τ_k) (written into row k of ``applied``), or None: τ_k is not finite
        (nothing written).

        Parameters
        ----------
        k : int
            The sample.
        tau : (n,) ndarray
            τ_k, float64, as the controller gave it [N·m or N].
        """
        tl = tau.tolist()
        if not math.isfinite(sum(tl)) and not np.isfinite(tau).all():  # (a sum of finite entries can overflow)
            return None
        low = self._lowest
        if self.clips and (max(tl) > low or -min(tl) > low) and any(map(operator.gt, map(abs, tl), self._limits)):
            applied = self.applied[k]  # np.clip(τ, −τ̄, τ̄) written into the row (two ufuncs: a third of np.clip's time)
            np.minimum(tau, self._upper, out=applied)
            np.maximum(applied, self._lower, out=applied)
            return applied
        self.applied[k] = tau
        return tau
