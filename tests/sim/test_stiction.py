"""Stick–slip friction: exact sticking (no creep, no chatter), breakaway at the predicted torque, and the
multi-joint constraint solve checked against arms whose stuck joints are locked in the model."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import armctl
from armctl.sim import simulate
from tests.sim.helpers import OpenLoop, PDGravity, Ramp, slider, zero_torque

# the pendulum's gravity torque in closed form: m g ℓ_c sin q with m = 2 kg, ℓ_c = 0.25 m
M_PEND, LC, G = 2.0, 0.25, 9.81


def gravity_pendulum(q: float) -> float:
    return M_PEND * G * LC * math.sin(q)


def pendulum(**friction: float) -> armctl.RobotModel:
    return armctl.models.pendulum().with_friction(**friction)


@pytest.mark.parametrize("integrator", ["rk4", "semi-implicit-euler", "implicit-euler"])
def test_pendulum_held_by_coulomb_friction_does_not_move_at_all(integrator: str) -> None:
    q0 = 0.3
    assert gravity_pendulum(q0) < 3.0
    res = simulate(
        pendulum(viscous=0.05, coulomb=3.0), zero_torque, armctl.Reference.hold([q0]), 10.0, integrator=integrator
    )
    assert not res.diverged and len(res.t) == 10001
    assert (res.q == q0).all()  # bit for bit: no creep
    assert (res.qd == 0.0).all() and (res.qdd == 0.0).all()  # no chatter
    assert res.stuck.all()
    # the holding friction torque balances gravity: 0 = τ − τ_f − g  ⇒  τ_f = −g
    assert res.tau_friction[:, 0] == pytest.approx(-gravity_pendulum(q0), rel=1e-12)


def test_noisy_controller_below_breakaway_does_not_make_it_chatter() -> None:
    """A PD fed noisy measurements commands a jittering torque that stays below the breakaway level."""
    model = pendulum(coulomb=3.0)
    ctrl = PDGravity(armctl.Dynamics(model.reduced(friction=False)), kp=5.0, kd=0.5)
    res = simulate(model, ctrl, armctl.Reference.hold([0.35]), 5.0, q0=[0.3], noise_q=1e-3, noise_qd=1e-2, seed=1)
    net = res.tau_applied[:, 0] - gravity_pendulum(0.3)
    assert np.ptp(res.tau_applied) > 1e-3 and np.abs(net).max() < 3.0
    assert (res.q == 0.3).all() and (res.qd == 0.0).all()


@pytest.mark.parametrize(
    ("rate", "coulomb", "static"), [(1.0, 3.0, None), (-1.0, 3.0, None), (2.0, 2.0, 3.5), (-0.5, 1.0, 2.5)]
)
def test_torque_ramp_breaks_away_at_the_predicted_torque(rate: float, coulomb: float, static: float | None) -> None:
    q0 = 0.3
    breakaway = coulomb if static is None else static
    # net torque τ − g(q0) reaches ±F_s
    predicted = gravity_pendulum(q0) + math.copysign(breakaway, rate)
    duration = round(abs(predicted / rate) * 1.3, 1)
    model = pendulum(coulomb=coulomb, static=static) if static is not None else pendulum(coulomb=coulomb)
    res = simulate(model, OpenLoop(Ramp([0.0], [rate])), armctl.Reference.hold([q0]), duration)
    moved = np.flatnonzero(res.q[:, 0] != q0)
    assert moved.size, "it never broke away"
    k = moved[0] - 1  # the control period in which it started moving
    assert (res.q[: k + 1, 0] == q0).all()
    assert res.tau_applied[k, 0] == pytest.approx(predicted, rel=0.01)
    assert np.sign(res.q[moved[0], 0] - q0) == np.sign(rate)
    assert res.info["breakaway_events"] >= 1


@pytest.mark.parametrize(("rate", "up", "down"), [(1.0, 3.0, 2.0), (-1.0, 3.0, 2.0), (1.0, 1.5, 2.5), (-1.0, 1.5, 2.5)])
def test_asymmetric_breakaway_levels_each_hold_their_own_side(rate: float, up: float, down: float) -> None:
    # Coulomb F_c⁺ = up for motion in +q, F_c⁻ = down for −q (no static level: each side breaks away at its
    # own): a ramp in +τ breaks away when τ − g(q0) reaches +F_c⁺, one in −τ when it reaches −F_c⁻. Swapping
    # the two levels anywhere in the stick–slip solve moves each prediction by |F_c⁺ − F_c⁻| = 1 N·m
    q0 = 0.3
    predicted = gravity_pendulum(q0) + (up if rate > 0 else -down)
    res = simulate(
        pendulum(coulomb=up, coulomb_negative=down),
        OpenLoop(Ramp([0.0], [rate])),
        armctl.Reference.hold([q0]),
        round(abs(predicted) * 1.3 + 0.2, 1),
    )
    moved = np.flatnonzero(res.q[:, 0] != q0)
    assert moved.size, "it never broke away"
    k = moved[0] - 1
    assert (res.q[: k + 1, 0] == q0).all()
    assert res.tau_applied[k, 0] == pytest.approx(predicted, rel=0.01, abs=0.01)
    assert np.sign(res.q[moved[0], 0] - q0) == np.sign(rate)


def test_gravity_beyond_the_lower_level_pulls_the_pendulum_down_at_once() -> None:
    # g(0.3) = 1.45 N·m pulls towards −q: F_c⁺ = 3 cannot hold it, F_c⁻ = 1 < 1.45 cannot either — it slides
    # from the start; with the levels the other way round (F_c⁻ = 3) it is held
    free = simulate(pendulum(coulomb=3.0, coulomb_negative=1.0), zero_torque, armctl.Reference.hold([0.3]), 0.5)
    held = simulate(pendulum(coulomb=1.0, coulomb_negative=3.0), zero_torque, armctl.Reference.hold([0.3]), 0.5)
    assert free.q[-1, 0] < 0.3 - 0.05 and not free.stuck[1:].any()
    assert (held.q == 0.3).all() and held.stuck.all()


def test_stribeck_friction_starts_at_the_static_level_and_falls_to_coulomb() -> None:
    fv, fc, fs, vs = 0.1, 2.0, 3.0, 0.05
    model = slider().with_friction(viscous=fv, coulomb=fc, static=fs, stribeck_velocity=vs)
    res = simulate(model, OpenLoop(Ramp([3.2], [0.0])), armctl.Reference.hold([0.0]), 1.0)
    v = res.qd[1:, 0]
    assert (v > 0).all()  # broke away at once (3.2 > 3.0) and kept going

    def curve(speed: np.ndarray) -> np.ndarray:  # the Stribeck curve, written out
        return fv * speed + fc + (fs - fc) * np.exp(-((speed / vs) ** 2))

    np.testing.assert_allclose(res.tau_friction[1:, 0], curve(v), rtol=1e-12)
    assert res.tau_friction[1, 0] > 2.9 and res.tau_friction[-1, 0] < fc + fv * v[-1] + 1e-6


def test_smooth_friction_creeps_where_stick_slip_holds() -> None:
    """The documented difference: tanh friction lets a joint under a net torque below F_c creep."""
    model = pendulum(coulomb=3.0)
    held = simulate(model, zero_torque, armctl.Reference.hold([0.3]), 2.0)
    creep = simulate(model, zero_torque, armctl.Reference.hold([0.3]), 2.0, friction="smooth")
    assert (held.q == 0.3).all()
    assert creep.q[-1, 0] < 0.3 - 1e-4


def test_panda_held_by_static_friction_stays_exactly_still() -> None:
    model = armctl.models.panda()
    q0 = np.array([0.2, -0.6, 0.1, -2.0, 0.3, 1.8, 0.5])
    g0 = armctl.Dynamics(model).gravity_torque(q0)
    sticky = model.with_friction(viscous=0.5, coulomb=np.abs(g0) + 1.0, static=np.abs(g0) + 3.0)
    res = simulate(sticky, zero_torque, armctl.Reference.hold(q0), 10.0)
    assert (res.q == q0).all() and (res.qd == 0.0).all() and res.stuck.all()
    np.testing.assert_allclose(res.tau_friction[-1], -g0, rtol=1e-9, atol=1e-9)


# ---------------------------------------------------------------------------------------- several joints
HANG = -math.pi / 2  # planar_2r hanging straight down


def _two_link(static1: float) -> armctl.RobotModel:
    return armctl.models.planar_2r().with_friction(viscous=[0.0, 5.0], coulomb=[static1, 20.0], static=[static1, 30.0])


def _drive(t: float) -> np.ndarray:
    return np.array([0.0, 900.0 * math.sin(2.0 * math.pi * t)])


def test_stuck_joint_acts_as_locked_and_holds_the_reaction_torque() -> None:
    """Joint 1 stuck by a large static friction: joint 2 moves exactly as on the arm with joint 1 locked
    (an independently built 1-joint Pinocchio model), and joint 1's friction is the reaction torque that
    the full model's inverse dynamics asks for with q̈₁ = 0."""
    model = _two_link(static1=1e5)
    res = simulate(model, OpenLoop(_drive), armctl.Reference.hold([HANG, 0.0]), 2.0)
    locked = model.reduced(lock={"joint1": HANG})
    ref = simulate(locked, OpenLoop(lambda t: _drive(t)[1:]), armctl.Reference.hold([0.0]), 2.0)
    assert (res.q[:, 0] == HANG).all() and (res.qd[:, 0] == 0.0).all()
    assert np.ptp(res.q[:, 1]) > 0.5  # joint 2 swung
    np.testing.assert_allclose(res.q[:, 1], ref.q[:, 0], atol=1e-9)
    rigid = armctl.Dynamics(model.reduced(friction=False))
    for k in range(0, 2001, 97):
        qd = np.array([0.0, ref.qd[k, 0]])
        qdd = np.array([0.0, ref.qdd[k, 0]])
        reaction = -rigid.inverse_dynamics(res.q[k], qd, qdd)[0]  # τ₁ = 0 = ID₁ + τ_f1
        assert res.tau_friction[k, 0] == pytest.approx(reaction, rel=1e-6, abs=1e-6)


