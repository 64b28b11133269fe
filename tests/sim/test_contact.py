"""Contact: static force against Jᵀh_e = τ − g, stiffness over four decades with the implicit scheme, a
Hunt–Crossley bounce against an independent ODE solution, Coulomb friction along a wall, several contact
points with a force sensor, and an external-wrench disturbance."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import armctl
from armctl.errors import SimulationWarning
from armctl.sim import ContactPoint, Forces, ForceSensor, HuntCrossley, KelvinVoigt, Plane, Sensing, simulate
from tests.sim.helpers import ForceControl, PDGravity, slider, zero_torque

PANDA_Q0 = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])  # hand pointing down


def _static_identity(dyn: armctl.Dynamics, res: armctl.sim.SimResult, point: int = 0) -> float:
    """Relative residual of J_pᵀh = τ − g(q) at the final sample (h: the logged contact force)."""
    q = res.q[-1]
    lhs = dyn.jacobian(q)[:3].T @ res.contact_force_on_environment[-1, point]
    rhs = res.tau_applied[-1] - dyn.gravity_torque(q)
    return float(np.linalg.norm(lhs - rhs) / np.linalg.norm(rhs))


# rk4 on the planes' regularised stiction: the warning is tested in its own test
@pytest.mark.filterwarnings("ignore:below their slip velocity:armctl.errors.SimulationWarning")
def test_planar_arm_pressing_a_wall_settles_at_the_commanded_force() -> None:
    """τ = g + J_linᵀf − K_d q̇ on a non-redundant arm: at rest the wall pushes back with exactly f."""
    model = armctl.models.planar_2r()
    dyn = armctl.Dynamics(model)
    q0 = np.array([0.6, -1.2])  # tool at x = 1.651 m, z = 0
    force = np.array([300.0, 0.0, 0.0])
    wall = Plane(KelvinVoigt(2e5, 5e3), normal=(-1.0, 0.0, 0.0), point=(1.70, 0.0, 0.0), friction=0.3)
    res = simulate(
        dyn, ForceControl(dyn, force, kd=400.0), armctl.Reference.hold(q0), 3.0, forces=Forces(environment=wall)
    )
    assert not res.diverged
    assert np.abs(res.qd[-1]).max() < 1e-4
    np.testing.assert_allclose(res.contact_force_on_environment[-1, 0], force, rtol=0.01, atol=0.01 * force[0])
    # the same force from the static balance Jᵀh = τ − g, solved by least squares
    q = res.q[-1]
    predicted = np.linalg.lstsq(dyn.jacobian(q)[:3].T, res.tau_applied[-1] - dyn.gravity_torque(q), rcond=None)[0]
    np.testing.assert_allclose(res.contact_force_on_environment[-1, 0], predicted, rtol=0.01, atol=0.01 * force[0])
    # penetration of a Kelvin–Voigt wall at rest: f / k
    depth = dyn.frame_pose(q)[0, 3] - 1.70
    assert depth == pytest.approx(force[0] / 2e5, rel=0.01)
    np.testing.assert_allclose(res.wrench[-1, :3], force, rtol=0.01, atol=0.01 * force[0])


@pytest.mark.parametrize("stiffness", [1e4, 1e5, 1e6, 1e7, 1e8])
def test_implicit_scheme_is_stable_over_four_decades_of_contact_stiffness(stiffness: float) -> None:
    """The Panda pressing a floor with 20 N under a posture spring, at 1 ms steps: settled, and the contact
    force balances τ − g through J_pᵀ to 1 %."""
    dyn = armctl.Dynamics(armctl.models.panda())
    z_floor = dyn.frame_pose(PANDA_Q0)[2, 3] - 0.01
    floor = Plane(KelvinVoigt(stiffness, 2 * 0.7 * math.sqrt(3.0 * stiffness)), point=(0.0, 0.0, z_floor))
    ctrl = ForceControl(dyn, [0.0, 0.0, -20.0], kd=5.0, kp=20.0)
    res = simulate(
        dyn, ctrl, armctl.Reference.hold(PANDA_Q0), 1.5, integrator="implicit-euler", forces=Forces(environment=floor)
    )
    assert not res.diverged
    assert np.abs(res.qd[-1]).max() < 1e-3
    assert res.info["implicit_unconverged"] == 0
    fz = res.contact_force_on_robot[-1, 0, 2]
    assert 15.0 < fz < 25.0
    assert _static_identity(dyn, res) <= 0.01
    depth = z_floor - dyn.frame_pose(res.q[-1])[2, 3]
    assert depth == pytest.approx(fz / stiffness, rel=0.01)


@pytest.mark.steps_may_differ("a contact unstable for RK4, on purpose")
# the unstable contact also shows in the energy balance
@pytest.mark.filterwarnings("ignore:the arm gained:armctl.errors.SimulationWarning")
# its run goes beyond a velocity limit on the way, as expected
@pytest.mark.filterwarnings("ignore:the run went beyond the plant's limits:armctl.errors.SimulationWarning")
def test_rk4_fails_on_the_stiffest_contact_where_the_implicit_scheme_holds() -> None:
    """At k = 10⁸ N/m, ω·Δt is beyond RK4's stability limit: the impact throws the hand off the floor — and the
    simulator says so before the run (a SimulationWarning, ``info["unstable_contacts"]``)."""
    dyn = armctl.Dynamics(armctl.models.panda())
    z_floor = dyn.frame_pose(PANDA_Q0)[2, 3] - 0.01
    floor = Plane(KelvinVoigt(1e8, 2 * 0.7 * math.sqrt(3e8)), point=(0.0, 0.0, z_floor))
    with pytest.warns(SimulationWarning, match="'rk4' is unstable on this contact"):
        res = simulate(
            dyn,
            ForceControl(dyn, [0.0, 0.0, -20.0], kd=5.0, kp=20.0),
            armctl.Reference.hold(PANDA_Q0),
            1.5,
            integrator="rk4",
            forces=Forces(environment=floor),
        )
    assert res.info["unstable_contacts"]
    settled = not res.diverged and abs(res.contact_force_on_robot[-1, 0, 2] - 19.6) < 1.0
    assert not settled
    assert res.diverged or np.abs(res.qd).max() > 1.0


def test_hunt_crossley_bounce_matches_an_independent_ode_solution() -> None:
    """A 1 kg body dropped 5 cm on a Hunt–Crossley floor, against SciPy's DOP853 on the same law."""
    mass, g, h0, k = 1.0, 9.81, 0.05, 1e5
    law = HuntCrossley.from_restitution(k, restitution=0.9, impact_velocity=math.sqrt(2 * g * h0))
    d = law.dissipation
    assert d == pytest.approx(1.5 * 0.1 / math.sqrt(2 * g * h0))
    model = slider(mass, vertical=True)
    res = simulate(
        model, zero_torque, armctl.Reference.hold([h0]), 0.25, dt=2e-5, forces=Forces(environment=Plane(law))
    )

    def rhs(t: float, x: np.ndarray) -> list[float]:
        z, v = x
        f = k * (-z) * (1.0 - d * v) if z < 0 else 0.0  # δ = −z, δ̇ = −v
        return [v, -g + max(f, 0.0) / mass]

    ref = solve_ivp(
        rhs, (0.0, 0.25), [h0, 0.0], method="DOP853", rtol=1e-11, atol=1e-13, max_step=1e-4, dense_output=True
    )
    np.testing.assert_allclose(res.q[:, 0], ref.sol(res.t)[0], atol=1e-7)
    # Hunt–Crossley's approximation of the restitution: apex after the bounce ≈ e² h0
    after = res.t > 0.15
    apex = res.q[after, 0].max()
    assert math.sqrt(apex / h0) == pytest.approx(0.9, abs=0.03)


