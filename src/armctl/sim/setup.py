"""Checking and normalising the arguments of :func:`armctl.simulate` (every bad input raises an
:class:`~armctl.errors.ArmctlError` subclass that names the value and says what is allowed)."""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, check_memory, scalar, vector, whole_number
from armctl.controllers.base import Controller
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError, ShapeError, SimulationWarning, UnknownNameError
from armctl.model.robot import RobotModel
from armctl.references import Reference
from armctl.sim.contact import Environment, ForceSensor
from armctl.sim.friction import FrictionModel, make_friction
from armctl.sim.integrators import INTEGRATORS

_REL = 1e-9


def plant_dynamics(plant: Any) -> Dynamics:
    """``plant`` as a Dynamics (a RobotModel gets the Pinocchio backend)."""
    if isinstance(plant, Dynamics):
        return plant
    if isinstance(plant, RobotModel):
        return Dynamics(plant)
    raise InvalidParameterError(
        f"plant must be an armctl.Dynamics or an armctl.RobotModel, got {type(plant).__name__}", value=plant
    )


def _as_written(x: Any) -> Any:
    """A time given in a lower precision than float64 (a NumPy float32 or float16, or a 0-d array of one) as the
    decimal it prints as, the value its author wrote: a float32 1e-3 is 0.0010000000475 s, and 1 s is then not
    a whole number of periods to 1e-9. Anything else unchanged (checked by the caller)."""
    if isinstance(x, np.ndarray) and x.ndim == 0:
        x = x[()]
    if isinstance(x, np.floating) and np.finfo(x.dtype).bits < 64:
        return float(np.format_float_positional(x, unique=True))
    return x


#: bytes a run records per sample and joint at least (q, q̇, q̈, τ, applied τ, friction and external torques,
#: the reference's q, q̇, q̈ in the result), and per sample besides (t, wrench, work)
RECORD_BYTES_PER_JOINT, RECORD_BYTES = 8 * 10, 8 * 9


def periods(duration: Any, control_dt: Any, dt: Any, n: int | None = None) -> tuple[float, float, int, int]:
    """(control_dt, dt, number of control periods N, sub-steps per period m), checked; a run too long to record
    on this machine (N + 1 samples of an ``n``-joint arm, see :data:`RECORD_BYTES_PER_JOINT`; None counts one
    joint, the least a run records) raises an :class:`~armctl.errors.InvalidParameterError` saying how much
    memory it would need, before anything is allocated."""
    for name, x in (("duration", duration), ("control_dt", control_dt), ("dt", dt)):
        if isinstance(x, bool | np.bool_):
            raise InvalidParameterError(f"{name} must be a time in s, got {x!r}", value=x)
    duration, control_dt, dt = (_as_written(x) for x in (duration, control_dt, dt))
    duration = scalar(duration, "duration [s]", positive=True)
    control_dt = scalar(control_dt, "control_dt [s]", positive=True)
    dt = control_dt if dt is None else scalar(dt, "dt [s]", positive=True)
    ratio = control_dt / dt
    m = round(ratio)
    if m < 1 or abs(ratio - m) > _REL * ratio:
        raise InvalidParameterError(
            f"control_dt = {control_dt} s must be a whole multiple of the integration step dt = {dt} s "
            f"(it is {ratio:.6g} steps); choose dt = control_dt / k, e.g. dt = {control_dt / max(m, 1):g}",
            value=dt,
        )
    steps = duration / control_dt
    n_steps = round(steps)
    if n_steps < 1 or abs(steps - n_steps) > _REL * max(steps, 1.0):
        lo, hi = math.floor(steps) * control_dt, math.ceil(steps) * control_dt
        use = f"{lo:g} s or {hi:g} s" if lo > 0 else f"{max(hi, control_dt):g} s (one control period)"
        raise InvalidParameterError(
            f"duration = {duration} s is not a whole number of control periods of {control_dt} s "
            f"({steps:.6g}); use {use}",
            value=duration,
        )
    check_memory(
        (n_steps + 1) * (RECORD_BYTES + RECORD_BYTES_PER_JOINT * (1 if n is None else n)),
        f"duration = {duration:g} s at control_dt = {control_dt:g} s is {n_steps:.4g} control periods; recording "
        f"them{'' if n is None else f' for a {n}-joint arm'}",
        "shorten the run or raise control_dt, or run it in pieces (the end state of one run, res.q[-1] and "
        "res.qd[-1], is q0 and qd0 of the next)",
        duration,
    )
    return control_dt, control_dt / m, n_steps, m


def integrator_name(name: Any) -> str:
    if not isinstance(name, str) or name not in INTEGRATORS:
        raise UnknownNameError("integrator", name, INTEGRATORS)
    return name


def reference_source(reference: Any, n: int) -> tuple[Reference | None, Callable[[float], Reference] | None]:
    """(fixed reference, None) or (None, callable); the value at t = 0 is checked."""
    if isinstance(reference, Reference):
        check_reference(reference, n, 0.0)
        return reference, None
    if callable(reference):
        check_reference(reference(0.0), n, 0.0)
        return None, reference
    raise InvalidParameterError(
        f"reference must be an armctl.Reference or a callable t -> Reference, got {type(reference).__name__}",
        value=reference,
    )


