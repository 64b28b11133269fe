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
import statistics
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar, TypeVar

import numpy as np

from armctl._checks import boolean, whole_number
from armctl.controllers import Adaptive, ComputedTorque, Controller, Measurement, PassivityBased, PDGravity
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError, UnknownNameError
from armctl.model.robot import RobotModel
from armctl.references import Reference
from armctl.references.quintic import minimum_jerk
from armctl.tuning.presets import load_preset

#: The joint-space control laws a joint-space scene runs, by name (PD + gravity, computed torque on the exact
#: and on a reduced model, passivity-based, adaptive).
JOINT_METHODS = ("pd_gravity", "computed_torque", "computed_torque_reduced", "passivity", "adaptive")
#: the gain keys of each built-in method: (required, optional)
GAIN_KEYS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "pd_gravity": (("kp", "kd"), ("ki",)),
    "computed_torque": (("kp", "kd"), ("ki",)),
    "computed_torque_reduced": (("kp", "kd"), ("ki",)),
    "passivity": (("lam", "kd"), ()),
    "adaptive": (("lam", "kd", "gamma"), ("projection", "sigma")),
}
#: the models a scene holds
MODELS = ("plant", "exact", "reduced")
#: the force/torque sensor's row in ``res.sensor`` (a scene's first sensor)
SENSOR = 0


def check_gains(method: str, gains: Any, required: tuple[str, ...], optional: tuple[str, ...] = ()) -> dict[str, Any]:
    """``gains`` as a dict; raise if it is not a mapping, has a key that is neither ``required`` nor
    ``optional`` (UnknownNameError listing the valid ones) or lacks a required one."""
    if not isinstance(gains, Mapping):
        raise InvalidParameterError(
            f"gains of {method!r} must be a dict such as {{'kp': ..., 'kd': ...}}, got {gains!r}", value=gains
        )
    valid = (*required, *optional)
    for key in gains:
        if key not in valid:
            raise UnknownNameError(f"{method} gain", key, valid)
    missing = [k for k in required if k not in gains]
    if missing:
        extra = f" (optional: {', '.join(optional)})" if optional else ""
        raise InvalidParameterError(
            f"gains of {method!r} lack {', '.join(map(repr, missing))}; give {', '.join(required)}{extra}",
            value=dict(gains),
        )
    return dict(gains)


#: a joint "beyond its velocity limit" in :meth:`Scene.metrics` exceeds it by more than this share (a
#: time-optimal reference runs exactly at the limit, which tracking then grazes)
VELOCITY_TOLERANCE = 0.01


def replay_times(controller: Controller, window: dict[str, Any], passes: int) -> list[float]:
    """Seconds per step of each of ``passes`` replays of ``window`` through ``controller`` (reset first); a window
    with a ``"measurement"`` list (the signals a controller reads, one per step) passes each step its own."""
    out = []
    measured = window.get("measurement")
    for _ in range(passes):
        if callable(getattr(controller, "reset", None)):
            controller.reset()
        t0 = time.perf_counter()
        if measured is None:
            for t, q, qd, r in zip(window["t"], window["q"], window["qd"], window["ref"], strict=True):
                controller(t, q, qd, r)
        else:
            for t, q, qd, r, m in zip(window["t"], window["q"], window["qd"], window["ref"], measured, strict=True):
                controller(t, q, qd, r, measurement=m)
        out.append((time.perf_counter() - t0) / len(window["t"]))
    return out


def diverged_errors(metrics: dict[str, Any]) -> dict[str, Any]:
    """``metrics`` with, for a diverged run, ``rms_error``, ``max_error`` (and ``force_rms_error``, if any) moved
    to ``*_until_divergence`` and set to NaN (a failed run has no tracking error to rank)."""
    if metrics["diverged"]:
        for key in ("rms_error", "max_error", "force_rms_error"):
            if key not in metrics:
                continue
            metrics[f"{key}_until_divergence"] = metrics[key]
            metrics[key] = float("nan")
    return metrics


