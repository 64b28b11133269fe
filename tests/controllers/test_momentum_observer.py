"""The momentum observer against the simulator's true external joint torques (Jᵀ h of the recorded wrench), the
closed-form first-order step response, known and unknown joint friction, free motion of the exact model from
random states (hypothesis), collision isolation by link, and the estimated wrench against the true one."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import armctl
from armctl.controllers import MomentumObserver, PDGravity
from armctl.errors import (
    InvalidParameterError,
    NonFiniteError,
    ShapeError,
    SimulationWarning,
    SingularConfigurationError,
    UnknownNameError,
)
from armctl.sim import ContactPoint, Forces, KelvinVoigt, Plane, simulate
from tests.helpers.arms import dynamics, model

Q_READY = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
KP = np.array([400.0, 400.0, 400.0, 400.0, 50.0, 50.0, 20.0])  # [N·m/rad]; the light wrist gets less
KD = np.array([40.0, 40.0, 40.0, 40.0, 4.0, 4.0, 1.0])  # [N·m·s/rad], stable at 1 kHz


def observe(obs: MomentumObserver, res: armctl.sim.SimResult) -> np.ndarray:
    """The observer run over a recorded run: at t_k it is given τ_{k−1}, the torque held since t_{k−1}."""
    out = []
    for k, (t, q, qd) in enumerate(zip(res.t, res.q, res.qd, strict=True)):
        out.append(obs.update(t, q, qd, res.tau_applied[k - 1] if k else np.zeros(len(q))))
    return np.array(out)


def push_run(step_at: float = 0.3, force: float = 20.0, duration: float = 0.6) -> armctl.sim.SimResult:
    """The Panda held at its ready pose by a stiff PD + gravity, pushed at the tool from ``step_at`` on."""
    dyn = dynamics("panda")
    h = np.array([0.0, force, force, 0.0, 0.0, 0.0])
    return simulate(
        model("panda"),
        PDGravity(dyn, KP, KD),
        armctl.Reference(Q_READY),
        duration,
        q0=Q_READY,
        forces=Forces(disturbance=lambda t: h if t >= step_at else np.zeros(6)),
    )


def test_estimate_matches_the_true_external_torques_after_five_time_constants() -> None:
    res = push_run()
    dyn = dynamics("panda")
    true = np.array([dyn.jacobian(q).T @ w for q, w in zip(res.q, res.wrench, strict=True)])  # Jᵀ h
    np.testing.assert_allclose(true, res.tau_ext, atol=1e-9)
    for gain in (20.0, 50.0, 200.0):
        r = observe(MomentumObserver(dyn, gain), res)
        peak = np.abs(true).max()
        late = res.t >= 0.3 + 5.0 / gain
        assert np.abs(r - true)[late].max() < 0.01 * peak, gain
        assert np.abs(r[res.t < 0.3]).max() < 1e-3 * peak  # free of the push: nothing read


def test_step_response_is_first_order_with_time_constant_one_over_the_gain() -> None:
    res = push_run(step_at=0.3)
    gain = 40.0
    r = observe(MomentumObserver(dynamics("panda"), gain), res)
    after = (res.t > 0.3) & (res.t <= 0.3 + 3.0 / gain)
    step = res.tau_ext[after]
    # the joints whose external torque is a step (the push's joint torque moves < 2 % as the arm gives way)
    steady = (np.abs(step - step[-1]).max(axis=0) < 0.02 * np.abs(step[-1])) & (np.abs(step[-1]) > 1.0)
    assert steady.sum() >= 3
    for j in np.flatnonzero(steady):
        # 1 − r/τ_ext = exp(−(t − t_s)/T): the slope of its logarithm is −1/T
        y = np.log(1.0 - r[after, j] / res.tau_ext[after, j])
        slope = np.polyfit(res.t[after] - 0.3, y, 1)[0]
        assert -1.0 / slope == pytest.approx(1.0 / gain, rel=0.05), j


def test_the_euler_form_has_the_pole_one_minus_gain_times_period() -> None:
    res = push_run(step_at=0.3)
    gain = 40.0
    r = observe(MomentumObserver(dynamics("panda"), gain, discretization="euler"), res)
    j = int(np.argmax(np.abs(res.tau_ext[-1])))
    k = int(np.flatnonzero(res.t > 0.3)[0])
    e = 1.0 - r[k : k + 20, j] / res.tau_ext[k : k + 20, j]  # e_k = (1 − K h)^k
    ratios = e[1:] / e[:-1]
    np.testing.assert_allclose(ratios, 1.0 - gain * 1e-3, rtol=5e-3)


def friction_run() -> armctl.sim.SimResult:
    """The Panda with viscous and Coulomb joint friction sweeping in one direction (no velocity reversal)."""
    m = model("panda").with_friction(viscous=0.5, coulomb=[1.0, 1.0, 1.0, 1.0, 0.4, 0.4, 0.4])
    dyn = armctl.Dynamics(m)
    speed = np.array([0.3, 0.2, 0.3, 0.25, 0.4, 0.3, 0.5])
    ref = lambda t: armctl.Reference(Q_READY + speed * t, speed, np.zeros(7))  # noqa: E731
    return simulate(m, PDGravity(dyn, KP, KD), ref, 0.6, q0=Q_READY, qd0=speed)


def test_known_friction_is_not_read_as_an_external_torque() -> None:
    res = friction_run()
    dyn = armctl.Dynamics(res.plant)
    assert np.all(res.qd[50:] * np.sign(res.qd[50:][0]) > 0)  # sliding: the simulator's friction is the law's
    gain = 50.0
    late = res.t >= 5.0 / gain
    friction_peak = np.abs(res.tau_friction[late]).max()
    known = observe(MomentumObserver(dyn, gain), res)
    assert np.abs(known[late]).max() < 0.01 * friction_peak
    # told not to know it, the observer reads the friction torque itself (τ_f enters as τ_ext does)
    unknown = observe(MomentumObserver(dyn, gain, friction=False), res)
    np.testing.assert_allclose(unknown[late], res.tau_friction[late], atol=0.05 * friction_peak)  # (its lag)


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.sampled_from(["planar_2r", "planar_3r", "panda"]),
    st.integers(0, 2**31 - 1),
    st.sampled_from([5.0, 50.0, 500.0]),
)
def test_residual_is_zero_along_free_motion_of_the_exact_model(name: str, seed: int, gain: float) -> None:
    """Zero up to the quadrature of β: the held torque and the momentum's change are exact."""
    dyn = dynamics(name)
    rng = np.random.default_rng(seed)
    q0, qd0 = rng.uniform(-1.5, 1.5, dyn.n), rng.uniform(-1.0, 1.0, dyn.n)
    push = rng.uniform(-20.0, 20.0, dyn.n) * np.diag(dyn.mass_matrix(q0))  # accelerations of order 20 rad/s²

    def law(t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        return dyn.gravity_torque(q) + push  # held over each period: the arm moves freely under it

    with warnings.catch_warnings():  # free motion far beyond the velocity limits: the run says so, as it should
        warnings.simplefilter("ignore", SimulationWarning)
        # the plant at 0.1 ms steps: its RK4 error on p, which the gain K_O multiplies, far below the bound
        res = simulate(dyn, law, armctl.Reference(q0), 0.2, q0=q0, qd0=qd0, dt=1e-4, saturate=False)
    assert not res.diverged
    r = observe(MomentumObserver(dyn, gain), res)
    # all that is left is the trapezoid's error on β = Cᵀq̇ − g over each period, −h²/12 β̈: bounded by the
    # second differences of β along the run (β from the Coriolis matrix, not the observer's code), and the
    # simulator's own integration error (RK4, far below)
    beta = np.array(
        [dyn.coriolis_matrix(q, qd).T @ qd - dyn.gravity_torque(q) for q, qd in zip(res.q, res.qd, strict=True)]
    )
    bound = np.abs(np.diff(beta, 2, axis=0)).max(axis=0) / 12.0
    assert (np.abs(r).max(axis=0) <= 2.0 * bound + 1e-6 * np.abs(res.tau_applied).max()).all()


def test_collision_isolation_names_the_link_that_was_hit() -> None:
    """A floor hit by a point on link 4 raises residuals on joints 1..4 only: joint 4 is the last above
    threshold, and the hook is called once with it."""
    m, dyn = model("panda"), dynamics("panda")
    pose = dyn.frame_pose(Q_READY, "panda_joint4")
    offset = np.array([0.0, 0.1, 0.0])  # off joint 4's axis: the contact force has a moment about it
    point = pose[:3, 3] + pose[:3, :3] @ offset
    floor = Plane(KelvinVoigt(5e3, 20.0), point=point - [0, 0, 0.005], points=[ContactPoint("panda_joint4", offset)])
    speed = np.array([0.0, 0.0, 0.0, -0.3, 0.0, 0.0, 0.0])  # the elbow folds: the point on link 4 goes down
    ref = lambda t: armctl.Reference(Q_READY + speed * t, speed, np.zeros(7))  # noqa: E731
    res = simulate(m, PDGravity(dyn, KP, KD), ref, 0.5, q0=Q_READY, forces=Forces(environment=floor))
    touched = np.flatnonzero(np.abs(res.contact_force_on_environment[:, 0]).max(axis=1) > 0)
    assert touched.size
    calls = []
    obs = MomentumObserver(dyn, 100.0, thresholds=2.0, on_collision=lambda o, c: calls.append(c))
    observe(obs, res)
    assert obs.collision and len(calls) == 1 and calls[0] is obs.collision
    assert obs.collision.joint == 3 and obs.collision.link == "panda_joint4"
    assert obs.collision.t >= res.t[touched[0]]
    assert np.abs(res.tau_ext[:, 4:]).max() < 1e-9  # the truth: nothing beyond joint 4
    obs.clear()
    assert not obs.collision


def test_wrench_estimate_matches_the_true_wrench() -> None:
    res = push_run(force=15.0)
    dyn = dynamics("panda")
    obs = MomentumObserver(dyn, 100.0)
    observe(obs, res)
    np.testing.assert_allclose(obs.wrench(res.q[-1]), res.wrench[-1], atol=0.01 * 15.0)
    # planar arm: the minimum-norm wrench explains the residual
    d2 = dynamics("planar_2r")
    obs2 = MomentumObserver(d2, 50.0)
    obs2.residual = np.array([1.0, 0.5])
    q = np.array([0.3, 1.0])
    np.testing.assert_allclose(d2.jacobian(q).T @ obs2.wrench(q), obs2.residual, atol=1e-12)


# ----------------------------------------------------------------------------------------------- bad input
def test_gain_must_be_positive_and_within_the_euler_bound() -> None:
    dyn = dynamics("planar_2r")
    for bad in (0.0, -5.0, [50.0, 0.0], float("nan")):
        with pytest.raises(InvalidParameterError, match="K_O"):
            MomentumObserver(dyn, bad)
    MomentumObserver(dyn, 1999.0, period=1e-3, discretization="euler")
    with pytest.raises(InvalidParameterError, match=r"K_O < 2000"):
        MomentumObserver(dyn, 2000.0, period=1e-3, discretization="euler")
    obs = MomentumObserver(dyn, 1500.0, discretization="euler")  # the period learnt at the second update
    obs.update(0.0, [0.1, 0.2], [0.0, 0.0], [0.0, 0.0])
    with pytest.raises(InvalidParameterError, match="too large for the period"):
        obs.update(2e-3, [0.1, 0.2], [0.0, 0.0], [0.0, 0.0])
    MomentumObserver(dyn, 1e5, period=1e-3)  # the exact form: stable for every gain


def test_other_bad_input_is_named() -> None:
    dyn = dynamics("planar_2r")
    with pytest.raises(InvalidParameterError, match="discretization"):
        MomentumObserver(dyn, 10.0, discretization="tustin")
    with pytest.raises(InvalidParameterError, match="thresholds"):
        MomentumObserver(dyn, 10.0, thresholds=-1.0)
    with pytest.raises(InvalidParameterError, match="on_collision"):
        MomentumObserver(dyn, 10.0, on_collision="stop")  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="dynamics"):
        MomentumObserver(model("planar_2r"), 10.0)  # type: ignore[arg-type]
    obs = MomentumObserver(dyn, 10.0)
    obs.update(0.1, [0.1, 0.2], [0.0, 0.0], [0.0, 0.0])
    with pytest.raises(InvalidParameterError, match="forward in time"):
        obs.update(0.1, [0.1, 0.2], [0.0, 0.0], [0.0, 0.0])
    with pytest.raises(ShapeError):
        obs.update(0.2, [0.1, 0.2, 0.3], [0.0, 0.0], [0.0, 0.0])
    with pytest.raises(NonFiniteError):
        obs.update(0.2, [0.1, 0.2], [np.nan, 0.0], [0.0, 0.0])


