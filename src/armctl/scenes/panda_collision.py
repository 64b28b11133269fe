"""``panda_collision``: the Panda swings its tool sideways along a joint-space path that runs through a wall it was
not told about. Computed torque tracks the path; a momentum observer (no force sensor) watches the residual.
Methods:

* ``no_reaction``: computed torque alone — it keeps pushing into the wall as the reference moves on;
* ``gravity``: on detection, switch to gravity compensation with damping (the push stops);
* ``reflex``: on detection, gravity compensation plus the amplified residual (the arm backs away).

The plant is the rigid Panda (no joint friction: the scene is about the contact) and the controller's model is the
plant's own, so the observer's residual in free motion is its discretisation error alone."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from armctl import models
from armctl.controllers.base import Controller
from armctl.controllers.collision_reaction import CollisionReaction
from armctl.controllers.computed_torque import ComputedTorque
from armctl.controllers.momentum_observer import MomentumObserver
from armctl.errors import UnknownNameError
from armctl.references import Quintic
from armctl.scenes.base import Scene

Q_START = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])  # the Panda's "ready" posture
Q_END = Q_START + np.array([0.8, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])  # the shoulder swings the tool 0.22 m along +y
#: the wall's plane y = WALL_Y [m] (normal −y): the tool reaches it about halfway along the path
WALL_Y = 0.12
#: the methods and the default gains of each (kp, kd of the computed torque; the observer's gain [1/s] and
#: thresholds [N·m]; the reaction's damping [N·m·s/rad] and reflex gain)
DEFAULTS: dict[str, Any] = {
    "kp": 400.0,
    "kd": 40.0,
    "observer_gain": 100.0,
    "thresholds": [3.0, 3.0, 3.0, 3.0, 1.0, 1.0, 1.0],
    "damping": [10.0, 10.0, 10.0, 10.0, 1.0, 1.0, 1.0],
    "reflex_gain": 1.0,
}
METHODS = ("no_reaction", "gravity", "reflex")


class CollisionScene(Scene):
    """The ``panda_collision`` scene (see the module). Its methods' gains are any keys of :data:`DEFAULTS` (the
    rest: the defaults); each method's controller is computed torque, wrapped for ``gravity`` and ``reflex`` in a
    :class:`~armctl.controllers.CollisionReaction` that logs the observer's residual and tool wrench. Its
    :meth:`metrics` keep the joint tracking error [rad] and add the collision's measures: ``contact_at`` (first
    sample in contact) and ``detected_at`` [s], ``detection_delay`` [s], ``peak_force`` [N], ``force_after`` (the
    contact force 0.3 s after detection) [N], ``push_impulse`` (∫ |f| dt after detection) [N·s], and
    ``wrench_error`` (the largest error of the observer's tool force against the simulator's while in contact,
    after 5/K_O) [N]. Its parameters are :class:`Scene`'s.
    """

    replay_reads = ("tau_applied",)  # the observer reads the torque applied over the period before
    gain_keys: ClassVar[dict[str, tuple[tuple[str, ...], tuple[str, ...]]]] = {
        m: ((), tuple(DEFAULTS)) for m in METHODS
    }

    def gains(self, method: str) -> dict[str, Any]:
        if method not in self.methods:
            raise UnknownNameError("method", method, self.methods)
        return dict(DEFAULTS)

    def build(self, method: str, gains: dict[str, Any]) -> Controller:
        g = {**DEFAULTS, **gains}
        dyn = self.dynamics("exact")
        ct = ComputedTorque(dyn, g["kp"], g["kd"])
        # the observer watches in every method (no_reaction: a reaction that is the controller itself), so that
        # each run logs its residual and detection
        obs = MomentumObserver(dyn, g["observer_gain"], thresholds=g["thresholds"], period=self.control_dt)
        reaction: Any = method if method != "no_reaction" else (lambda t, q, qd, ref, o: ct.compute(t, q, qd, ref))
        return CollisionReaction(ct, obs, reaction, damping=g["damping"], reflex_gain=g["reflex_gain"], log_wrench=True)

    def scene_measures(self, res: Any, method: str, gains: dict[str, Any] | None = None) -> dict[str, Any]:
        nan = float("nan")
        h = res.contact_force_on_environment
        f = np.linalg.norm(h[:, 0], axis=1) if h.size else np.zeros(len(res.t))
        touch = np.flatnonzero(f > 0)
        hit = np.flatnonzero(res.logs["collision"] > 0) if "collision" in res.logs else np.zeros(0, int)
        k_o = {**DEFAULTS, **(gains or {})}["observer_gain"]
        contact_at = float(res.t[touch[0]]) if touch.size else nan
        detected_at = float(res.t[hit[0]]) if hit.size else nan
        after = res.t >= detected_at if hit.size else np.zeros(len(res.t), bool)
        later = np.flatnonzero(res.t >= detected_at + 0.3) if hit.size else np.zeros(0, int)
        settled = (f > 0) & (res.t >= contact_at + 5.0 / k_o) if touch.size else np.zeros(len(res.t), bool)
        est = res.logs.get("wrench_estimate")
        werr = (
            float(np.nanmax(np.linalg.norm(est[settled, :3] - res.wrench[settled, :3], axis=1)))
            if est is not None and settled.any()
            else nan
        )
        return {
            "contact_at": contact_at,
            "detected_at": detected_at,
            "detection_delay": detected_at - contact_at,
            "peak_force": float(f.max()) if f.size else nan,
            "force_after": float(f[later[0]]) if later.size else nan,
            "push_impulse": float(np.sum(f[after]) * self.control_dt),
            "wrench_error": werr,
            "error_unit": "rad",
        }


def panda_collision() -> Scene:
    """The Panda swinging its tool into an unexpected wall (a Kelvin–Voigt plane of 10 kN/m); computed torque
    with a momentum observer: the methods ``no_reaction``, ``gravity`` and ``reflex`` (:class:`CollisionScene`).

    Returns
    -------
    CollisionScene
    """
    from armctl.sim import KelvinVoigt, Plane

    model = models.panda()
    wall = Plane(KelvinVoigt(1e4, 30.0), normal=(0, -1, 0), point=(0, WALL_Y, 0))
    return CollisionScene(
        "panda_collision",
        "Panda swinging its tool into a wall it does not know of: a momentum observer detects the hit, and the "
        "reaction stops the push",
        plant=model,
        exact=model,
        reduced=model,
        reference=Quintic(Q_START, Q_END, 2.0),
        duration=2.5,
        methods=METHODS,
        q0=Q_START,
        sim_options={"environment": wall},
    )