# rk4 on the planes' regularised stiction: the warning is tested in its own test
@pytest.mark.filterwarnings("ignore:below their slip velocity:armctl.errors.SimulationWarning")
def test_coulomb_friction_along_the_wall_is_mu_times_the_normal_force() -> None:
    """planar_2r pushed down onto a floor and along it: while sliding faster than the slip velocity the
    tangential force is μ f_n, along the motion (the arm drags the floor with it)."""
    model = armctl.models.planar_2r()
    dyn = armctl.Dynamics(model)
    q0 = np.array([0.5, -1.4])  # tool at x = 1.500, z = −0.304
    mu = 0.5
    floor = Plane(
        KelvinVoigt(1e6, 2e4), normal=(0.0, 0.0, 1.0), point=(0.0, 0.0, -0.31), friction=mu, slip_velocity=1e-3
    )
    res = simulate(
        dyn,
        ForceControl(dyn, [400.0, 0.0, -500.0], kd=100.0),
        armctl.Reference.hold(q0),
        1.0,
        forces=Forces(environment=floor),
    )
    h = res.contact_force_on_environment[:, 0]
    v = np.array([dyn.jacobian(q)[:3] @ qd for q, qd in zip(res.q, res.qd, strict=True)])
    sliding = (h[:, 2] < -1.0) & (np.abs(v[:, 0]) > 1e-3)
    assert sliding.sum() > 100
    np.testing.assert_allclose(np.abs(h[sliding, 0]), mu * np.abs(h[sliding, 2]), rtol=1e-9)
    assert (np.sign(h[sliding, 0]) == np.sign(v[sliding, 0])).all()


