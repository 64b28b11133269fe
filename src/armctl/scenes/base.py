"""`Scene`: a standard closed-loop setup — the true plant, what the controller knows, environment, reference,
duration and rates — and the controllers that run on it.

A scene models no more than it needs: the plant carries what the scene is about (a payload, stiction, a
table), the controller-side models only what a controller could know. Methods:

* ``pd_gravity``, ``computed_torque``, ``passivity``: on the scene's ``exact`` model (everything a
  controller could know: the plant without its simulation-only details);
* ``computed_torque_reduced``: computed torque on the scene's ``reduced`` model (wrong or simplified on
  purpose: no payload, no rotors, no friction — the scene says which);
* ``adaptive``: Slotine–Li starting from the reduced model's parameters;
* ``osc_qp``, ``osc_closed_form``: operational-space control (contact scenes).

Gains come from the presets in ``controllers/`` (see :mod:`armctl.tuning.presets`) unless given.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from armctl.controllers import Adaptive, ComputedTorque, Controller, PassivityBased, PDGravity
from armctl.dynamics.base import Dynamics
from armctl.errors import UnknownNameError
from armctl.model.robot import RobotModel
from armctl.reference import Reference
from armctl.tuning.presets import load_preset

JOINT_METHODS = ("pd_gravity", "computed_torque", "computed_torque_reduced", "passivity", "adaptive")


@dataclass
class Scene:
    name: str
    description: str
    plant: RobotModel
    exact: RobotModel
    reduced: RobotModel
    reference: Callable[[float], Reference]
    duration: float
    methods: tuple[str, ...] = JOINT_METHODS
    control_dt: float = 1e-3
    dt: float | None = None
    integrator: str = "rk4"
    q0: Any = None
    sim_options: dict[str, Any] = field(default_factory=dict)
    builders: dict[str, Callable[[Scene, dict[str, Any]], Controller]] = field(default_factory=dict)
    backend: str = "pinocchio"

    def dynamics(self, which: str = "exact") -> Dynamics:
        """Dynamics of the ``plant``, ``exact`` or ``reduced`` model (pickles by rebuilding)."""
        return Dynamics({"plant": self.plant, "exact": self.exact, "reduced": self.reduced}[which],
                        backend=self.backend)

    def gains(self, method: str) -> dict[str, Any]:
        return dict(load_preset(self.name, method)["gains"])

    def controller(self, method: str, gains: dict[str, Any] | None = None) -> Controller:
        if method not in self.methods:
            raise UnknownNameError("method", method, self.methods)
        g = self.gains(method) if gains is None else dict(gains)
        if method in self.builders:
            return self.builders[method](self, g)
        if method == "pd_gravity":
            return PDGravity(self.dynamics("exact"), g["kp"], g["kd"], g.get("ki"))
        if method in ("computed_torque", "computed_torque_reduced"):
            dyn = self.dynamics("exact" if method == "computed_torque" else "reduced")
            return ComputedTorque(dyn, g["kp"], g["kd"], g.get("ki"))
        if method == "passivity":
            return PassivityBased(self.dynamics("exact"), g["lam"], g["kd"])
        if method == "adaptive":
            return Adaptive(self.dynamics("reduced"), g["lam"], g["kd"], g["gamma"],
                            projection=bool(g.get("projection", True)), sigma=float(g.get("sigma", 0.0)))
        raise UnknownNameError("method", method, self.methods)  # pragma: no cover

    def run(self, method: str, gains: dict[str, Any] | None = None, **overrides: Any) -> Any:
        """Simulate ``method`` on this scene; ``overrides`` go to :func:`armctl.sim.simulate`."""
        from armctl.sim import simulate

        options = {"control_dt": self.control_dt, "dt": self.dt, "integrator": self.integrator, "q0": self.q0,
                   **self.sim_options, **overrides}
        return simulate(self.dynamics("plant"), self.controller(method, gains), self.reference, self.duration,
                        **options)

    def metrics(self, res: Any, method: str, gains: dict[str, Any] | None = None,
                timing_samples: int = 200) -> dict[str, Any]:
        """Tracking error (RMS, max) [rad], torque RMS [N·m], share of samples whose command exceeds the
        effort limits, divergence, and the controller's compute time per step [s], measured by replaying a
        contiguous window of recorded states (from the middle of the run, as a loop would see them: warm
        starts stay warm) through a fresh controller, so the simulator's own cost is not counted."""
        want = np.array([self.reference(t).q for t in res.t])
        err = np.abs(res.q - want) if len(res.t) else np.zeros((0, self.plant.n))
        limit = self.plant.effort_limit
        over = np.abs(res.tau) > limit * (1 + 1e-9) if len(res.t) else np.zeros((0, 1), bool)
        ctrl = self.controller(method, gains)
        count = min(timing_samples, len(res.t))
        first = max((len(res.t) - count) // 2, 0)
        idx = np.arange(first, first + count)
        refs = [self.reference(float(res.t[k])) for k in idx]
        t0 = time.perf_counter()
        for k, r in zip(idx, refs, strict=True):
            ctrl(float(res.t[k]), res.q_measured[k], res.qd_measured[k], r)
        step = (time.perf_counter() - t0) / max(len(idx), 1)
        return {"rms_error": float(np.sqrt((err**2).mean())) if err.size else float("nan"),
                "max_error": float(err.max()) if err.size else float("nan"),
                "torque_rms": float(np.sqrt((res.tau_applied**2).mean())) if len(res.t) else float("nan"),
                "limit_violation_share": float(over.any(axis=1).mean()) if len(res.t) else 0.0,
                "diverged": bool(res.diverged), "diverged_at": res.diverged_at, "compute_s": step}
