"""Impedance control against closed forms: pressing on a compliant plane, the normal force at rest is
k_e k_d / (k_e + k_d) times the commanded penetration; the default damping makes every mode of Λ ë + D ė + K e
critically damped; joint impedance yields K⁻¹ Jᵀ h under a constant wrench."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import armctl
from armctl.controllers import CartesianImpedance, JointImpedance
from armctl.controllers.interaction.gains import critical_damping
from armctl.sim import ForceSensor, KelvinVoigt, Plane

Q_READY = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])


@pytest.fixture(scope="module")
def panda() -> armctl.Dynamics:
    return armctl.Dynamics(armctl.models.panda())


@pytest.mark.parametrize(("ke", "kd"), [(5e3, 800.0), (2e4, 300.0), (1e3, 2000.0)])
def test_pressing_on_a_plane_gives_the_series_spring_force(panda: armctl.Dynamics, ke: float, kd: float) -> None:
    pose = panda.frame_pose(Q_READY)
    z_surface = pose[2, 3] - 0.002  # 2 mm below the tool: it reaches the plane on the way down
    depth = 0.01  # the target 1 cm beyond the surface
    plane = Plane(KelvinVoigt(ke, 80.0), point=(0.0, 0.0, z_surface))
    ctrl = CartesianImpedance(panda, [kd, kd, kd, 50.0, 50.0, 50.0], nullspace_stiffness=5.0)
    target = pose.copy()
    target[2, 3] = z_surface - depth
    ctrl.set_target(target)
    res = armctl.simulate(
        panda.model,
        ctrl,
        armctl.Reference(Q_READY),
        2.5,
        q0=Q_READY,
        dt=2e-4,
        environment=plane,
        sensors=ForceSensor(world_axes=True),
    )
    assert not res.diverged
    normal = -res.sensor[-200:, 0, 2]  # the arm pushes down (−z): the normal force is −f_z
    expected = ke * kd / (ke + kd) * depth
    assert np.ptp(normal) < 1e-3 * expected  # at rest
    assert normal[-1] == pytest.approx(expected, rel=0.01)


def test_default_damping_makes_every_mode_critically_damped() -> None:
    rng = np.random.default_rng(3)
    a = rng.normal(size=(6, 6))
    lam = a @ a.T + 0.5 * np.eye(6)
    b = rng.normal(size=(6, 6))
    k = b @ b.T * 100.0
    d = critical_damping(lam, k)
    # each eigenvalue s of the pencil (Λ s² + D s + K) is a double root: s = −ω for each ω² of Λ⁻¹ K
    n = 6
    companion = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(lam, k), -np.linalg.solve(lam, d)]])
    roots = np.sort_complex(np.linalg.eigvals(companion))
    omega = np.sqrt(np.sort(np.linalg.eigvals(np.linalg.solve(lam, k)).real))
    np.testing.assert_allclose(np.sort(roots.real), np.sort(np.repeat(-omega, 2)), rtol=1e-4)
    assert np.abs(roots.imag).max() < 1e-3 * omega.max()


def test_joint_impedance_yields_the_compliance_of_its_springs(panda: armctl.Dynamics) -> None:
    model = panda.model
    push = np.array([0.0, 0.0, -5.0, 0.0, 0.0, 0.0])  # the arm exerts 5 N down: the world pushes it up
    k = np.array([300.0, 300.0, 300.0, 300.0, 100.0, 100.0, 100.0])
    ctrl = JointImpedance(panda, k)
    res = armctl.simulate(model, ctrl, armctl.Reference(Q_READY), 3.0, q0=Q_READY, disturbance=lambda t: push)
    q_end = res.q[-1]
    # at rest: K (q_d − q) = Jᵀ h at the final configuration
    np.testing.assert_allclose(k * (Q_READY - q_end), panda.jacobian(q_end).T @ push, atol=2e-3)


@pytest.mark.parametrize("given_damping", [True, False])
@pytest.mark.parametrize("null", [0.0, 10.0])
@pytest.mark.parametrize("axes", [6, 3])
def test_generated_law_matches_the_numpy_law(
    panda: armctl.Dynamics, null: float, axes: int, given_damping: bool
) -> None:
    # two implementations: generated C from the recursive algorithms and CasADi, and Pinocchio with NumPy
    k = [800.0, 600.0, 700.0, 50.0, 40.0, 30.0][:axes]
    d = [60.0, 50.0, 55.0, 5.0, 4.0, 3.0][:axes] if given_damping else None
    fast = CartesianImpedance(panda, k, d, nullspace_stiffness=null, compile=True)
    slow = CartesianImpedance(panda, k, d, nullspace_stiffness=null, compile=False)
    assert fast._generated is not None and slow._generated is None
    rng = np.random.default_rng(7)
    pose = panda.frame_pose(Q_READY)
    target = pose if axes == 6 else pose[:3, 3]
    twist = np.array([0.1, -0.05, 0.02, 0.3, 0.0, -0.2])[:axes]
    accel = np.array([0.5, 0.0, -0.3, 0.0, 1.0, 0.0])[:axes]
    for c in (fast, slow):
        c.set_target(target, twist, accel)
    for _ in range(5):
        q = Q_READY + rng.uniform(-0.4, 0.4, 7)
        qd = rng.uniform(-1.0, 1.0, 7)
        ref = armctl.Reference(Q_READY + rng.uniform(-0.2, 0.2, 7))
        np.testing.assert_allclose(fast(0.0, q, qd, ref), slow(0.0, q, qd, ref), rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(fast.last_log["force"], slow.last_log["force"], rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("shaped", [False, True])
def test_the_frame_accelerates_as_its_inertia_says(panda: armctl.Dynamics, shaped: bool) -> None:
    # at rest on its target, under a wrench h the arm exerts, the frame accelerates by −Λ⁻¹ h: Λ = Λ_d with
    # inertia shaping, the arm's own Λ(q) without; the acceleration from the model's forward dynamics
    from armctl.controllers import Measurement

    q = Q_READY + np.array([0.1, -0.1, 0.05, 0.1, -0.05, 0.1, 0.0])
    h = np.array([3.0, -2.0, 5.0, 0.2, -0.1, 0.3])
    lam_d = np.diag([4.0, 4.0, 4.0, 0.05, 0.05, 0.05])
    ctrl = CartesianImpedance(panda, [500.0] * 3 + [30.0] * 3, inertia=lam_d if shaped else None)
    ctrl.set_target(panda.frame_pose(q))
    tau = ctrl(0.0, q, np.zeros(7), armctl.Reference(q), measurement=Measurement(wrench=h, world_axes=True))
    xdd = panda.jacobian(q) @ panda.forward_dynamics(q, np.zeros(7), tau, wrench=h)
    jac = panda.jacobian(q)
    lam = lam_d if shaped else np.linalg.inv(jac @ np.linalg.solve(panda.mass_matrix(q), jac.T))
    np.testing.assert_allclose(xdd, -np.linalg.solve(lam, h), rtol=1e-8, atol=1e-9)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), zeta=st.floats(0.1, 2.0), m=st.sampled_from([3, 6, 7]))
def test_default_damping_gives_every_mode_its_damping_ratio(seed: int, zeta: float, m: int) -> None:
    # the modes from SciPy's generalized eigensolver, K v = ω² Λ v (vᵀ Λ v = 1): D is diagonal on them, 2 ζ ω
    from scipy.linalg import eigh

    rng = np.random.default_rng(seed)
    a, b = rng.normal(size=(m, m)), rng.normal(size=(m, m))
    lam = a @ a.T + 0.1 * np.eye(m)
    k = b @ b.T * 10.0 ** rng.uniform(0, 3)
    omega2, v = eigh(k, lam)
    modal = v.T @ critical_damping(lam, k, zeta) @ v
    expected = 2.0 * zeta * np.sqrt(np.maximum(omega2, 0.0))
    scale = np.abs(expected).max()
    np.testing.assert_allclose(np.diag(modal), expected, atol=1e-8 * scale)
    np.testing.assert_allclose(modal - np.diag(np.diag(modal)), 0.0, atol=1e-8 * scale)
