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

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, boolean, nonnegative_vector, real_array
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError, ShapeError, SimulationWarning
from armctl.model.robot import RobotModel
from armctl.reference import Reference
from armctl.sim import setup
from armctl.sim.after_run import after_run
from armctl.sim.compiled import choose_step
from armctl.sim.contact import Environment, ForceSensor
from armctl.sim.friction import FrictionModel
from armctl.sim.plant import Plant
from armctl.sim.recorder import Recorder
from armctl.sim.result import SimResult
from armctl.sim.stability import contact_stability
from armctl.sim.stepper import advance
from armctl.sim.stick_slip import NotPositiveDefinite

_GT = float.__gt__
_FLOAT = np.dtype(float)


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
    friction: str | FrictionModel = "stick-slip",
    environment: Environment | Sequence[Environment] | None = None,
    sensors: ForceSensor | Sequence[ForceSensor] = (),
    disturbance: Callable[[float], ArrayLike] | None = None,
    saturate: bool = True,
    noise_q: ArrayLike = 0.0,
    noise_qd: ArrayLike = 0.0,
    seed: int | None = None,
    delay: int = 0,
    max_velocity: float = 1e3,
    max_position: float = math.inf,
    reset: bool = True,
    energy: bool = True,
    compile: bool | str = "auto",
    engine: str = "native",
) -> SimResult:
    """Simulate ``controller`` driving ``plant`` along ``reference`` for ``duration`` seconds.

    plant: the true arm, a Dynamics or a RobotModel (its friction, payload, … are the truth; it may differ
    from the controller's own model). controller: ``tau = controller(t, q, qd, ref)``; its ``reset()`` is
    called first (``reset=True``), its ``end_run()`` (if it has one) after the last step, and its ``last_log``
    dict recorded after every call. reference: a Reference
    or a callable t → Reference. duration [s]: a whole number of control periods. q0, qd0: initial state
    (None: the reference at t = 0). control_dt: controller period Δt_c [s]. dt: integration step [s]; Δt_c
    must be a whole multiple of it (None: Δt_c). integrator: "rk4", "semi-implicit-euler"
    (symplectic: no energy drift), "implicit-euler" (stiff contact and damping) or "euler" (the cheapest);
    see :mod:`armctl.sim.integrators`.

    friction: "stick-slip" (exact sticking), "smooth" (tanh) or a FrictionModel, applied to the plant
    model's joint friction. environment: contact environment(s); sensors: force sensor(s) recorded in
    ``res.sensor``; disturbance: t → h_d (6,), a wrench at the tool frame with the sign of Dynamics' ``wrench``
    (what the arm exerts: a push F on the arm is −F). saturate: clip τ at the model's effort limits.
    noise_q [rad], noise_qd [rad/s]: standard deviations (scalar or per joint) of Gaussian measurement noise,
    drawn from ``seed`` (None: a fresh seed, kept in ``res.info["seed"]`` to repeat the run). delay: the
    controller sees the measurement of ``delay`` periods earlier (the first one before that). max_velocity
    [rad/s], max_position [rad]: a state beyond them, or non-finite, stops the run as diverged (as does a
    non-finite torque from the controller or a mass matrix that is no longer positive definite). energy:
    provide ``res.energy``, E = T + U at every sample, computed from the recorded states when first read
    (False: NaN). compile: ``"auto"`` integrates with C code generated for this plant wherever it can be built
    (:mod:`armctl.sim.compiled`: a few seconds on first use, logged once, then cached on disk; without a C
    compiler the Python step, with a warning), True insists on it (an error if it cannot be had), False uses the
    Python step; ``res.info["compiled"]`` says which ran. engine: ``"native"`` (armctl's integrators) or ``"mujoco"``
    (MuJoCo integrates the plant, a :class:`~armctl.sim.mujoco_plant.MujocoPlant` scene or the model's MJCF; see
    :mod:`armctl.sim.mujoco_engine` for what it takes and records).

    Returns a :class:`~armctl.sim.result.SimResult`; a run that diverges returns the samples before it with
    ``diverged=True``, ``diverged_at``, ``divergence`` and the offending state — it does not raise. A contact
    the integrator cannot integrate stably at this step (:mod:`armctl.sim.stability`) is reported before the
    run by a :class:`~armctl.errors.SimulationWarning` and kept in ``res.info["unstable_contacts"]``: the run
    still happens (the failure is a result to show), but past the first impact it is not the arm's motion.
    After a run with contact, what that check cannot see is checked on the record (:mod:`armctl.sim.after_run`):
    energy the arm gained that no force supplied (``res.info["energy_gain"]``), positive work by the passive
    environments (``res.info["environment_work"]``) and a plane's friction too stiff below its slip velocity
    for the step (``res.info["unstable_friction"]``), each with a warning.
    """
    if engine != "native":  # MuJoCo integrates the plant: armctl.sim.mujoco_engine
        args = dict(locals())
        from armctl.sim.mujoco_engine import run_engine

        return run_engine(**args)
    dyn = setup.plant_dynamics(plant)
    n = dyn.n
    cdt, h, n_periods, m = setup.periods(duration, control_dt, dt, n=n)
    scheme = setup.integrator_name(integrator)
    fixed_ref, ref_fn = setup.reference_source(reference, n)
    ref0 = fixed_ref if fixed_ref is not None else ref_fn(0.0)  # type: ignore[misc]
    call = setup.controller_call(controller, n)
    sig_q, sig_qd = (
        nonnegative_vector(noise_q, n, "noise_q (a standard deviation)"),
        nonnegative_vector(noise_qd, n, "noise_qd (a standard deviation)"),
    )
    lag = setup.delay_periods(delay)
    if lag >= n_periods > 0:
        warnings.warn(
            f"delay = {lag} control periods is not shorter than the run ({n_periods} periods): the "
            "controller sees only the first measurement",
            SimulationWarning,
            stacklevel=2,
        )
    saturate, reset, energy = (boolean(saturate, "saturate"), boolean(reset, "reset"), boolean(energy, "energy"))
    vmax, qmax = setup.bound(max_velocity, "max_velocity"), setup.bound(max_position, "max_position")
    q, v = setup.initial_state(q0, qd0, ref0, n, qmax, vmax)
    setup.warn_outside_limits(dyn.model, q)
    seed = setup.seed_value(seed)
    dyn.check_mass_matrix(q)  # a plant whose M is singular from the start is a model to fix, not a run that diverged
    sc = setup.scene(dyn, friction, environment, sensors, disturbance)

    unstable = _check_contacts(dyn, sc.environments, q, scheme, h)
    chosen = choose_step(dyn, scheme, Plant(dyn, sc.friction, sc.environments, sc.disturbance), compile)
    pl, step, fast = chosen.plant, chosen.step, chosen.fast
    simple = pl.simple
    implicit = scheme in ("implicit-euler", "semi-implicit-euler")  # these give no q̈ at the step start
    samples = n_periods + 1
    noisy = bool(sig_q.any() or sig_qd.any())
    rec = Recorder(n, samples, cdt, sc.environments, sc.sensors, measured=noisy or lag > 0)
    rng = np.random.default_rng(seed)
    # sample k's noise is the k-th block of 2n draws (q's, then q̇'s): a longer run with the same seed sees the
    # same noise over the common samples
    draws = rng.standard_normal((samples, 2, n)) if noisy else None
    nq = draws[:, 0] * sig_q if draws is not None else None
    nv = draws[:, 1] * sig_qd if draws is not None else None
    limit = dyn.model.effort_limit
    clip = saturate and bool(np.isfinite(limit).any())
    lim_list = limit.tolist()
    lim_min = min(lim_list)  # |τ| below every limit needs no clipping: the cheap test first
    if reset and callable(getattr(controller, "reset", None)):
        controller.reset()  # type: ignore[union-attr]
    has_log = hasattr(controller, "last_log")

    Q, QD, QDD, TAU, TAUA = rec.q, rec.qd, rec.qdd, rec.tau, rec.tau_applied
    QM, QDM, WF, WE = rec.q_measured, rec.qd_measured, rec.work_friction, rec.work_external
    REFS = rec.references  # the reference given at each sample, for res.reference
    # read-only views of the recorded rows: the controller is given these (it cannot change the record)
    QR, QDR, QMR, QDMR = Q.view(), QD.view(), QM.view(), QDM.view()
    for view in (QR, QDR, QMR, QDMR):
        view.flags.writeable = False
    shape = (n,)
    wf = we = 0.0
    clipped: list[int] = []  # rows where saturation clipped τ
    divergence = None
    rows = samples
    t0 = time.perf_counter()
    with np.errstate(all="ignore"):
        for k in range(samples):
            t = k * cdt
            ql, vl = q.tolist(), v.tolist()
            if not math.isfinite(sum(ql) + sum(vl)):
                divergence, rows = (t, "the state is not finite", q, v), k
                break
            if max(vl) > vmax or -min(vl) > vmax:
                divergence, rows = (t, f"a joint velocity is beyond max_velocity = {vmax:g}", q, v), k
                break
            if qmax < math.inf and (max(ql) > qmax or -min(ql) > qmax):
                divergence, rows = (t, f"a joint position is beyond max_position = {qmax:g}", q, v), k
                break
            Q[k] = q
            QD[k] = v
            if not simple:
                WF[k] = wf
                WE[k] = we
            qm, vm = QR[k], QDR[k]  # read-only views of the rows: the controller cannot change the state
            if rec.measured:
                if noisy:
                    QM[k] = q + nq[k]  # type: ignore[index]
                    QDM[k] = v + nv[k]  # type: ignore[index]
                else:
                    QM[k] = q
                    QDM[k] = v
                j = k - lag if k >= lag else 0
                qm, vm = QMR[j], QDMR[j]
            ref = fixed_ref if fixed_ref is not None else setup.check_reference(ref_fn(t), n, t)  # type: ignore[misc]
            REFS[k] = ref
            try:
                tau = call(t, qm, vm, ref)
            except ValueError as exc:
                if "read-only" not in str(exc):
                    raise
                raise InvalidParameterError(
                    f"the controller wrote into a read-only array at t = {t:g} s ({exc}); "
                    "the q and q̇ it is given are read-only views of the run's record: "
                    "work on a copy (q = q.copy()) or on new arrays (e = q - ref.q)",
                    value=t,
                ) from exc
            if tau.__class__ is not np.ndarray or tau.dtype is not _FLOAT:  # complex or text: named errors
                tau = real_array(tau, f"the controller's torque at t = {t:g} s")
            if has_log and controller.last_log:  # type: ignore[union-attr]
                rec.log_controller(k, controller.last_log)  # type: ignore[union-attr]
            if tau.shape != shape:
                raise ShapeError(
                    f"the controller returned a torque of shape {tau.shape} at t = {t}; expected ({n},)", value=tau
                )
            tl = tau.tolist()
            if not math.isfinite(sum(tl)):
                divergence, rows = (t, f"the controller returned a non-finite torque {tau}", q, v), k
                break
            tau_a = tau
            if clip and (max(tl) > lim_min or -min(tl) > lim_min) and any(map(_GT, map(abs, tl), lim_list)):
                tau_a = np.clip(tau, -limit, limit)
                clipped.append(k)
            TAU[k] = tau  # the applied torque is τ too, but for the clipped rows: written after the loop
            try:
                if not simple:
                    pl.begin(t, q, v, tau_a)
                    rec.record_plant(k, pl, t, q, v)
                if implicit or k == n_periods:
                    QDD[k] = pl.accel(t, q, v, tau_a)
                if k == n_periods:
                    break
                if fast is not None:  # no friction, contact or disturbance: straight to ABA
                    for s in range(m):
                        q, v, a0 = fast(q, v, tau_a, h)
                        if s == 0:
                            QDD[k] = a0
                    continue
                for s in range(m):
                    q, v, a0, dwf, dwe = advance(pl, step, t + s * h, q, v, tau_a, h, begun=s == 0)
                    if s == 0 and a0 is not None:
                        QDD[k] = a0
                    wf += dwf
                    we += dwe
            except (NotPositiveDefinite, np.linalg.LinAlgError) as exc:  # (the latter: the Lagrange backend's)
                divergence, rows = (
                    (t + cdt, f"{exc} during the control period from t = {t:g} s", Q[k].copy(), QD[k].copy()),
                    k + 1,
                )
                break
    end_run = getattr(controller, "end_run", None)
    if callable(end_run):
        end_run()  # the controller's account of the run (e.g. the OSC's solver fallbacks), once
    TAUA[:] = TAU
    if clipped:
        TAUA[clipped] = np.clip(TAU[clipped], -limit, limit)
    wall = time.perf_counter() - t0
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
        "seed": seed,
        "wall_time": wall,
        "real_time_factor": (rows - 1) * cdt / wall if wall > 0 and rows > 1 else math.nan,
        **pl.stats,
    }
    if unstable:
        info["unstable_contacts"] = unstable
    if divergence is not None:
        divergence = (divergence[0], divergence[1], np.array(divergence[2]), np.array(divergence[3]))
    res = rec.result(rows, dyn, energy, info, divergence)
    after_run(res, dyn, sc.environments, scheme, h, sc.disturbance is not None)
    return res


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