def test_several_contact_points_and_force_sensors() -> None:
    """Two points under the Panda's hand on a floor: the sensors and the logged wrench are the sums of the
    point forces, with moments about their origins computed here from the frames' poses."""
    dyn = armctl.Dynamics(armctl.models.panda())
    offsets = [np.array([0.0, 0.03, 0.0]), np.array([0.0, -0.03, 0.0])]
    points = [ContactPoint("panda_hand_tcp", o) for o in offsets]
    z_floor = dyn.frame_pose(PANDA_Q0)[2, 3] - 0.01
    floor = Plane(KelvinVoigt(1e5, 2e3), point=(0.0, 0.0, z_floor), points=points)
    sensors = [ForceSensor("panda_hand", world_axes=True), ForceSensor("panda_hand"), ForceSensor("panda_joint1")]
    res = simulate(
        dyn,
        ForceControl(dyn, [0.0, 0.0, -30.0], kd=5.0, kp=20.0),
        armctl.Reference.hold(PANDA_Q0),
        1.0,
        integrator="implicit-euler",
        forces=Forces(environment=floor),
        sensing=Sensing(sensors=sensors),
    )
    assert res.contact_force_on_environment.shape == (1001, 2, 3) and res.sensor.shape == (1001, 3, 6)
    q = res.q[-1]
    tcp, hand, tool = (dyn.frame_pose(q, f) for f in ("panda_hand_tcp", "panda_hand", None))
    pos = [tcp[:3, :3] @ o + tcp[:3, 3] for o in offsets]
    h = res.contact_force_on_environment[-1]
    assert (h[:, 2] < -5.0).all()  # both points press
    force = h.sum(axis=0)
    moment = sum(np.cross(p - hand[:3, 3], f) for p, f in zip(pos, h, strict=True))
    np.testing.assert_allclose(res.sensor[-1, 0], np.concatenate([force, moment]), atol=1e-9)
    np.testing.assert_allclose(
        res.sensor[-1, 1], np.concatenate([hand[:3, :3].T @ force, hand[:3, :3].T @ moment]), atol=1e-9
    )
    np.testing.assert_allclose(res.sensor[-1, 2, :3], force, atol=1e-9)  # a base sensor sees every contact
    tool_moment = sum(np.cross(p - tool[:3, 3], f) for p, f in zip(pos, h, strict=True))
    np.testing.assert_allclose(res.wrench[-1], np.concatenate([force, tool_moment]), atol=1e-9)
    # static balance with both points: Σ J_pᵀ h_p = τ − g
    jac, R = dyn.jacobian(q, "panda_hand_tcp"), tcp[:3, :3]
    lhs = sum((jac[:3] - _skew(R @ o) @ jac[3:]).T @ f for o, f in zip(offsets, h, strict=True))
    rhs = res.tau_applied[-1] - dyn.gravity_torque(q)
    assert np.linalg.norm(lhs - rhs) <= 0.01 * np.linalg.norm(rhs)


def _skew(r: np.ndarray) -> np.ndarray:
    return np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])


@pytest.mark.parametrize("integrator", ["rk4", "implicit-euler"])
def test_constant_disturbance_wrench_is_applied_and_logged(integrator: str) -> None:
    """A PD-held arm under a constant wrench h_d at the tool settles where τ − g = Jᵀh_d (the implicit scheme
    takes the disturbance through its own Newton residual)."""
    model = armctl.models.planar_2r()
    dyn = armctl.Dynamics(model)
    hd = np.array([400.0, 0.0, -300.0, 0.0, 150.0, 0.0])
    res = simulate(
        dyn,
        PDGravity(dyn, kp=2e4, kd=3e3),
        armctl.Reference.hold([0.3, 0.5]),
        3.0,
        integrator=integrator,
        forces=Forces(disturbance=lambda t: hd),
    )
    q = res.q[-1]
    jac = dyn.jacobian(q)
    np.testing.assert_allclose(res.wrench, np.tile(hd, (len(res.t), 1)))
    np.testing.assert_allclose(res.tau_ext[-1], jac.T @ hd, rtol=1e-12)
    rhs = res.tau_applied[-1] - dyn.gravity_torque(q)
    np.testing.assert_allclose(jac.T @ hd, rhs, rtol=0.01)
    assert np.abs(q - [0.3, 0.5]).max() > 1e-3  # it was pushed off its set-point