def test_coupling_breaks_a_stuck_joint_loose_when_the_reaction_exceeds_its_static_level() -> None:
    """With a smaller static level, joint 1 breaks away when the reaction torque that joint 2's motion
    puts on it — computed from the locked-arm run and the full model's inverse dynamics — first exceeds it."""
    locked = _two_link(static1=1e5).reduced(lock={"joint1": HANG})
    ref = simulate(locked, OpenLoop(lambda t: _drive(t)[1:]), armctl.Reference.hold([0.0]), 2.0)
    rigid = armctl.Dynamics(armctl.models.planar_2r())
    reaction = np.array(
        [
            -rigid.inverse_dynamics([HANG, q], [0.0, v], [0.0, a])[0]
            for q, v, a in zip(ref.q[:, 0], ref.qd[:, 0], ref.qdd[:, 0], strict=True)
        ]
    )
    static1 = 0.6 * np.abs(reaction).max()
    predicted = int(np.flatnonzero(np.abs(reaction) > static1)[0])
    res = simulate(_two_link(static1), OpenLoop(_drive), armctl.Reference.hold([HANG, 0.0]), 2.0)
    started = int(np.flatnonzero(res.q[:, 0] != HANG)[0])
    assert predicted <= started <= predicted + 2, (predicted, started)
    np.testing.assert_allclose(res.q[:predicted, 1], ref.q[:predicted, 0], atol=1e-9)