@dataclass
class Scene:
    """A standard closed-loop setup: a true plant, the models its controllers are given, a reference, and
    the methods it runs. :meth:`controller` builds a method's controller (gains from the presets unless given),
    :meth:`run` simulates it, :meth:`metrics` measures a run.

    Parameters
    ----------
    name : str
        The scene's name (its presets are ``controllers/<name>.<method>.toml``).
    description : str
        What the scene shows.
    plant : RobotModel
        The true arm.
    exact : RobotModel
        The controller-side model that is the plant's own.
    reduced : RobotModel
        The controller-side model with less in it, for the methods that are given a reduced or wrong model.
    reference : callable
        t → :class:`~armctl.Reference`.
    duration : float
        [s].
    methods : tuple of str, optional
        The methods it runs.
    control_dt : float, optional
        The control period [s].
    dt : float, optional
        The integration step [s] (None: the control period).
    integrator : str, optional
        The integration scheme (see :func:`armctl.sim.simulate`).
    q0 : array_like, optional
        The start (None: the reference at 0).
    sim_options : dict, optional
        Other :func:`~armctl.sim.simulate` options (environment, friction, …).
    builders : dict, optional
        Method name → function (scene, gains) → Controller, for methods that are not built in.
    backend : str, optional
        The backend of the scene's Dynamics.
    """

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
    timing_samples: ClassVar[int] = 200  # recorded states :meth:`metrics` replays to time a controller
    #: method → (required, optional) gain names, against which :meth:`controller` checks the gains it passes to
    #: :meth:`build`
    gain_keys: ClassVar[dict[str, tuple[tuple[str, ...], tuple[str, ...]]]] = GAIN_KEYS
    #: the signals :meth:`replay_window` gives each sample (a :class:`~armctl.controllers.Measurement`), for the
    #: controllers that read them: ``"tau_applied"``, the torque applied over the period before it [N·m];
    #: ``"wrench"``, the force/torque sensor's reading (row :data:`SENSOR` of ``res.sensor``, world axes) [N; N·m]
    replay_reads: ClassVar[tuple[str, ...]] = ()

    def dynamics(self, which: str = "exact") -> Dynamics:
        """Dynamics of one of the scene's models (pickles by rebuilding).

        Parameters
        ----------
        which : {"plant", "exact", "reduced"}, optional
            The model.

        Returns
        -------
        Dynamics

        Raises
        ------
        UnknownNameError
            Another name.
        """
        if not isinstance(which, str) or which not in MODELS:
            raise UnknownNameError("scene model", which, MODELS)
        return Dynamics(
            {"plant": self.plant, "exact": self.exact, "reduced": self.reduced}[which], backend=self.backend
        )

    def gains(self, method: str) -> dict[str, Any]:
        """A method's default gains: its preset (``controllers/<scene>.<method>.toml``), unless the scene has
        defaults of its own.

        Parameters
        ----------
        method : str
            The method.

        Returns
        -------
        dict of str
            Gain name → value (see :mod:`armctl.tuning.presets`).

        Raises
        ------
        ModelLoadError
            No preset for the method.
        UnknownNameError
            A scene with defaults of its own: an unknown method.
        """
        return dict(load_preset(self.name, method)["gains"])

    def controller(self, method: str, gains: dict[str, Any] | None = None) -> Controller:
        """The controller of a method, built by :meth:`build` (the keys of each method's gains are in
        :attr:`gain_keys`, :data:`GAIN_KEYS` for the built-in joint-space methods; an unknown key or a missing
        required one is an error, not ignored) or by the method's entry in :attr:`builders`.

        Parameters
        ----------
        method : str
            One of :attr:`methods`.
        gains : dict, optional
            Gain name → value (default: the preset).

        Returns
        -------
        Controller

        Raises
        ------
        UnknownNameError
            An unknown method or gain.
        InvalidParameterError
            A required gain missing, or a value out of range.
        """
        if method not in self.methods:
            raise UnknownNameError("method", method, self.methods)
        if method in self.builders:  # a custom builder checks its own gains
            return self.builders[method](self, self.gains(method) if gains is None else dict(gains))
        g = check_gains(method, self.gains(method) if gains is None else gains, *self.gain_keys[method])
        return self.build(method, g)

    def build(self, method: str, gains: dict[str, Any]) -> Controller:
        """The controller of ``method`` with checked ``gains`` (see :meth:`controller`): here the built-in
        joint-space methods (an UnknownNameError for any other); a subclass with methods of its own overrides it,
        and :attr:`gain_keys`.

        Parameters
        ----------
        method : str
            One of :attr:`methods`.
        gains : dict
            Its gains, checked against :attr:`gain_keys`.

        Returns
        -------
        Controller
            The method's control law on this scene's models.
        """
        g = gains
        if method == "pd_gravity":
            return PDGravity(self.dynamics("exact"), g["kp"], g["kd"], g.get("ki"))
        if method in ("computed_torque", "computed_torque_reduced"):
            dyn = self.dynamics("exact" if method == "computed_torque" else "reduced")
            return ComputedTorque(dyn, g["kp"], g["kd"], g.get("ki"))
        if method == "passivity":
            return PassivityBased(self.dynamics("exact"), g["lam"], g["kd"])
        if method == "adaptive":
            return Adaptive(
                self.dynamics("reduced"),
                g["lam"],
                g["kd"],
                g["gamma"],
                projection=boolean(g.get("projection", True), "gains['projection']"),
                sigma=g.get("sigma", 0.0),
            )
        raise UnknownNameError("method", method, self.methods)  # pragma: no cover

    def run(self, method: str, gains: dict[str, Any] | None = None, **overrides: Any) -> Any:
        """Simulate a method on this scene. The plant, controller and reference are the scene's (build another scene
        to change them).

        Parameters
        ----------
        method, gains
            As for :meth:`controller`.
        **overrides
            ``duration`` and any option of :func:`armctl.sim.simulate`: they win over the scene's settings.

        Returns
        -------
        SimResult

        Raises
        ------
        UnknownNameError
            An unknown method, or an override that is not an option of simulate.
        """
        from armctl.sim import simulate
        from armctl.sim.options import regroup

        valid = tuple(
            p for p in inspect.signature(simulate).parameters if p not in ("plant", "controller", "reference")
        )
        for key in overrides:
            if key not in valid:
                raise UnknownNameError("simulate option", key, valid)
        options = {
            "control_dt": self.control_dt,
            "dt": self.dt,
            "integrator": self.integrator,
            "q0": self.q0,
            **self.sim_options,
            **overrides,
        }
        duration = options.pop("duration", self.duration)
        return simulate(
            self.dynamics("plant"), self.controller(method, gains), self.reference, duration, **regroup(options)
        )

    def metrics(
        self,
        res: Any,
        method: str,
        gains: dict[str, Any] | None = None,
        timing_samples: int | None = None,
        timing_rounds: int = 5,
    ) -> dict[str, Any]:
        """Tracking error (RMS, max) [rad], torque RMS [N·m], the share of samples beyond the plant's limits
        (``limit_violation_share``: any of ``torque_violation_share``, the command beyond the effort limits;
        ``velocity_violation_share``, a joint more than :data:`VELOCITY_TOLERANCE` beyond its velocity limit;
        ``position_violation_share``, a joint outside its position range), divergence, and the controller's compute
        time per step [s] (``compute_s``, see :meth:`compute_time` on :meth:`replay_window`). A run without samples
        gives NaN for every measure (compute time and limit-violation shares included). A run that diverged has no
        tracking error (NaN): the error of its samples before the divergence, which can look better than a stable
        method's, is kept apart as ``rms_error_until_divergence`` and ``max_error_until_divergence`` (and a force
        error as ``force_rms_error_until_divergence``). A scene adds its own measures, or replaces the joint
        tracking error with its own, through :meth:`scene_measures`.

        Parameters
        ----------
        res : SimResult
            A run of this scene.
        method : str
            The method that ran.
        gains : dict, optional
            Its gains (default: the preset), to rebuild the controller for timing.
        timing_samples : int, optional
            Recorded states replayed to time the controller (default :attr:`timing_samples`).
        timing_rounds : int, optional
            Timed passes (0: not timed, NaN).

        Returns
        -------
        dict of str
        """
        timing_samples = whole_number(
            self.timing_samples if timing_samples is None else timing_samples, "timing_samples", 1
        )
        want = np.array([self.reference(t).q for t in res.t])
        err = np.abs(res.q - want) if len(res.t) else np.zeros((0, self.plant.n))
        shares = self.limit_violations(res)
        timing_rounds = whole_number(timing_rounds, "timing_rounds", 0)
        step = (
            self.compute_time(method, self.replay_window(res, timing_samples), gains, timing_rounds)
            if timing_rounds
            else float("nan")
        )
        out = {
            "rms_error": float(np.sqrt((err**2).mean())) if err.size else float("nan"),
            "max_error": float(err.max()) if err.size else float("nan"),
            "torque_rms": float(np.sqrt((res.tau_applied**2).mean())) if len(res.t) else float("nan"),
            **shares,
            "diverged": bool(res.diverged),
            "diverged_at": res.diverged_at,
            "compute_s": step,
        }
        out.update(self.scene_measures(res, method, gains))
        return diverged_errors(out)

    def scene_measures(self, res: Any, method: str, gains: dict[str, Any] | None = None) -> dict[str, Any]:
        """A scene's own measures of a run, which :meth:`metrics` adds to (or puts in place of) its joint-space
        ones before it sets a diverged run's errors apart: here none; a scene with measures of its own (a tool
        error, a force error, a collision's timing) overrides this, not :meth:`metrics`.

        Parameters
        ----------
        res, method, gains
            As for :meth:`metrics`.

        Returns
        -------
        dict of str
        """
        return {}

    def limit_violations(self, res: Any) -> dict[str, float]:
        """Shares of a run's samples beyond the plant's limits (see :meth:`metrics`); NaN without samples.

        Parameters
        ----------
        res : SimResult
            A run of this scene.

        Returns
        -------
        dict of str to float
        """
        keys = ("torque", "velocity", "position")
        if not len(res.t):
            return {f"{k}_violation_share": float("nan") for k in ("limit", *keys)}
        p = self.plant
        over = {
            "torque": np.abs(res.tau) > p.effort_limit * (1 + 1e-9),
            "velocity": np.abs(res.qd) > p.velocity_limit * (1 + VELOCITY_TOLERANCE),
            "position": (res.q < p.lower) | (res.q > p.upper),
        }
        rows = {k: v.any(axis=1) for k, v in over.items()}
        return {
            "limit_violation_share": float(np.logical_or.reduce(list(rows.values())).mean()),
            **{f"{k}_violation_share": float(rows[k].mean()) for k in keys},
        }

    def replay_window(self, res: Any, samples: int = 200) -> dict[str, Any]:
        """A contiguous window of recorded states from the middle of a run, as the controller measured them (t, q,
        q̇ and the references), for :meth:`compute_time`; with :attr:`replay_reads`, each sample's measurement too
        (``"measurement"``).

        Parameters
        ----------
        res : SimResult
            A run of this scene.
        samples : int, optional
            The window's length.

        Returns
        -------
        dict of str
        """
        samples = whole_number(samples, "timing_samples", 1)
        count = min(samples, len(res.t))
        first = (len(res.t) - count) // 2
        idx = np.arange(first, first + count)
        t = [float(res.t[k]) for k in idx]
        window = {
            "t": t,
            "q": res.q_measured[idx].copy(),
            "qd": res.qd_measured[idx].copy(),
            "ref": [self.reference(tk) for tk in t],
        }
        if self.replay_reads:
            wrench = "wrench" in self.replay_reads
            window["measurement"] = [
                Measurement(
                    wrench=res.sensor[k, SENSOR] if wrench else None,
                    tau_applied=res.tau_applied[k - 1] if k else np.zeros(res.q.shape[1]),
                    world_axes=wrench,
                )
                for k in idx
            ]
        return window

    def compute_time(
        self, method: str, window: dict[str, Any], gains: dict[str, Any] | None = None, rounds: int = 5
    ) -> float:
        """Seconds per control step of a method's controller replaying a window of states (as a loop would see them:
        warm starts stay warm), so the simulator's own cost is not counted: the median over ``rounds`` passes after a
        warm-up pass, the controller reset before each.

        Parameters
        ----------
        method : str
            The method.
        window : dict
            From :meth:`replay_window`.
        gains : dict, optional
            Its gains (default: the preset).
        rounds : int, optional
            Timed passes.

        Returns
        -------
        float
            [s]; NaN for an empty window.
        """
        rounds = whole_number(rounds, "timing_rounds", 1)
        if not len(window["t"]):
            return float("nan")
        return statistics.median(replay_times(self.controller(method, gains), window, rounds + 1)[1:])


