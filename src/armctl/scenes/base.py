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

import inspect
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from armctl._checks import boolean, whole_number
from armctl.controllers import Adaptive, ComputedTorque, Controller, PassivityBased, PDGravity
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError, UnknownNameError
from armctl.model.robot import RobotModel
from armctl.reference import Reference
from armctl.tuning.presets import load_preset

JOINT_METHODS = ("pd_gravity", "computed_torque", "computed_torque_reduced", "passivity", "adaptive")
#: the gain keys of each built-in method: (required, optional)
GAIN_KEYS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "pd_gravity": (("kp", "kd"), ("ki",)), "computed_torque": (("kp", "kd"), ("ki",)),
    "computed_torque_reduced": (("kp", "kd"), ("ki",)), "passivity": (("lam", "kd"), ()),
    "adaptive": (("lam", "kd", "gamma"), ("projection", "sigma"))}
#: the models a scene holds
MODELS = ("plant", "exact", "reduced")


def check_gains(method: str, gains: Any, required: tuple[str, ...], optional: tuple[str, ...] = ()) -> dict[str, Any]:
    """``gains`` as a dict; raise if it is not a mapping, has a key that is neither ``required`` nor
    ``optional`` (UnknownNameError listing the valid ones) or lacks a required one."""
    if not isinstance(gains, Mapping):
        raise InvalidParameterError(f"gains of {method!r} must be a dict such as {{'kp': ..., 'kd': ...}}, "
                                    f"got {gains!r}", value=gains)
    valid = (*required, *optional)
    for key in gains:
        if key not in valid:
            raise UnknownNameError(f"{method} gain", key, valid)
    missing = [k for k in required if k not in gains]
    if missing:
        extra = f" (optional: {', '.join(optional)})" if optional else ""
        raise InvalidParameterError(f"gains of {method!r} lack {', '.join(map(repr, missing))}; give "
                                    f"{', '.join(required)}{extra}", value=dict(gains))
    return dict(gains)


@dataclass
class Scene:
    """A standard closed-loop setup: the true ``plant``, the controller-side models (``exact``: the plant's
    own; ``reduced``: with less in it, for the methods that are given a reduced or wrong model), the
    ``reference`` (t → :class:`~armctl.Reference`), ``duration`` [s], rates and integrator, the start ``q0``
    and other :func:`~armctl.sim.simulate` options (``sim_options``: environment, friction, …), and the
    ``methods`` it runs. :meth:`controller` builds a method's controller (gains from the presets unless given),
    :meth:`run` simulates it, :meth:`metrics` measures a run."""

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
        if not isinstance(which, str) or which not in MODELS:
            raise UnknownNameError("scene model", which, MODELS)
        return Dynamics({"plant": self.plant, "exact": self.exact, "reduced": self.reduced}[which],
                        backend=self.backend)

    def gains(self, method: str) -> dict[str, Any]:
        return dict(load_preset(self.name, method)["gains"])

    def controller(self, method: str, gains: dict[str, Any] | None = None) -> Controller:
        """The controller of ``method`` with ``gains`` (default: the preset). The keys of each built-in method
        are in :data:`GAIN_KEYS`; an unknown key or a missing required one is an error, not ignored."""
        if method not in self.methods:
            raise UnknownNameError("method", method, self.methods)
        if method in self.builders:  # a custom builder checks its own gains
            return self.builders[method](self, self.gains(method) if gains is None else dict(gains))
        g = check_gains(method, self.gains(method) if gains is None else gains, *GAIN_KEYS[method])
        if method == "pd_gravity":
            return PDGravity(self.dynamics("exact"), g["kp"], g["kd"], g.get("ki"))
        if method in ("computed_torque", "computed_torque_reduced"):
            dyn = self.dynamics("exact" if method == "computed_torque" else "reduced")
            return ComputedTorque(dyn, g["kp"], g["kd"], g.get("ki"))
        if method == "passivity":
            return PassivityBased(self.dynamics("exact"), g["lam"], g["kd"])
        if method == "adaptive":
            return Adaptive(self.dynamics("reduced"), g["lam"], g["kd"], g["gamma"],
                            projection=boolean(g.get("projection", True), "gains['projection']"),
                            sigma=g.get("sigma", 0.0))
        raise UnknownNameError("method", method, self.methods)  # pragma: no cover

    def run(self, method: str, gains: dict[str, Any] | None = None, **overrides: Any) -> Any:
        """Simulate ``method`` on this scene; ``overrides`` (``duration`` and any option of
        :func:`armctl.sim.simulate`) go to :func:`armctl.sim.simulate` and win over the scene's settings. The
        plant, controller and reference are the scene's (build another scene to change them)."""
        from armctl.sim import simulate

        valid = tuple(p for p in inspect.signature(simulate).parameters if p not in ("plant", "controller",
                                                                                     "reference"))
        for key in overrides:
            if key not in valid:
                raise UnknownNameError("simulate option", key, valid)
        options = {"control_dt": self.control_dt, "dt": self.dt, "integrator": self.integrator, "q0": self.q0,
                   **self.sim_options, **overrides}
        duration = options.pop("duration", self.duration)
        return simulate(self.dynamics("plant"), self.controller(method, gains), self.reference, duration,
                        **options)

    def metrics(self, res: Any, method: str, gains: dict[str, Any] | None = None,
                timing_samples: int = 200) -> dict[str, Any]:
        """Tracking error (RMS, max) [rad], torque RMS [N·m], share of samples whose command exceeds the
        effort limits, divergence, and the controller's compute time per step [s], measured by replaying a
        contiguous window of recorded states (from the middle of the run, as a loop would see them: warm
        starts stay warm) through a fresh controller, so the simulator's own cost is not counted.
        ``timing_samples`` (≥ 1): how many states to replay. A run without samples gives NaN for every measure
        (compute time and limit-violation share included)."""
        timing_samples = whole_number(timing_samples, "timing_samples", 1)
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
        step = (time.perf_counter() - t0) / len(idx) if len(idx) else float("nan")  # nothing to replay
        return {"rms_error": float(np.sqrt((err**2).mean())) if err.size else float("nan"),
                "max_error": float(err.max()) if err.size else float("nan"),
                "torque_rms": float(np.sqrt((res.tau_applied**2).mean())) if len(res.t) else float("nan"),
                "limit_violation_share": float(over.any(axis=1).mean()) if len(res.t) else float("nan"),
                "diverged": bool(res.diverged), "diverged_at": res.diverged_at, "compute_s": step}
