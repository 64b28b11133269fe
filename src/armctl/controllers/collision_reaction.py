"""`CollisionReaction`: a controller that watches for collisions with a :class:`MomentumObserver` and reacts.

At every control instant the observer is updated with the measured q, q̇ and the torque applied over the last period
(``"tau_applied"``, declared in ``reads``). Until it detects a collision the wrapped controller runs; from the
detection on, the reaction (Haddadin et al., T-RO 2017, sec. VI):

===============  ==============================================================================================
``"gravity"``    τ = g(q) − D q̇: the arm stops pushing and comes to rest, floating under its own compensated weight
``"reflex"``     τ = g(q) − D q̇ − K_R r: the estimated external torque r is amplified in the direction it pushes
                 the arm, which retreats from the contact until r has decayed
callable         ``reaction(t, q, qd, ref, observer) -> τ``: your own
===============  ==============================================================================================

with g from the observer's model. Each step logs ``residual`` (n,), ``collision`` (0 or 1) and, with
``log_wrench=True``, ``wrench_estimate`` (6,): the observer's h_e at the tool frame (NaN where J is singular).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, boolean, nonnegative_vector
from armctl.controllers.base import Controller
from armctl.controllers.collision import explaining_wrench
from armctl.controllers.momentum_observer import MomentumObserver
from armctl.errors import InvalidParameterError, SingularConfigurationError
from armctl.references import Reference

#: the built-in reactions
REACTIONS = ("gravity", "reflex")


class CollisionReaction(Controller):
    """Run ``controller`` until ``observer`` detects a collision, then react (see the module).

    Parameters
    ----------
    controller : Controller
        The nominal controller (it reads q and q̇ only).
    observer : MomentumObserver
        The observer, with collision thresholds; its model is the one g(q) is taken from.
    reaction : {"gravity", "reflex"} or callable, optional
        What to do after a detection (default ``"gravity"``).
    damping : float or (n,) array_like, optional
        D [N·m·s/rad] of the reaction, ≥ 0 (default 5).
    reflex_gain : float or (n,) array_like, optional
        K_R (dimensionless) of ``"reflex"``, ≥ 0 (default 1).
    log_wrench : bool, optional
        Log the observer's tool wrench at every step (an SVD of J per step; default False).

    Raises
    ------
    InvalidParameterError
        ``controller`` is not a Controller, ``observer`` not a MomentumObserver or without thresholds, the two
        have other numbers of joints, an unknown reaction, a negative damping or reflex gain.
    """

    reads: frozenset[str] = frozenset({"tau_applied"})

    def __init__(
        self,
        controller: Controller,
        observer: MomentumObserver,
        reaction: str | Callable[..., ArrayLike] = "gravity",
        damping: ArrayLike = 5.0,
        reflex_gain: ArrayLike = 1.0,
        log_wrench: bool = False,
    ) -> None:
        if not isinstance(controller, Controller):
            raise InvalidParameterError(
                f"controller must be an armctl Controller, got {type(controller).__name__}", value=controller
            )
        if not isinstance(observer, MomentumObserver):
            raise InvalidParameterError(
                f"observer must be a MomentumObserver, got {type(observer).__name__}", value=observer
            )
        if observer.thresholds is None:
            raise InvalidParameterError(
                "the observer has no collision thresholds: give MomentumObserver(..., thresholds=[N·m])",
                value=observer,
            )
        if controller.n != observer.n:
            raise InvalidParameterError(
                f"the controller has {controller.n} joints, the observer {observer.n}", value=observer
            )
        if controller.reads:
            raise InvalidParameterError(
                f"{type(controller).__name__} reads {sorted(controller.reads)}: CollisionReaction wraps controllers "
                f"that read q and q̇ only",
                value=controller,
            )
        if not (callable(reaction) or reaction in REACTIONS):
            raise InvalidParameterError(
                f"reaction must be one of {REACTIONS} or a callable (t, q, qd, ref, observer) -> tau, got {reaction!r}",
                value=reaction,
            )
        super().__init__(observer.dynamics)
        self.controller = controller
        self.observer = observer
        self.reaction = reaction
        self.damping = nonnegative_vector(damping, self.n, "damping")
        self.reflex_gain = nonnegative_vector(reflex_gain, self.n, "reflex_gain")
        self.log_wrench = boolean(log_wrench, "log_wrench")
        self._nan6 = np.full(6, np.nan)

    def reset(self) -> None:
        super().reset()
        self.controller.reset()
        self.observer.reset()

    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        obs = self.observer
        r = obs.step(t, q, qd, self.measured("tau_applied"))
        hit = obs.collision is not None
        if not hit:
            tau = np.asarray(self.controller.compute(t, q, qd, ref), dtype=float)
        elif callable(self.reaction):
            tau = np.asarray(self.reaction(t, q, qd, ref, obs), dtype=float)
        else:
            tau = obs.dynamics.kernel.gravity(q) - self.damping * qd
            if self.reaction == "reflex":
                tau -= self.reflex_gain * r
        log: dict[str, Any] = {"residual": r, "collision": 1.0 if hit else 0.0}
        if self.log_wrench:
            try:
                log["wrench_estimate"] = explaining_wrench(obs.dynamics.kernel.jacobian(q, None), r, 1e-3)
            except SingularConfigurationError:
                log["wrench_estimate"] = self._nan6
        self.last_log = log
        return tau