@settings(max_examples=15, deadline=None)
@given(q0=st.floats(-1.2, 1.2), margin=st.floats(0.05, 2.0), sign=st.sampled_from([-1.0, 1.0]))
def test_pendulum_sticks_exactly_when_gravity_is_below_breakaway(q0: float, margin: float, sign: float) -> None:
    g = abs(gravity_pendulum(q0))
    level = max(g + sign * margin, 0.01)
    res = simulate(pendulum(coulomb=level), zero_torque, armctl.Reference.hold([q0]), 0.2)
    if level > g:
        assert (res.q == q0).all()
    else:
        assert abs(res.q[-1, 0] - q0) > 0.0 and np.sign(res.q[-1, 0] - q0) == -np.sign(q0)


@settings(max_examples=12, deadline=None)
@given(
    q0=st.lists(st.floats(-2.0, 2.0), min_size=3, max_size=3),
    static=st.lists(st.floats(0.5, 40.0), min_size=3, max_size=3),
    ratio=st.floats(0.3, 1.0),
    torque=st.lists(st.floats(-10.0, 10.0), min_size=3, max_size=3),
)
# its run goes beyond a velocity limit on the way, as expected
@pytest.mark.filterwarnings("ignore:the run went beyond the plant's limits:armctl.errors.SimulationWarning")
def test_several_joints_stick_and_slip_consistently(
    q0: list[float], static: list[float], ratio: float, torque: list[float]
) -> None:
    """planar_3r from rest under random constant torques and random stiction: whatever sticks or slips, a
    stuck joint has exactly zero velocity and a holding torque within its breakaway band, and the energy
    balance closes (the stick solve and the events lose or make no energy)."""
    static_a = np.array(static)
    model = armctl.models.planar_3r().with_friction(viscous=0.2, coulomb=ratio * static_a, static=static_a)
    res = simulate(model, OpenLoop(Ramp(torque, [0.0, 0.0, 0.0])), armctl.Reference.hold(q0), 0.3, dt=5e-4)
    assert not res.diverged
    stuck = res.stuck
    assert (res.qd[stuck] == 0.0).all()
    held = np.abs(res.tau_friction) <= static_a * (1 + 1e-9) + 1e-9
    assert held[stuck].all()
    scale = max(np.abs(res.work_actuator).max(), 1.0)
    assert np.abs(res.energy_balance()).max() <= 1e-6 * scale


