"""`simulate`: a controller in closed loop with a plant, at a real control rate.

At every control instant t_k = k·Δt_c the controller is given the measured state and the reference and
returns τ_k; τ_k, saturated at the plant's effort limits, is held constant over [t_k, t_k + Δt_c) (zero-order
hold) while the plant is integrated with m = Δt_c/Δt sub-steps:

    M(q) q̈ + C(q, q̇) q̇ + g(q) = sat(τ_k) − τ_f − Σ_p J_pᵀ h_p − J_toolᵀ h_d(t)

(see :mod:`armctl.sim.plant` for the terms, :mod:`armctl.sim.friction` and :mod:`armctl.sim.contact` for the
models, :mod:`armctl.sim.integrators` for the schemes).
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import fields

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, boolean, nonnegative_vector
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError, SimulationWarning
from armctl.model.robot import RobotModel
from armctl.references import Reference
from armctl.sim import setup
from armctl.sim.after_run import after_run
from armctl.sim.compiled import choose_step
from armctl.sim.contact import Environment, ForceSensor
from armctl.sim.friction import FrictionModel
from armctl.sim.loop import ClosedLoop, LoopSettings
from armctl.sim.measurement_feed import MeasurementFeed, declared_reads
from armctl.sim.options import Forces, Sensing, StopRules, grouped
from armctl.sim.plant import Plant
from armctl.sim.recorder import Recorder
from armctl.sim.result import SimResult
from armctl.sim.run_failure import attach, end_run
from armctl.sim.stability import contact_stability


def simulate(
    plant: Dynamics | RobotModel,
    controller: Callable[..., ArrayLike],
    reference: Reference | Callable[[float], Reference],
    duration: float,
    q0: ArrayLike | None = None,
    qd0: ArrayLike | None = None,
    control_dt: float = 1e-3,
    dt: float | None = None,
    integrator: str = "rk4",
    *,
    sensing: Sensing | None = None,
    forces: Forces | None = None,
    stop: StopRules | None = None,
    saturate: bool = True,
    reset: bool = True,
    energy: bool = True,
    compile: bool | str = "auto",
    engine: str = "native",
    friction: str | FrictionModel | None = None,
    environment: Environment | Sequence[Environment] | None = None,
    disturbance: Callable[[float], ArrayLike] | None = None,
    sensors: ForceSensor | Sequence[ForceSensor] | None = None,
    noise_q: ArrayLike | None = None,
    noise_qd: ArrayLike | None = None,
    seed: int | None = None,
    delay: int | None = None,
    max_velocity: float | None = None,
    max_position: float | None = None,
) -> SimResult:
    """Simulate ``controller`` driving ``plant`` along ``reference`` for ``duration`` seconds.

    Parameters
    ----------
    plant : Dynamics or RobotModel
        The true arm: its friction, payload, … are the truth (it may differ from the controller's own model).
    controller : callable
        ``tau = controller(t, q, qd, ref)`` [N·m]; its ``reset()`` is called first (``reset=True``), its
        ``end_run()`` (if it has one) after the last step, and its ``last_log`` dict recorded after every call.
        A controller that declares signals in ``reads`` (a force sensor's wrench, the applied or measured
        torques: :mod:`armctl.controllers.measurement`) is given them at every sample, through the measurement
        chain of ``sensing``.
    reference : Reference or callable
        A :class:`~armctl.Reference`, or t [s] → Reference.
    duration : float
        Length of the run [s], a whole number of control periods.
    q0, qd0 : (n,) array_like, optional
        Initial state [rad, rad/s] (None: the reference at t = 0).
    control_dt : float
        Controller period Δt_c [s].
    dt : float, optional
        Integration step [s]; Δt_c must be a whole multiple of it (None: Δt_c).
    integrator : {"rk4", "semi-implicit-euler", "implicit-euler", "euler"}
        The scheme (:mod:`armctl.sim.integrators`): ``"rk4"`` (the default), ``"semi-implicit-euler"``
        (symplectic: no energy drift), ``"implicit-euler"`` (stiff contact and damping), ``"euler"`` (the cheapest).
    sensing : Sensing, optional
        What the controller measures: noise, its seed, delay, force sensors (:class:`~armctl.sim.options.Sensing`;
        its fields may be given as keywords instead).
    forces : Forces, optional
        Friction model, contact environments, disturbance (:class:`~armctl.sim.options.Forces`; its fields may be
        given as keywords instead).
    stop : StopRules, optional
        ``max_velocity`` [rad/s], ``max_position`` [rad] (:class:`~armctl.sim.options.StopRules`; its fields may be
        given as keywords instead).
    saturate : bool
        Clip τ at the plant model's effort limits.
    reset : bool
        Call ``controller.reset()`` first.
    energy : bool
        Provide ``res.energy``, E = T + U at every sample, computed from the recorded states when first read
        (False: NaN).
    compile : {"auto", True, False}
        ``"auto"``: integrate with C code generated for this plant wherever it can be built (:mod:`armctl.sim.compiled`:
        a few seconds on first use, logged once, then cached on disk; without a C compiler, the Python step and a
        warning); True: the generated step or an error saying why there is none; False: the Python step.
        ``res.info["compiled"]`` says which ran.
    engine : {"native", "mujoco"}
        ``"mujoco"``: MuJoCo integrates the plant, a :class:`~armctl.sim.mujoco_plant.MujocoPlant` scene or the
        model's MJCF (see :mod:`armctl.sim.mujoco_engine` for what it takes and records).
    friction, environment, disturbance : optional
        The fields of ``forces``, as keywords (defaults: ``"stick-slip"``, none, none).
    sensors, noise_q, noise_qd, seed, delay : optional
        The fields of ``sensing``, as keywords (defaults: none, 0 rad, 0 rad/s, a fresh seed, 0 periods).
    max_velocity, max_position : float, optional
        The fields of ``stop``, as keywords (defaults: 1e3 rad/s, inf).

    Returns
    -------
    SimResult
        The samples at t_k = k·Δt_c. A run that diverges (a non-finite or out-of-bounds state, a non-finite torque,
        a mass matrix no longer positive definite) returns the samples before it with ``diverged=True``,
        ``diverged_at``, ``divergence`` and the offending state: it does not raise.

    Raises
    ------
    ArmctlError
        A bad argument, named.
    Exception
        Whatever the controller, the reference, the disturbance or the controller's ``end_run`` raised during the
        run, unchanged, carrying the samples simulated up to it as ``exc.result`` (a :class:`SimResult`; the last
        sample's state is the one the exception was raised at, with NaN for the torque, acceleration or reference
        not computed there): nothing simulated is lost.

    Notes
    -----
    A contact the integrator cannot integrate stably at this step (:mod:`armctl.sim.stability`) is reported before
    the run by a :class:`~armctl.errors.SimulationWarning` and kept in ``res.info["unstable_contacts"]``: the run
    still happens, but past the first impact it is not the arm's motion. After a run with contact, what that check
    cannot see is checked on the record (:mod:`armctl.sim.after_run`): energy the arm gained that no force
    supplied (``res.info["energy_gain"]``), positive work by the passive environments
    (``res.info["environment_work"]``) and a plane's friction too stiff below its slip velocity for the step
    (``res.info["unstable_friction"]``), each with a warning.
    """
    given = {
        name: value
        for name, value in (
            ("friction", friction),
            ("environment", environment),
            ("disturbance", disturbance),
            ("sensors", sensors),
            ("noise_q", noise_q),
            ("noise_qd", noise_qd),
            ("seed", seed),
            ("delay", delay),
            ("max_velocity", max_velocity),
            ("max_position", max_position),
        )
        if value is not None
    }
    sense, force, rules = grouped({"sensing": sensing, "forces": forces, "stop": stop}, given)
    reads = declared_reads(controller)
    if engine != "native":  # another engine integrates the plant (armctl.sim.mujoco_engine)
        from armctl.sim.mujoco_engine import run_engine

        if reads:
            raise InvalidParameterError(
                f"the controller reads {sorted(reads)}, which engine={engine!r} does not measure: use engine='native'",
                value=engine,
            )
        options = {
            f.name: getattr(group, f.name)
            for group in (sense, force, rules)
            for f in fields(group)
            if f.name not in _SIGNAL_OPTIONS
        }
        return run_engine(
            engine,
            plant=plant,
            controller=controller,
            reference=reference,
            duration=duration,
            q0=q0,
            qd0=qd0,
            control_dt=control_dt,
            dt=dt,
            integrator=integrator,
            saturate=saturate,
            reset=reset,
            energy=energy,
            compile=compile,
            **options,
        )
    dyn = setup.plant_dynamics(plant)
    n = dyn.n
    cdt, h, n_periods, m = setup.periods(duration, control_dt, dt, n=n)
    scheme = setup.integrator_name(integrator)
    fixed_ref, ref_fn = setup.reference_source(reference, n)
    ref0 = fixed_ref if fixed_ref is not None else ref_fn(0.0)  # type: ignore[misc]  # one of the two is set
    call = setup.controller_call(controller, n)
    sig_q = nonnegative_vector(sense.noise_q, n, "noise_q (a standard deviation)")
    sig_qd = nonnegative_vector(sense.noise_qd, n, "noise_qd (a standard deviation)")
    lag = setup.delay_periods(sense.delay)
    if lag >= n_periods > 0:
        warnings.warn(
            f"delay = {lag} control periods is not shorter than the run ({n_periods} periods): the "
            "controller sees only the first measurement",
            SimulationWarning,
            stacklevel=2,
        )
    saturate, reset, energy = (boolean(saturate, "saturate"), boolean(reset, "reset"), boolean(energy, "energy"))
    vmax, qmax = setup.bound(rules.max_velocity, "max_velocity"), setup.bound(rules.max_position, "max_position")
    q, v = setup.initial_state(q0, qd0, ref0, n, qmax, vmax)
    setup.warn_outside_limits(dyn.model, q)
    seed_used = setup.seed_value(sense.seed)
    dyn.check_mass_matrix(q)  # a plant whose M is singular from the start is a model to fix, not a run that diverged
    sc = setup.scene(dyn, force.friction, force.environment, sense.sensors, force.disturbance)

    unstable = _check_contacts(dyn, sc.environments, q, scheme, h)
    chosen = choose_step(dyn, scheme, Plant(dyn, sc.friction, sc.environments, sc.disturbance), compile)
    pl, step, fast = chosen.plant, chosen.step, chosen.fast
    samples = n_periods + 1
    noisy = bool(sig_q.any() or sig_qd.any())
    rec = Recorder(n, samples, cdt, sc.environments, sc.sensors, measured=noisy or lag > 0)
    # sample k's noise is the k-th block of 2n draws (q's, then q̇'s): a longer run with the same seed sees the
    # same noise over the common samples
    draws = np.random.default_rng(seed_used).standard_normal((samples, 2, n)) if noisy else None
    feed = (
        MeasurementFeed(
            reads,
            n,
            cdt,
            sc.sensors,
            nonnegative_vector(sense.noise_wrench, 6, "noise_wrench (a standard deviation)"),
            nonnegative_vector(sense.noise_tau, n, "noise_tau (a standard deviation)"),
            sense.cutoff,
            lag,
            seed_used,
            dyn.model.effort_limit,
            saturate,
        )
        if reads
        else None
    )
    settings = LoopSettings(
        n=n,
        control_dt=cdt,
        dt=h,
        periods=n_periods,
        substeps=m,
        implicit=scheme in ("implicit-euler", "semi-implicit-euler"),
        controller=controller,
        call=call,
        fixed_reference=fixed_ref,
        reference_fn=ref_fn,
        plant=pl,
        step=step,
        fast=fast,
        recorder=rec,
        noise_q=draws[:, 0] * sig_q if draws is not None else None,
        noise_qd=draws[:, 1] * sig_qd if draws is not None else None,
        delay=lag,
        effort_limit=dyn.model.effort_limit,
        saturate=saturate,
        max_velocity=vmax,
        max_position=qmax,
        feed=feed,
    )
    reset_controller = getattr(controller, "reset", None)
    if reset and callable(reset_controller):
        reset_controller()
    loop = ClosedLoop(settings, q, v)
    t0 = time.perf_counter()
    loop.run()
    wall = time.perf_counter() - t0
    failure = end_run(controller, loop.failure)
    if failure is not loop.failure:  # end_run raised after a run that did not
        loop.failure, loop.failed_at = failure, (loop.rows - 1) * cdt
    loop.applied_torques()
    rows = loop.rows
    info = {
        "plant": dyn.model.name,
        "n": n,
        "backend": dyn.backend,
        "integrator": scheme,
        "control_dt": cdt,
        "dt": h,
        "substeps": m,
        "periods": n_periods,
        "friction": sc.friction.name if pl.friction else "none",
        "saturate": bool(saturate),
        "delay": lag,
        "compiled": chosen.compiled,
        "seed": seed_used,
        "wall_time": wall,
        "real_time_factor": (rows - 1) * cdt / wall if wall > 0 and rows > 1 else math.nan,
        **pl.stats,
    }
    if unstable:
        info["unstable_contacts"] = unstable
    if loop.failure is not None:
        info["failure"] = f"{type(loop.failure).__name__}: {loop.failure}"
    res = rec.result(rows, dyn, energy, info, loop.divergence)
    if loop.failure is not None:
        attach(loop.failure, res, loop.failed_at)
        raise loop.failure
    after_run(res, dyn, sc.environments, scheme, h, sc.disturbance is not None)
    return res


#: Sensing's fields that only a controller's declared signals use (no other engine measures them)
_SIGNAL_OPTIONS = frozenset({"noise_wrench", "noise_tau", "cutoff"})


def _check_contacts(
    dyn: Dynamics, environments: Sequence[Environment], q0: FloatArray, scheme: str, h: float
) -> list[dict[str, float]]:
    """Warn (:class:`~armctl.errors.SimulationWarning`) about every contact point the integrator cannot
    integrate stably at step h (see :mod:`armctl.sim.stability`); returns them for ``info``."""
    if not environments:
        return []
    found = [c for c in contact_stability(dyn, environments, q0, scheme, h) if not c.stable]
    for c in found:
        why = (
            f"one-step growth ×{c.radius:.3g}"
            if c.radius > 1.0 + 1e-12
            else f"linearly stable, but as a one-sided contact beyond ω·dt = {c.one_sided:g}, where impacts can "
            "gain energy"
        )
        warnings.warn(
            f"environment {c.environment}, contact point {c.point}: {scheme!r} is unstable on this contact "
            f"at dt = {h:g} s (ω·dt = {c.omega_h:.3g}, {why}): once in contact the arm gains energy the "
            f"contact never had. Use dt <= {c.max_dt:.3g} s (at the initial configuration) or "
            "integrator='implicit-euler'",
            SimulationWarning,
            stacklevel=3,
        )
    return [
        {
            "environment": c.environment,
            "point": c.point,
            "omega_dt": c.omega_h,
            "growth": c.radius,
            "one_sided_limit": c.one_sided,
            "max_dt": c.max_dt,
        }
        for c in found
    ]