def check_reference(ref: Any, n: int, t: float) -> Reference:
    if not isinstance(ref, Reference):
        raise InvalidParameterError(
            f"reference(t) must return an armctl.Reference, got {type(ref).__name__} at t = {t}", value=ref
        )
    if ref.q.shape[0] != n:
        raise ShapeError(f"reference has {ref.n} joints, the plant {n} (at t = {t})", value=ref)
    return ref


def controller_call(controller: Any, n: int) -> Callable[..., Any]:
    """How the simulator calls ``controller``: a :class:`Controller`'s ``compute`` (the simulator's state and
    references are already checked, so the controller's own checks of them are skipped), else the callable itself."""
    if not callable(controller):
        raise InvalidParameterError(
            f"controller must be callable as controller(t, q, qd, ref) -> tau, got {type(controller).__name__}",
            value=controller,
        )
    cn = getattr(controller, "n", None)
    if isinstance(cn, int | np.integer) and int(cn) != n:
        raise ShapeError(f"controller is for {cn} joints, the plant has {n}", value=controller)
    if isinstance(controller, Controller) and type(controller).__call__ is Controller.__call__:
        return controller.compute
    return controller


def initial_state(
    q0: ArrayLike | None, qd0: ArrayLike | None, ref0: Reference, n: int, max_position: float, max_velocity: float
) -> tuple[FloatArray, FloatArray]:
    """(q0, q̇0) as fresh arrays, within the run's bounds; None starts on the reference at t = 0."""
    q = ref0.q if q0 is None else vector(q0, n, "q0")
    qd = ref0.qd if qd0 is None else vector(qd0, n, "qd0")
    for name, x, limit, bound_name in (
        ("q0", q, max_position, "max_position"),
        ("qd0", qd, max_velocity, "max_velocity"),
    ):
        worst = float(np.abs(x).max()) if len(x) else 0.0
        if worst > limit:
            source = name if (q0 if name == "q0" else qd0) is not None else f"{name} (the reference at t = 0)"
            raise InvalidParameterError(
                f"{source} reaches {worst:g}, beyond {bound_name} = {limit:g}: the run "
                f"would stop as diverged before it starts; raise {bound_name}",
                value=x,
            )
    return np.array(q, dtype=float), np.array(qd, dtype=float)


def warn_outside_limits(model: RobotModel, q: FloatArray) -> None:
    """Warn (:class:`~armctl.errors.SimulationWarning`, pointing at the caller of ``simulate``) if the start
    configuration is outside the model's position limits."""
    lower, upper = model.lower, model.upper
    outside = np.flatnonzero((q < lower) | (q > upper))
    if outside.size:
        joints = "; ".join(
            f"joint {i} ({model.joint_names[i]!r}) at {q[i]:.4g} outside [{lower[i]:.4g}, {upper[i]:.4g}]"
            for i in outside
        )
        warnings.warn(
            f"the run starts outside the model's position limits: {joints}. The simulator does not stop "
            "a joint at its limits, but a controller that keeps them (a JointPositionLimit in an "
            "operational-space QP) acts hard from the first step; for a revolute joint, the same pose "
            "2π away may be inside the range",
            SimulationWarning,
            stacklevel=3,
        )


def seed_value(seed: Any) -> int:
    """``seed`` for numpy's default_rng: a whole number >= 0, or for None a fresh one from the operating
    system's entropy (recorded in the result, so that a noisy run can be repeated)."""
    return int(cast(int, np.random.SeedSequence().entropy)) if seed is None else whole_number(seed, "seed")


def delay_periods(delay: Any) -> int:
    return whole_number(delay, "delay (in control periods)")


def bound(x: Any, name: str) -> float:
    v = float(x) if isinstance(x, int | float | np.floating | np.integer) and not isinstance(x, bool) else math.nan
    if not v > 0:
        raise InvalidParameterError(f"{name} must be a positive number (inf: no bound), got {x!r}", value=x)
    return v


def seq(x: Any, kind: type, name: str) -> tuple[Any, ...]:
    if x is None:
        return ()
    items = (x,) if isinstance(x, kind) else tuple(x) if isinstance(x, Sequence) else None
    if items is None or not all(isinstance(i, kind) for i in items):
        raise InvalidParameterError(f"{name} must be a {kind.__name__} or a sequence of them, got {x!r}", value=x)
    return items


@dataclass(frozen=True)
class Scene:
    """What the plant is made of, checked against its model."""

    friction: FrictionModel | None  # None: the engine's own (MuJoCo's frictionloss and damping)
    environments: tuple[Environment, ...]
    sensors: tuple[ForceSensor, ...]
    disturbance: Callable[[float], Any] | None


def scene(dyn: Dynamics, friction: Any, environment: Any, sensors: Any, disturbance: Any) -> Scene:
    """The plant's forces and sensors, checked (``friction`` None: none of armctl's)."""
    envs = seq(environment, Environment, "environment")
    for env in envs:
        env.check(dyn.model)
    sens = seq(sensors, ForceSensor, "sensors")
    for s in sens:
        dyn.model.frame(s.frame)
    if disturbance is not None and not callable(disturbance):
        raise InvalidParameterError(
            f"disturbance must be a callable t -> (6,) wrench or None, got {type(disturbance).__name__}",
            value=disturbance,
        )
    return Scene(None if friction is None else make_friction(friction, dyn.model), envs, sens, disturbance)
