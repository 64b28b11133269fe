"""``simulate(..., compile=True)`` on a plant without friction, contact or disturbance: the integration step as C
code generated from the recursive algorithms of :mod:`armctl.dynamics.recursive`; and what has no generated step.

References: the textbook RK4 of :func:`armctl.sim.integrators.rk4` (and the Euler formulas) on Pinocchio's q̈
for the compiled step; the uncompiled simulator for whole runs.
"""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.errors import ArmctlError, InvalidParameterError
from armctl.references import Reference
from armctl.sim import StopRules
from armctl.sim.compiled import compiled_step
from armctl.sim.contact import ContactPoint, Environment
from armctl.sim.friction import FrictionModel
from armctl.sim.integrators import rk4, semi_implicit_euler
from armctl.sim.options import regroup
from tests.dynamics.helpers import skewed_rpr
from tests.sim.helpers import ComputedTorque

pytestmark = pytest.mark.one_step  # each test names the step it runs


def _textbook(
    dyn: armctl.Dynamics, scheme: str, q: np.ndarray, v: np.ndarray, tau: np.ndarray, h: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    scheme_step = rk4 if scheme == "rk4" else semi_implicit_euler
    return scheme_step(lambda t, q_, v_, tau_: dyn.forward_dynamics(q_, v_, tau_), 0.0, q.copy(), v.copy(), tau, h)


@pytest.mark.parametrize("scheme", ["rk4", "euler"])
def test_compiled_step_is_the_scheme_on_pinocchios_accelerations(scheme: str, tmp_path) -> None:
    model = skewed_rpr()
    dyn = armctl.Dynamics(model)
    step = compiled_step(model, scheme, cache_dir=tmp_path)
    rng = np.random.default_rng(4)
    q, v = rng.uniform(-1.0, 1.0, (2, model.n))
    ref_q, ref_v = q.copy(), v.copy()
    kept = []
    for k in range(6):
        tau = rng.uniform(-5.0, 5.0, model.n)
        h = 1e-3 if k != 3 else 5e-4  # a step of another size in between
        q, v, a = step(q, v, tau, h)
        ref_q, ref_v, ref_a = _textbook(dyn, scheme, ref_q, ref_v, tau, h)
        np.testing.assert_allclose(q, ref_q, rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(v, ref_v, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(a, ref_a, rtol=1e-10, atol=1e-10)
        kept.append((q, q.copy()))
    assert np.array_equal(kept[-1][0], kept[-1][1]) and np.array_equal(kept[-2][0], kept[-2][1])
    # states that are not the last result, or alias the step's own arrays, are read as values; the caller's
    # arrays are not written
    q1, v1 = q, v
    q0, v0 = rng.uniform(-1.0, 1.0, (2, model.n))
    for qi, vi in ((q0, v0), (v1, q1), (q1, q1)):
        before = (qi.copy(), vi.copy())
        want = _textbook(dyn, scheme, before[0], before[1], np.zeros(model.n), 1e-3)
        got = step(qi, vi, np.zeros(model.n), 1e-3)
        np.testing.assert_allclose(got[0], want[0], rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(got[1], want[1], rtol=1e-12, atol=1e-12)
        if qi is q0:
            assert np.array_equal(q0, before[0]) and np.array_equal(v0, before[1])


def test_compiled_library_is_cached_per_model(tmp_path) -> None:
    """One library per model and scheme, loaded (not rebuilt) the second time; a payload changes the numbers
    built into the code, so it gets its own library, with its own dynamics."""
    model = armctl.models.planar_2r().reduced(friction=False)
    compiled_step(model, "euler", cache_dir=tmp_path)
    libs = list(tmp_path.rglob("*.so"))
    assert len(libs) == 1
    stamp = libs[0].stat().st_mtime_ns
    compiled_step(model, "euler", cache_dir=tmp_path)
    assert list(tmp_path.rglob("*.so")) == libs and libs[0].stat().st_mtime_ns == stamp
    heavy = model.with_payload(2.0, (0.0, 0.0, 0.0), np.zeros((3, 3)))
    step = compiled_step(heavy, "euler", cache_dir=tmp_path)
    assert len(list(tmp_path.rglob("*.so"))) == 2
    q, v, tau = np.array([0.3, 0.5]), np.array([0.1, -0.2]), np.array([1.0, 2.0])
    _, _, a = step(q, v, tau, 1e-3)
    np.testing.assert_allclose(a, armctl.Dynamics(heavy).forward_dynamics(q, v, tau), rtol=1e-10)
    assert not np.allclose(a, armctl.Dynamics(model).forward_dynamics(q, v, tau), rtol=1e-3)


@pytest.mark.parametrize("integrator", ["rk4", "euler"])
# its run goes beyond a velocity limit on the way, as expected
@pytest.mark.filterwarnings("ignore:the run went beyond the plant's limits:armctl.errors.SimulationWarning")
def test_simulate_compiled_is_the_same_run(integrator: str) -> None:
    model = armctl.models.planar_3r().reduced(friction=False)
    dyn = armctl.Dynamics(model)
    ctrl = ComputedTorque(armctl.Dynamics(model), 400.0, 40.0)  # critically damped at 20 rad/s
    ref = Reference(np.array([0.5, -0.4, 0.3]))
    runs = [
        armctl.sim.simulate(
            dyn, ctrl, ref, 0.5, q0=np.zeros(3), control_dt=2e-3, dt=5e-4, integrator=integrator, compile=c
        )
        for c in (False, True)
    ]
    assert [r.info["compiled"] for r in runs] == [False, True]
    for field in ("q", "qd", "qdd", "tau"):
        np.testing.assert_allclose(getattr(runs[1], field), getattr(runs[0], field), rtol=1e-10, atol=1e-10)
    assert np.abs(runs[1].q[-1] - ref.q).max() < 1e-2  # (the run went somewhere: it tracked the set point)


# its run goes beyond a velocity limit on the way, as expected
@pytest.mark.filterwarnings("ignore:the run went beyond the plant's limits:armctl.errors.SimulationWarning")
# its run saturates the torque, as expected
@pytest.mark.filterwarnings("ignore:torque at its limit on most samples:armctl.errors.SimulationWarning")
def test_simulate_compiled_reports_divergence_as_the_uncompiled_run_does() -> None:
    model = armctl.models.planar_2r().reduced(friction=False)

    def push(t: float, q: np.ndarray, qd: np.ndarray, ref: Reference) -> np.ndarray:
        return np.array([1e6, -1e6])

    runs = [
        armctl.sim.simulate(
            model, push, Reference(np.zeros(2)), 1.0, saturate=False, compile=c, stop=StopRules(max_velocity=50.0)
        )
        for c in (False, True)
    ]
    assert all(r.diverged for r in runs)
    assert runs[1].diverged_at == runs[0].diverged_at
    assert "max_velocity" in runs[1].divergence


class _OwnFriction(FrictionModel):
    """A user's friction model: no generated code for it."""

    def torque(self, qd: np.ndarray, direction: np.ndarray) -> np.ndarray:
        return self.viscous * qd

    def slope(self, qd: np.ndarray, direction: np.ndarray) -> np.ndarray:
        return self.viscous.copy()


class _OwnEnvironment(Environment):
    """A user's environment (a spring pulling the tool towards the origin): no generated code for it."""

    points = (ContactPoint(),)

    def force(self, p: np.ndarray, v: np.ndarray, derivatives: bool) -> tuple:
        return -10.0 * p, -10.0 * np.eye(3), np.zeros((3, 3))


@pytest.mark.parametrize("case", ["rotor_coupling", "own_friction", "own_environment"])
def test_compile_true_refuses_a_plant_without_generated_code(case: str) -> None:
    """The rotors' gyroscopic coupling, a friction model or an environment of the user's own have no generated
    step: compile=True is an error naming the cause and the way out, compile='auto' runs the Python step."""
    rigid = armctl.models.planar_2r().reduced(friction=False)
    plant: armctl.RobotModel | armctl.Dynamics = rigid
    kw: dict = {}
    if case == "rotor_coupling":
        plant = armctl.Dynamics(rigid, backend="lagrange")  # rotor_coupling=True by default
    elif case == "own_friction":
        plant = rigid.with_friction(viscous=1.0)
        kw["friction"] = _OwnFriction(plant)
    else:
        kw["environment"] = _OwnEnvironment()
    ctrl = ComputedTorque(armctl.Dynamics(rigid), 100.0, 20.0)
    with pytest.raises(InvalidParameterError) as err:
        armctl.sim.simulate(plant, ctrl, Reference(np.zeros(2)), 0.01, compile=True, **regroup(kw))
    expect = {
        "rotor_coupling": "rotor_coupling=False",
        "own_friction": "_OwnFriction has no generated code",
        "own_environment": "_OwnEnvironment has no generated code",
    }[case]
    assert expect in str(err.value) and "compile=False" in str(err.value)
    assert armctl.sim.simulate(plant, ctrl, Reference(np.zeros(2)), 0.01, **regroup(kw)).info["compiled"] is False


@pytest.mark.parametrize("value", ["yes", 1, None])
def test_compile_is_true_false_or_auto(value: object) -> None:
    model = armctl.models.planar_2r().reduced(friction=False)
    with pytest.raises(ArmctlError, match="compile must be True"):
        armctl.sim.simulate(model, lambda t, q, qd, r: np.zeros(2), Reference(np.zeros(2)), 0.01, compile=value)