def test_wrench_at_a_singular_configuration_is_refused_by_name() -> None:
    obs = MomentumObserver(dynamics("panda"), 10.0)
    with pytest.raises(SingularConfigurationError, match="singular") as info:
        obs.wrench(np.zeros(7))  # the Panda stretched upright: joints 1, 3, 5 and 7 share one axis
    assert info.value.sigma_min < 1e-9
    with pytest.raises(UnknownNameError):
        obs.wrench(Q_READY, frame="no_such_frame")


@pytest.mark.parametrize("compile", [False, True])
def test_every_non_finite_entry_is_named(compile: bool) -> None:
    """NaN or inf in any entry of q, q̇ or τ raises a NonFiniteError naming the input, on the unchecked fast path
    too (the Panda's M(q) does not depend on q₁: the estimate must not silently ignore it)."""
    dyn = armctl.Dynamics(model("panda"), compile=compile)
    for name in ("q", "qd", "tau_applied"):
        for j in range(7):
            for bad in (np.nan, np.inf):
                obs = MomentumObserver(dyn, 20.0, compile=compile)
                obs.update(0.0, Q_READY, np.zeros(7), np.zeros(7))
                args = {"q": Q_READY.copy(), "qd": np.zeros(7), "tau_applied": np.zeros(7)}
                args[name][j] = bad
                with pytest.raises(NonFiniteError, match=name):
                    obs.update(1e-3, args["q"], args["qd"], args["tau_applied"])


