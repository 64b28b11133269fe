"""``simulate(..., engine="mujoco")``: the closed loop of :func:`armctl.simulate` on a MuJoCo plant.

The loop is the native one: at every control instant t_k = k·Δt_c the controller is given the measured state
(noise, delay) and the reference; its torque, saturated at the armctl model's effort limits, is held over
[t_k, t_k + Δt_c) (zero-order hold, as ``qfrc_applied`` on the arm's joints) while MuJoCo integrates m = Δt_c/Δt
steps of its own integrator; a state that is not finite or beyond ``max_velocity`` / ``max_position``, or a
non-finite torque, ends the run as diverged. What differs is the plant (:mod:`armctl.sim.mujoco_plant`): MuJoCo's
equations, contacts and joint friction (``frictionloss``, a soft constraint: a joint loaded below its friction
level creeps where armctl's stick–slip model holds it exactly), the scene's geometry.

Each step is ``mj_forward`` then the integrator (what ``mj_step`` does, without MuJoCo's reset of a diverging
state: the loop reports it instead); the forward dynamics of a sample's first step give what is recorded at the
sample: q̈, the friction and external torques, the contact forces and the wrench. ``disturbance`` is held over each
step (its joint torque −J_toolᵀ h_d from the state at the step's start); the work of friction and of the external
forces over a step is that of the forces at its start.
"""

from __future__ import annotations

import math
import time
import warnings
from typing import Any

import numpy as np

from armctl._checks import boolean, nonnegative_vector, real_array, vector
from armctl._mujoco import require_mujoco
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError, ShapeError, SimulationWarning, UnknownNameError
from armctl.model.robot import RobotModel
from armctl.sim import setup
from armctl.sim.compiled import compile_option
from armctl.sim.contact import ForceSensor
from armctl.sim.mujoco_plant import MujocoPlant, Readout, available_integrators, integrator_code
from armctl.sim.recorder import Recorder
from armctl.sim.result import SimResult
from armctl.sim.run_failure import attach, end_run

ENGINES = ("native", "mujoco")


def run_engine(engine: Any, **args: Any) -> SimResult:
    """:func:`armctl.simulate` on another engine than the native one (``args``: simulate's arguments)."""
    if engine != "mujoco":
        raise UnknownNameError("engine", engine, ENGINES)
    return simulate_mujoco(**args)


def _plant(plant: Any) -> tuple[MujocoPlant, Dynamics]:
    if isinstance(plant, MujocoPlant):
        return plant, Dynamics(plant.model)
    if not isinstance(plant, Dynamics | RobotModel):
        raise InvalidParameterError(
            "with engine='mujoco' the plant must be an armctl.sim.MujocoPlant (a MuJoCo scene), an armctl.Dynamics "
            f"or an armctl.RobotModel; got {type(plant).__name__}",
            value=plant,
        )
    dyn = setup.plant_dynamics(plant)
    return MujocoPlant.from_model(dyn.model), dyn


def _refuse(name: str, value: Any, why: str) -> None:
    raise InvalidParameterError(f"{name}={value!r} is not available with engine='mujoco': {why}", value=value)


