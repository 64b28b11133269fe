"""What is recorded of the contacts at a sample — the points' forces on the environment and positions, the external
torques τ_ext, the wrench about the tool frame's origin and the force sensors' readings — by the generated engine (its
C period, the kernel ``pk_sample``) and by the Python engine (:meth:`Recorder.record_external
<armctl.sim.recorder.Recorder.record_external>`, NumPy and Pinocchio), at the same states.

References: the Python recorder, written independently of the generated code; the classification of the states
(sliding, sticking, out of contact) from Pinocchio's frame poses and Jacobians computed here.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import armctl
from armctl.sim import ContactPoint, ForceSensor, HuntCrossley, KelvinVoigt, Plane, simulate
from armctl.sim.compiled import choose_step
from armctl.sim.engine import EngineRun
from armctl.sim.generated_engine import GeneratedEngine
from armctl.sim.plant import Plant
from armctl.sim.recorder import Recorder
from armctl.sim.saturation import Saturation

pytestmark = pytest.mark.one_step  # each test names the engines it compares

PANDA_Q0 = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])  # hand pointing down
#: the recorded quantities compared, by the Recorder's name
QUANTITIES = ("contact_force", "contact_position", "tau_ext", "wrench", "sensor")


def _scene(dyn: armctl.Dynamics) -> tuple[list[Plane], list[ForceSensor]]:
    """A Kelvin–Voigt floor under three points of the hand (two off its centre), with sliding friction, and a
    Hunt–Crossley wall beside the flange with friction of its own; sensors at the hand (both axes) and at the base."""
    z_floor = dyn.frame_pose(PANDA_Q0)[2, 3] - 0.004
    x_wall = dyn.frame_pose(PANDA_Q0, "panda_link7")[0, 3] + 0.003
    hand = [ContactPoint("panda_hand_tcp", o) for o in ([0.0, 0.03, 0.0], [0.0, -0.03, 0.0], [0.02, 0.0, 0.0])]
    floor = Plane(KelvinVoigt(2e4, 300.0), point=(0.0, 0.0, z_floor), friction=0.5, slip_velocity=0.02, points=hand)
    wall = Plane(
        HuntCrossley(3e5, 0.4, 1.5),
        normal=(-1.0, 0.0, 0.0),
        point=(x_wall, 0.0, 0.0),
        friction=0.3,
        slip_velocity=0.02,
        points=[ContactPoint("panda_link7")],
    )
    sensors = [ForceSensor("panda_hand", world_axes=True), ForceSensor("panda_hand"), ForceSensor("panda_joint1")]
    return [floor, wall], sensors


def _states(n: int, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """States about PANDA_Q0: small position offsets (the points in and out of the floor and wall), velocities
    from nearly still (below the slip velocity) to fast (sliding)."""
    rng = np.random.default_rng(7)
    q = PANDA_Q0 + rng.normal(0.0, 0.01, (samples, n))
    scale = np.where(np.arange(samples) % 2 == 0, 2e-3, 0.3)[:, None]
    return q, rng.normal(0.0, 1.0, (samples, n)) * scale


def _records(dyn: armctl.Dynamics, q: np.ndarray, qd: np.ndarray) -> tuple[Recorder, Recorder, Plant]:
    """(the Python record, the generated one) of the states (q, q̇)."""
    environments, sensors = _scene(dyn)
    plant = Plant(dyn, None, environments)
    samples, n = q.shape
    records = []
    for _ in range(2):
        rec = Recorder(n, samples, 1e-3, plant.environments, tuple(sensors), measured=False)
        rec.q[:], rec.qd[:] = q, qd
        records.append(rec)
    python, generated = records
    for k in range(samples):
        python.record_external(k, plant, k * 1e-3, q[k], qd[k])
    choice = choose_step(dyn, "rk4", plant, True)
    assert choice.compiled
    engine = GeneratedEngine(choice.plant)
    sat = Saturation(generated.tau_applied, np.full(n, np.inf), False)
    engine.bind(EngineRun(generated, sat, 1, 1e-3, False))  # records sample 0
    for k in range(samples):
        if k:
            choice.plant.record_sample(k)
        engine.observe(k, k * 1e-3)  # the sensors, from the recorded forces
    return python, generated, plant


def test_the_engines_record_the_same_contacts_at_the_same_states() -> None:
    """Every recorded contact quantity, for several points on two planes (both normal laws), sliding, sticking and
    out of contact: the generated record equals the Python record within 1e-9 (relative to the quantity's scale)."""
    dyn = armctl.Dynamics(armctl.models.panda())
    q, qd = _states(dyn.n, 400)
    python, generated, plant = _records(dyn, q, qd)
    for name in QUANTITIES:
        a, b = getattr(generated, name), getattr(python, name)
        scale = max(float(np.abs(b).max()), 1.0)
        assert np.abs(a - b).max() <= 1e-9 * scale, name
    # the states cover every case (classified here from Pinocchio's kinematics, independently of both records)
    seen = {"sliding": 0, "sticking": 0, "free": 0}
    for env, kin in zip(plant.environments, plant.kinematics, strict=True):
        plane = env
        assert isinstance(plane, Plane)
        for p in kin.points:
            for k in range(len(q)):
                pose = dyn.frame_pose(q[k], p.frame)
                pos = pose[:3, :3] @ p.offset + pose[:3, 3]
                jac = dyn.jacobian(q[k], p.frame)
                r = pose[:3, :3] @ p.offset
                vel = jac[:3] @ qd[k] + np.cross(jac[3:] @ qd[k], r)
                vt = vel - (plane.normal @ vel) * plane.normal
                if plane.depth(pos) <= 0.0:
                    seen["free"] += 1
                elif math.hypot(*vt) > plane.slip_velocity:
                    seen["sliding"] += 1
                else:
                    seen["sticking"] += 1
    assert min(seen.values()) >= 20, seen
    pressing = np.abs(python.contact_force).max(axis=2) > 1e-3
    assert pressing.any(axis=0).all()  # every point touches at some sample
    # the base sensor reads every point's force (in its own axes: compared by magnitude)
    np.testing.assert_allclose(
        np.linalg.norm(python.sensor[:, 2, :3], axis=1), np.linalg.norm(python.wrench[:, :3], axis=1), atol=1e-9
    )


@pytest.mark.parametrize("integrator", ["rk4", "implicit-euler"])
def test_the_engines_record_the_same_contacts_over_a_run(integrator: str) -> None:
    """A run of the Panda pushed down and sideways onto the scene's floor: the two engines' runs agree,
    and so do their records of the contacts (the run's rounding differences, times the contacts' stiffness)."""
    dyn = armctl.Dynamics(armctl.models.panda())
    environments, sensors = _scene(dyn)
    g0 = dyn.gravity_torque(PANDA_Q0)
    push = dyn.jacobian(PANDA_Q0)[:3].T @ np.array([3.0, 1.0, -20.0])

    def controller(t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        return g0 + push * min(t / 0.1, 1.0) + 30.0 * (ref.q - q) - 3.0 * qd

    runs = [
        simulate(
            dyn,
            controller,
            armctl.Reference.hold(PANDA_Q0),
            0.3,
            integrator=integrator,
            compile=c,
            forces=armctl.sim.Forces(environment=environments),
            sensing=armctl.sim.Sensing(sensors=sensors),
        )
        for c in (False, True)
    ]
    python, generated = runs
    assert (python.info["compiled"], generated.info["compiled"]) == (False, True)
    assert np.abs(generated.q - python.q).max() <= 1e-9
    assert (np.abs(python.contact_force_on_environment).max(axis=2) > 1.0).any(axis=0).sum() >= 2  # several points
    for name in ("contact_force_on_environment", "contact_position", "tau_ext", "wrench", "sensor"):
        a, b = getattr(generated, name), getattr(python, name)
        assert np.abs(a - b).max() <= 1e-6 * max(float(np.abs(b).max()), 1.0), name