def test_the_generated_update_agrees_with_the_kernel_one() -> None:
    m = model("panda").with_friction(viscous=0.4, coulomb=[1.0, 1.0, 1.0, 1.0, 0.3, 0.3, 0.3])
    plain = MomentumObserver(armctl.Dynamics(m), 30.0, thresholds=4.0, compile=False)
    fast = MomentumObserver(armctl.Dynamics(m), 30.0, thresholds=4.0)  # compile="auto": the generated code
    assert fast.compiled and not plain.compiled
    rng = np.random.default_rng(3)
    for k in range(60):
        q, qd, tau = rng.uniform(-1.0, 1.0, (3, 7))
        np.testing.assert_allclose(fast.update(k * 1e-3, q, qd, tau), plain.update(k * 1e-3, q, qd, tau),
                                   rtol=1e-10, atol=1e-9)  # fmt: skip
    assert fast.collision is not None and plain.collision is not None
    assert (fast.collision.t, fast.collision.joint) == (plain.collision.t, plain.collision.joint)
    with pytest.raises(InvalidParameterError, match="exact"):
        MomentumObserver(armctl.Dynamics(m), 30.0, discretization="euler", compile=True)
    assert not MomentumObserver(armctl.Dynamics(m), 30.0, discretization="euler").compiled  # "auto": the kernel
    assert not MomentumObserver(armctl.Dynamics(m, backend="lagrange"), 30.0).compiled  # another model's code
    with pytest.raises(InvalidParameterError, match="compile"):
        MomentumObserver(armctl.Dynamics(m), 30.0, compile="yes")