_S = TypeVar("_S", bound=Scene)


def holding_scene(cls: type[_S], name: str, description: str, model: RobotModel, q0: Any, **settings: Any) -> _S:
    """A scene of class ``cls`` whose plant and controller-side models are all ``model`` and whose reference holds
    the posture ``q0``, where it also starts (the scenes whose task is their own, not a joint-space reference).

    Parameters
    ----------
    cls : type
        :class:`Scene` or a subclass.
    name, description : str
        As for :class:`Scene`.
    model : RobotModel
        The plant, and the model its controllers are given.
    q0 : array_like, shape (n,)
        The posture held and the start [rad].
    **settings
        The other fields of :class:`Scene` (``duration``, ``methods``, ``dt``, ``sim_options``, …).

    Returns
    -------
    Scene
        Of class ``cls``.
    """
    held = Reference(q0)  # (read-only: one for every instant)
    return cls(
        name,
        description,
        plant=model,
        exact=model,
        reduced=model,
        reference=lambda t: held,
        q0=q0,
        **settings,
    )


def quintic(start: Any, end: Any, t0: float, duration: float) -> Callable[[float], tuple[Any, Any, Any]]:
    """t → (position, velocity, acceleration) of a minimum-jerk move from ``start`` to ``end`` (arrays, or floats:
    then floats) between t0 and t0 + duration [s], held before and after."""
    a: Any = np.asarray(start, dtype=float)
    b: Any = np.asarray(end, dtype=float)
    if a.ndim == b.ndim == 0:  # floats: the same arithmetic without arrays
        a, b = float(a), float(b)

    def at(t: float) -> tuple[Any, Any, Any]:
        shape, rate, accel = minimum_jerk(t, t0, duration)
        return a + (b - a) * shape, (b - a) * rate, (b - a) * accel

    return at