def simulate_mujoco(
    plant: Any,
    controller: Any,
    reference: Any,
    duration: float,
    q0: Any = None,
    qd0: Any = None,
    control_dt: float = 1e-3,
    dt: float | None = None,
    integrator: str = "rk4",
    *,
    friction: Any = "stick-slip",
    environment: Any = None,
    sensors: Any = (),
    disturbance: Any = None,
    saturate: bool = True,
    noise_q: Any = 0.0,
    noise_qd: Any = 0.0,
    seed: int | None = None,
    delay: int = 0,
    max_velocity: float = 1e3,
    max_position: float = math.inf,
    reset: bool = True,
    energy: bool = True,
    compile: bool | str = "auto",
) -> SimResult:
    """The run of :func:`armctl.simulate` with ``engine="mujoco"`` (see the module and ``simulate``).

    plant: a :class:`~armctl.sim.mujoco_plant.MujocoPlant`, or a Dynamics / RobotModel (then
    :meth:`MujocoPlant.from_model`). integrator: one of MuJoCo's, ``"rk4"``, ``"euler"``, ``"implicit"``,
    ``"implicitfast"`` or ``"discrete"`` (:data:`~armctl.sim.mujoco_plant.MUJOCO_INTEGRATORS`). Joint friction is
    the plant's ``frictionloss`` and ``damping`` (``friction`` must stay at its default); contact is the scene's
    (``environment`` must be None); ``compile`` must not be True. ``sensors`` read the contacts of the links at and
    beyond their joint, as in the native engine."""
    mj = require_mujoco("simulate(..., engine='mujoco')")
    if friction != "stick-slip":
        _refuse("friction", friction, "the joint friction is MuJoCo's frictionloss and damping of the plant")
    if environment is not None and environment != ():
        _refuse("environment", environment, "contact is the MuJoCo scene's: put the geometry in its MJCF (MujocoPlant)")
    if compile_option(compile) is True:
        _refuse("compile", compile, "MuJoCo integrates the plant")
    names = available_integrators()
    if integrator not in names:
        raise UnknownNameError("MuJoCo integrator", integrator, names)
    mp, dyn = _plant(plant)
    n, model = dyn.n, dyn.model
    cdt, h, n_periods, m_sub = setup.periods(duration, control_dt, dt)
    fixed_ref, ref_fn = setup.reference_source(reference, n)
    ref0 = fixed_ref if fixed_ref is not None else ref_fn(0.0)  # type: ignore[misc]  # one of the two is set
    call = setup.controller_call(controller, n)
    sig_q = nonnegative_vector(noise_q, n, "noise_q (a standard deviation)")
    sig_qd = nonnegative_vector(noise_qd, n, "noise_qd (a standard deviation)")
    lag = setup.delay_periods(delay)
    if lag >= n_periods > 0:
        warnings.warn(
            f"delay = {lag} control periods is not shorter than the run ({n_periods} periods): the controller sees "
            "only the first measurement",
            SimulationWarning,
            stacklevel=3,
        )
    saturate, reset, energy = boolean(saturate, "saturate"), boolean(reset, "reset"), boolean(energy, "energy")
    vmax, qmax = setup.bound(max_velocity, "max_velocity"), setup.bound(max_position, "max_position")
    q, v = setup.initial_state(q0, qd0, ref0, n, qmax, vmax)
    setup.warn_outside_limits(model, q)
    seed = setup.seed_value(seed)
    sens = setup.seq(sensors, ForceSensor, "sensors")
    for s in sens:
        model.frame(s.frame)
    if disturbance is not None and not callable(disturbance):
        raise InvalidParameterError(
            f"disturbance must be a callable t -> (6,) wrench or None, got {type(disturbance).__name__}",
            value=disturbance,
        )

    m, chain = mp.compile()
    m.opt.timestep = h
    m.opt.integrator = integrator_code(mj, integrator)
    m.opt.disableflags |= int(mj.mjtDisableBit.mjDSBL_ACTUATION)  # the controller's torque is all that drives
    d = mj.MjData(m)
    ro = Readout.of(mj, m, chain)
    qadr, vadr = ro.qadr, ro.vadr
    d.qpos[qadr] = q
    d.qvel[vadr] = v
    own_step = {"rk4": lambda: mj.mj_RungeKutta(m, d, 4), "euler": lambda: mj.mj_Euler(m, d)}.get(
        integrator, (lambda: mj.mj_implicit(m, d)) if integrator in ("implicit", "implicitfast") else None
    )
    forward = mj.mj_forward
    contact_on = not (m.opt.disableflags & mj.mjtDisableBit.mjDSBL_CONTACT) and bool(
        np.any(m.geom_contype) or np.any(m.geom_conaffinity)
    )
    has_friction = bool(np.any(m.dof_damping[vadr]) or np.any(m.dof_frictionloss[vadr]))
    simple = not (contact_on or has_friction or disturbance is not None or m.neq or m.ntendon)

    samples = n_periods + 1
    noisy = bool(sig_q.any() or sig_qd.any())
    rec = Recorder(n, samples, cdt, (), sens, measured=noisy or lag > 0)
    rec.contact_force = np.zeros((samples, n, 3))  # one row per link: the force it exerts on the scene
    rng = np.random.default_rng(seed)
    draws = rng.standard_normal((samples, 2, n)) if noisy else None
    limit = model.effort_limit
    clip = saturate and bool(np.isfinite(limit).any())
    if reset and callable(getattr(controller, "reset", None)):
        controller.reset()
    Q, QD, QDD, TAU = rec.q, rec.qd, rec.qdd, rec.tau
    views = [a.view() for a in (Q, QD, rec.q_measured, rec.qd_measured)]
    for a in views:
        a.flags.writeable = False
    QR, QDR, QMR, QDMR = views
    wf = we = 0.0
    clipped: list[int] = []
    divergence, rows = None, samples
    failure: BaseException | None = None
    failed_at = math.nan
    qfrc = d.qfrc_applied

    t0 = time.perf_counter()
    with np.errstate(all="ignore"):
        try:
            for k in range(samples):
                t = k * cdt
                q, v = d.qpos[qadr], d.qvel[vadr]
                ql, vl = q.tolist(), v.tolist()
                if not math.isfinite(sum(ql) + sum(vl)) and not (np.isfinite(q).all() and np.isfinite(v).all()):
                    divergence, rows = (t, "the state is not finite", q, v), k
                    break
                if max(vl) > vmax or -min(vl) > vmax:
                    divergence, rows = (t, f"a joint velocity is beyond max_velocity = {vmax:g}", q, v), k
                    break
                if qmax < math.inf and (max(ql) > qmax or -min(ql) > qmax):
                    divergence, rows = (t, f"a joint position is beyond max_position = {qmax:g}", q, v), k
                    break
                Q[k], QD[k] = q, v
                if not simple:
                    rec.work_friction[k], rec.work_external[k] = wf, we
                qm, vm = QR[k], QDR[k]
                if rec.measured:
                    rec.q_measured[k] = q + draws[k, 0] * sig_q if draws is not None else q
                    rec.qd_measured[k] = v + draws[k, 1] * sig_qd if draws is not None else v
                    j = k - lag if k >= lag else 0
                    qm, vm = QMR[j], QDMR[j]
                ref = fixed_ref if fixed_ref is not None else setup.check_reference(ref_fn(t), n, t)  # type: ignore[misc]  # one is set
                rec.references[k] = ref
                try:
                    tau = call(t, qm, vm, ref)
                except ValueError as exc:
                    if "read-only" not in str(exc):
                        raise
                    raise InvalidParameterError(
                        f"the controller wrote into a read-only array at t = {t:g} s ({exc}); the q and q̇ it is "
                        "given are read-only views of the run's record: work on a copy (q = q.copy()) or on new arrays",
                        value=t,
                    ) from exc
                if not isinstance(tau, np.ndarray) or tau.dtype != np.float64:
                    tau = real_array(tau, f"the controller's torque at t = {t:g} s")
                log = getattr(controller, "last_log", None)  # (read every step: a controller may set it later)
                if log:
                    rec.log_controller(k, log)
                if tau.shape != (n,):
                    raise ShapeError(
                        f"the controller returned a torque of shape {tau.shape} at t = {t}; expected ({n},)", value=tau
                    )
                if not np.isfinite(tau).all():
                    divergence, rows = (t, f"the controller returned a non-finite torque {tau}", q, v), k
                    break
                tau_a = tau
                if clip and np.any(np.abs(tau) > limit):
                    tau_a = np.clip(tau, -limit, limit)
                    clipped.append(k)
                TAU[k] = tau
                for s in range(m_sub):
                    hd = None
                    if disturbance is not None:
                        hd = vector(
                            real_array(disturbance(t + s * h), "disturbance(t)"), 6, "disturbance(t) (a wrench)"
                        )
                        qfrc[vadr] = tau_a - dyn.jacobian(d.qpos[qadr] if s else q).T @ hd
                    else:
                        qfrc[vadr] = tau_a
                    forward(m, d)
                    if s == 0:
                        QDD[k] = d.qacc[vadr]
                    if not simple:
                        tf, te = ro.torques(d)
                        if s == 0:
                            ro.record(rec, d, dyn, k, q, tf, te, hd)
                    if k == n_periods:
                        break
                    before = d.qpos[qadr] if not simple else None
                    if own_step is not None:
                        own_step()
                    else:
                        mj.mj_step(m, d)  # (an integrator without its own entry point: one more forward dynamics)
                    if before is not None:
                        dq = d.qpos[qadr] - before
                        wf -= float(tf @ dq)
                        we -= float(te @ dq)
                        if hd is not None:  # −J_toolᵀ h_d is in qfrc_applied, not in te
                            we += float((qfrc[vadr] - tau_a) @ dq)
        except BaseException as exc:  # the controller's, the reference's or the disturbance's: the run so far is kept
            failure, failed_at, rows = exc, t, k + 1  # (sample k's state is recorded; what was not computed is NaN)

    rec.tau_applied[:] = rec.tau
    if clipped:
        rec.tau_applied[clipped] = np.clip(rec.tau[clipped], -limit, limit)
    wall = time.perf_counter() - t0
    info = {
        "engine": "mujoco",
        "mujoco": mj.__version__,
        "plant": model.name,
        "n": n,
        "backend": "mujoco",
        "integrator": integrator,
        "control_dt": cdt,
        "dt": h,
        "substeps": m_sub,
        "periods": n_periods,
        "friction": "frictionloss" if has_friction else "none",
        "contact": bool(contact_on),
        "saturate": bool(saturate),
        "delay": lag,
        "compiled": False,
        "seed": seed,
        "wall_time": wall,
        "real_time_factor": (rows - 1) * cdt / wall if wall > 0 and rows > 1 else math.nan,
    }
    if divergence is not None:
        divergence = (divergence[0], divergence[1], np.array(divergence[2]), np.array(divergence[3]))
    raised = end_run(controller, failure)
    if raised is not failure:  # end_run raised after a run that did not
        failed_at = (rows - 1) * cdt
    if raised is not None:
        info["failure"] = f"{type(raised).__name__}: {raised}"
    res = rec.result(rows, dyn, energy, info, divergence)
    if raised is not None:
        attach(raised, res, failed_at)
        raise raised
    return res