@pytest.mark.parametrize("compile", [False, True])
def test_a_refused_sample_leaves_the_observer_as_it_was(compile: bool) -> None:
    dyn = armctl.Dynamics(model("panda"), compile=compile)
    rng = np.random.default_rng(5)
    samples = [rng.uniform(-1.0, 1.0, (3, 7)) for _ in range(6)]
    clean, hit = MomentumObserver(dyn, 20.0, compile=compile), MomentumObserver(dyn, 20.0, compile=compile)
    for k, (q, qd, tau) in enumerate(samples):
        if k == 3:
            with pytest.raises(NonFiniteError):
                hit.update(k * 1e-3 - 5e-4, q, np.full(7, np.nan), tau)
        np.testing.assert_array_equal(hit.update(k * 1e-3, q, qd, tau), clean.update(k * 1e-3, q, qd, tau))


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_the_generated_code_takes_c_transpose_qdot_as_the_gradient_of_kinetic_energy(seed: int) -> None:
    """Cᵀ q̇ = ∂T/∂q (Ṁ = C + Cᵀ): the generated β against central differences of Pinocchio's kinetic energy, and
    against the Coriolis matrix."""
    from armctl.controllers.momentum_code import symbolic_step

    dyn = dynamics("panda")
    rng = np.random.default_rng(seed)
    q, qd = rng.uniform(-2.0, 2.0, 7), rng.uniform(-2.0, 2.0, 7)
    fn = symbolic_step(model("panda"))
    state = np.concatenate((np.zeros(21), np.ones(7), [1.0]))
    coeffs = np.concatenate((np.zeros(21), np.full(7, np.inf), [0.0]))
    beta = np.asarray(fn(np.concatenate((q, qd, np.zeros(7))), state, coeffs)[0]).ravel()[14:21]
    eps = 1e-6
    grad = np.array([(dyn.kinetic_energy(q + eps * e, qd) - dyn.kinetic_energy(q - eps * e, qd)) / (2 * eps)
                     for e in np.eye(7)])  # fmt: skip
    np.testing.assert_allclose(beta + dyn.gravity_torque(q), grad, atol=1e-6)
    np.testing.assert_allclose(grad, dyn.coriolis_matrix(q, qd).T @ qd, atol=1e-6)


def test_force_control_reads_the_observer_instead_of_a_sensor() -> None:
    """Parallel force/position control pressing 10 N on a table, its force from the observer (the applied torques,
    no sensor): at rest the true contact force is 10 N, as with the sensor."""
    from armctl.bench.interaction_borders import press
    from armctl.controllers import ParallelForcePosition

    dyn = dynamics("panda")
    c = ParallelForcePosition(dyn, [0.0, 0.0, -10.0], 2e-4, 1e-3, kp=400.0, force_source=MomentumObserver(dyn, 100.0))
    assert c.reads == {"tau_applied"}
    res = press(c, 3e4, 2.0)
    f = res.contact_force_on_robot[:, 0, 2]  # the simulator's truth
    assert np.abs(f[res.t > 1.7] - 10.0).max() < 0.01
