"""Energy: conservation in free motion, and the energy balance E(t) − E(0) = ∫q̇ᵀ(τ − τ_f − Jᵀh_e)dt with
friction and contact, closing to the integrator's order.

Energies are functions of the recorded state (the free-motion tests evaluate them here with the Dynamics' own
kinetic_energy and potential_energy, and check the result's energy against them), not something the
integrator reports; the work of the held actuator torque is τᵀΔq exactly."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import armctl
from armctl.errors import SimulationWarning
from armctl.sim import Forces, HuntCrossley, KelvinVoigt, Plane, simulate
from tests.sim.helpers import PDGravity, zero_torque

# free motion from rest, released under gravity (the panda starts near its hanging pose, so that it swings
# rather than tumbles: a tumbling wrist spins at > 100 rad/s)
FREE = {
    "planar_2r": ([0.5, -0.3], [0.0, 0.0]),
    "panda": ([0.0, np.pi - 0.3, 0.0, -0.3, 0.0, 0.3, 0.0], [0.4, 0.0, -0.3, 0.2, 0.5, 0.0, -0.6]),
}


def _free_run(name: str, integrator: str, duration: float = 10.0) -> tuple[armctl.sim.SimResult, float]:
    model = getattr(armctl.models, name)()
    q0, qd0 = FREE[name]
    outside = (np.asarray(q0) < model.lower) | (np.asarray(q0) > model.upper)  # the Panda hangs past joint 2's
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = simulate(
            model, zero_torque, armctl.Reference.hold(q0), duration, qd0=qd0, integrator=integrator, saturate=False
        )
    said = [str(w.message) for w in caught if issubclass(w.category, SimulationWarning)]
    # a start outside the position limits is said, once; inside, nothing. A free swing may also overrun a limit
    # (the Panda's, which it is said after the run): no other warning
    assert all(s.startswith(("the run starts outside", "the run went beyond")) for s in said)
    said = [s for s in said if s.startswith("the run starts outside")]
    assert len(said) == outside.any()
    if outside.any():
        assert said[0].startswith(
            "the run starts outside the model's position limits: joint 1 ('panda_joint2') "
            "at 2.842 outside [-1.763, 1.763]"
        )
    dyn = armctl.Dynamics(model)
    kinetic = np.array([dyn.kinetic_energy(q, v) for q, v in zip(res.q[::5], res.qd[::5], strict=True)])
    energy = kinetic + [dyn.potential_energy(q) for q in res.q[::5]]
    np.testing.assert_allclose(res.energy[::5], energy, rtol=0, atol=1e-9 * np.abs(energy).max())
    return res, float(kinetic.max())


@pytest.mark.steps_may_differ("a 10 s free swing of the Panda tumbles: rounding differences grow")
@pytest.mark.parametrize("name", ["planar_2r", "panda"])
def test_rk4_conserves_energy_in_free_motion(name: str) -> None:
    res, t_max = _free_run(name, "rk4")
    assert not res.diverged
    assert res.work.max() == 0.0  # no torque, no friction, no contact
    drift = np.abs(res.energy - res.energy[0]).max()
    # relative to the energy that moves between kinetic and potential (max T), stricter than |E|
    assert drift <= 1e-6 * t_max, (drift, t_max)
    assert t_max > 1.0  # the arm did move


@pytest.mark.steps_may_differ("a 10 s free swing of the Panda tumbles: rounding differences grow")
@pytest.mark.parametrize("name", ["planar_2r", "panda"])
def test_semi_implicit_euler_energy_stays_bounded(name: str) -> None:
    res, t_max = _free_run(name, "semi-implicit-euler")
    err = (res.energy - res.energy[0]) / t_max
    assert np.abs(err).max() < 0.05
    # no trend: the error fluctuates about zero (its size follows the speed of the motion); a least-squares
    # line through it moves by a small fraction of the fluctuation over the whole run, and the mean error
    # of the second half is no further from 0 than a fraction of the fluctuation
    slope = np.polyfit(res.t, err, 1)[0]
    assert abs(slope) * res.t[-1] <= 0.2 * np.ptp(err), (slope, np.ptp(err))
    half = len(err) // 2
    assert abs(err[half:].mean()) <= 0.2 * np.ptp(err), (err[half:].mean(), np.ptp(err))


def test_velocity_euler_drifts_where_symplectic_does_not() -> None:
    """The cheap velocity-form Euler gains energy on planar_2r (M depends on q): why semi-implicit-euler is
    the symplectic momentum form."""
    res, t_max = _free_run("planar_2r", "euler")
    err = (res.energy - res.energy[0]) / t_max
    slope = np.polyfit(res.t, err, 1)[0]
    assert slope * res.t[-1] > 0.5 * np.ptp(err), (slope, np.ptp(err))


def _balance_scene(integrator: str, dt: float, friction: str, mu: float = 0.0) -> armctl.sim.SimResult:
    """planar_2r under a PD towards a set-point behind a Hunt–Crossley wall, with viscous + Coulomb (+
    Stribeck) joint friction and tangential friction μ at the wall: every term of the balance is at work."""
    model = armctl.models.planar_2r().with_friction(
        viscous=[30.0, 20.0], coulomb=[40.0, 25.0], static=[60.0, 35.0], stribeck_velocity=0.05
    )
    dyn = armctl.Dynamics(model)
    ctrl = PDGravity(armctl.Dynamics(model.reduced(friction=False)), kp=3000.0, kd=300.0)
    wall = Plane(HuntCrossley(2e5, 0.5), normal=(-1.0, 0.0, 0.0), point=(1.55, 0.0, 0.0), friction=mu)
    return simulate(
        dyn,
        ctrl,
        armctl.Reference.hold([0.4, -0.2]),
        1.0,
        q0=[1.0, -0.5],
        dt=dt,
        integrator=integrator,
        forces=Forces(friction=friction, environment=wall),
    )


def test_energy_balance_closes_to_fourth_order_with_rk4() -> None:
    """Smooth friction and Hunt–Crossley contact (continuous force): halving the step divides the balance
    residual by ~2⁴."""
    errors = []
    for dt in (1e-3, 5e-4):
        res = _balance_scene("rk4", dt, "smooth")
        assert not res.diverged
        assert res.contact_force_on_environment[:, 0, 0].max() > 1000.0  # the wall was hit
        assert res.work_friction[-1] < -10.0 and res.work_external[-1] < -10.0
        errors.append(np.abs(res.energy_balance()).max())
    assert errors[0] <= 1e-6 * np.abs(res.work_friction).max()
    assert errors[0] / errors[1] > 10.0, errors


@pytest.mark.steps_may_differ(
    "the wall's friction below its slip velocity is stiff for RK4 at 1 ms: rounding differences grow"
)
# rk4 on the planes' regularised stiction: the warning is tested in its own test
@pytest.mark.filterwarnings("ignore:below their slip velocity:armctl.errors.SimulationWarning")
def test_energy_balance_with_tangential_contact_friction() -> None:
    """Coulomb friction along the wall (regularised: stiff below its slip velocity) still closes."""
    errors = []
    for dt in (1e-3, 5e-4):
        res = _balance_scene("rk4", dt, "smooth", mu=0.4)
        assert np.abs(res.contact_force_on_environment[:, 0, 2]).max() > 500.0  # tangential force along z
        errors.append(np.abs(res.energy_balance()).max())
    assert errors[0] <= 1e-3 * abs(res.work_external[-1])
    assert errors[0] / errors[1] > 4.0, errors


@pytest.mark.parametrize("integrator", ["semi-implicit-euler", "implicit-euler"])
def test_energy_balance_closes_to_first_order(integrator: str) -> None:
    errors = [np.abs(_balance_scene(integrator, dt, "smooth").energy_balance()).max() for dt in (1e-3, 5e-4)]
    assert 1.6 < errors[0] / errors[1] < 2.5, errors


def test_energy_balance_with_stick_slip_events() -> None:
    """With stick–slip the dynamics switch at every stop; events are located, so the balance still closes
    far below the energies involved, and shrinks with the step."""
    errors = []
    for dt in (1e-3, 5e-4):
        res = _balance_scene("rk4", dt, "stick-slip")
        assert res.info["stick_events"] > 0
        errors.append(np.abs(res.energy_balance()).max())
    scale = np.abs(res.work_actuator).max()
    assert errors[0] <= 1e-5 * scale, (errors, scale)
    assert errors[1] < errors[0]


def test_kelvin_voigt_contact_work_is_external_work() -> None:
    """A pendulum falling onto a damped Kelvin–Voigt floor: all the energy lost is contact work."""
    model = armctl.models.pendulum().reduced(friction=False)
    floor = Plane(KelvinVoigt(2e4, 50.0), normal=(-1.0, 0.0, 0.0), point=(0.3, 0.0, 0.0))
    res = simulate(model, zero_torque, armctl.Reference.hold([0.0]), 2.0, q0=[-1.2], dt=2e-4)
    res_c = simulate(
        model, zero_torque, armctl.Reference.hold([0.0]), 2.0, q0=[-1.2], dt=2e-4, forces=Forces(environment=floor)
    )
    assert abs(res.energy[-1] - res.energy[0]) < 1e-9
    lost = res_c.energy[-1] - res_c.energy[0]
    assert lost < -0.1
    assert res_c.work_external[-1] == pytest.approx(lost, rel=1e-4)