def test_constrained_acceleration_is_the_free_block_solve() -> None:
    """q̈_S = 0 and M_FF q̈_F = r_F, against numpy's general solver on the free block, for every mask of a
    random 5-joint mass matrix (including none and all stuck); a matrix that is not positive definite raises."""
    import itertools

    from armctl.sim.stick_slip import NotPositiveDefinite, constrained_accel

    rng = np.random.default_rng(7)
    a = rng.standard_normal((5, 5))
    mass, rhs = a @ a.T + 0.5 * np.eye(5), rng.standard_normal(5)
    for bits in itertools.product([False, True], repeat=5):
        stuck = np.array(bits)
        got = constrained_accel(mass, rhs, stuck if stuck.any() else None)
        free = ~stuck
        want = np.zeros(5)
        if free.any():
            want[free] = np.linalg.solve(mass[np.ix_(free, free)], rhs[free])
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-13)
    with pytest.raises(NotPositiveDefinite):
        constrained_accel(-mass, rhs, np.array([True, False, False, False, False]))


def test_a_joint_released_brings_its_kinetic_friction_into_the_others_holding_torque() -> None:
    # two joints at rest, M = [[3, 1.2], [1.2, 1]], r = [400, 60] N·m; joint 0: F_c = 200, F_s = 250; joint 1:
    # F_c = 40, F_s = 50. Both held: λ = r, and joint 0 is beyond its band (400/250 > 60/50). Released (+q), it
    # slides against F_c: q̈₀ = (400 − 200)/3 and joint 1 must hold λ₁ = 60 − 1.2 q̈₀ = −20 N·m, inside ±50: it
    # stays stuck. Without the kinetic friction in r, λ₁ = 60 − 1.2·400/3 = −100 would release it too
    from armctl.sim.friction import StickSlip
    from armctl.sim.stick_slip import solve_sticking

    model = armctl.models.planar_2r().with_friction(coulomb=[200.0, 40.0], static=[250.0, 50.0])
    mass = np.array([[3.0, 1.2], [1.2, 1.0]])
    stuck, direction, lam = solve_sticking(
        StickSlip(model), mass, np.array([400.0, 60.0]), np.array([True, True]), np.zeros(2)
    )
    assert stuck.tolist() == [False, True] and direction.tolist() == [1.0, 0.0]
    np.testing.assert_allclose(lam, [0.0, 60.0 - 1.2 * (400.0 - 200.0) / 3.0], rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize(("push", "moves"), [(4.0, False), (10.0, True)])
def test_an_external_push_breaks_a_stuck_joint_loose_beyond_its_friction(push: float, moves: bool) -> None:
    """A 2 kg slider at rest with 5 N of Coulomb friction and no torque, pushed along its axis by an external
    wrench of F (h_d = −F, what the arm exerts): below 5 N it stays exactly still; above, it slides at once with
    q = (F − 5 N) t² / (2 m)."""
    mass, coulomb = 2.0, 5.0
    model = slider(mass).with_friction(coulomb=coulomb)
    res = simulate(
        model,
        zero_torque,
        armctl.Reference.hold([0.0]),
        0.5,
        disturbance=lambda t: np.array([-push, 0.0, 0.0, 0.0, 0.0, 0.0]),
    )
    if moves:
        np.testing.assert_allclose(res.q[:, 0], (push - coulomb) / (2.0 * mass) * res.t**2, rtol=1e-9, atol=1e-12)
        assert not res.stuck[1:].any()
    else:
        assert (res.q == 0.0).all() and (res.qd == 0.0).all() and res.stuck.all()
        assert res.tau_friction[:, 0] == pytest.approx(push, rel=1e-12)  # the holding torque balances the push


def test_two_joints_coasting_to_a_stop_in_the_same_step_stop_where_coulomb_friction_stops_them() -> None:
    """Two decoupled prismatic joints (x carrying y: M = diag(m₁ + m₂, m₂)) coasting under Coulomb friction F_i
    alone decelerate at F_i / M_ii and stop for good at t_i = M_ii v_i / F_i, where q_i = M_ii v_i² / (2 F_i)
    (closed form). Both stops fall within the same 1 ms step, so both events must be located inside it."""
    from armctl.model.parts import Frame, Joint, Link

    m1, m2 = 1.0, 2.0
    joints = tuple(
        Joint(name, "prismatic", axis, np.eye(4), Link(mass, (0, 0, 0), (1e-3, 1e-3, 1e-3)))
        for name, axis, mass in (("x", (1.0, 0.0, 0.0), m1), ("y", (0.0, 1.0, 0.0), m2))
    )
    model = armctl.RobotModel(joints, name="xy", frames=(Frame("tool", 2, np.eye(4)),), tool_frame="tool")
    inertia, coulomb, v0 = np.array([m1 + m2, m2]), np.array([4.5, 1.5]), np.array([1.0, 0.5002])
    stop = inertia * v0 / coulomb
    assert 0.666 < stop.min() < stop.max() < 0.667  # the same step
    res = simulate(model.with_friction(coulomb=coulomb), zero_torque, armctl.Reference.hold([0.0, 0.0]), 1.0, qd0=v0)
    for i in range(2):
        t = np.minimum(res.t, stop[i])
        np.testing.assert_allclose(res.q[:, i], v0[i] * t - 0.5 * coulomb[i] / inertia[i] * t**2, rtol=1e-9, atol=1e-12)
    assert (res.qd[res.t > stop.max()] == 0.0).all() and res.stuck[res.t > stop.max()].all()
