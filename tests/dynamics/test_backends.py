"""The two backends against each other, and against closed-form textbook models.

Wherever both express the model (rotor coupling off), Lagrange (CasADi) = Pinocchio to ≤ 1e-9 relative. With
the coupling on, their difference is exactly the rotors' gyroscopic term, here computed independently from
Pinocchio's joint Jacobians.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import armctl
from tests.helpers.arms import dynamics, model

G = 9.81


def rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(np.asarray(a) - b).max() / max(np.abs(b).max(), 1e-12))


@pytest.mark.parametrize("name", ["pendulum", "planar_2r", "planar_3r", "puma560", "panda", "ur5"])
def test_lagrange_equals_pinocchio_without_rotor_coupling(name: str) -> None:
    pin_dyn = dynamics(name)
    lag = dynamics(name, "lagrange", rotor_coupling=False)
    rng = np.random.default_rng(3)
    for _ in range(5):
        q, qd, qdd = rng.uniform(-2.5, 2.5, (3, pin_dyn.n))
        wrench = rng.normal(size=6)
        assert rel(lag.mass_matrix(q), pin_dyn.mass_matrix(q)) <= 1e-9
        assert rel(lag.coriolis_matrix(q, qd), pin_dyn.coriolis_matrix(q, qd)) <= 1e-9
        assert rel(lag.gravity_torque(q), pin_dyn.gravity_torque(q)) <= 1e-9
        assert rel(lag.inverse_dynamics(q, qd, qdd, wrench), pin_dyn.inverse_dynamics(q, qd, qdd, wrench)) <= 1e-9
        assert rel(lag.forward_dynamics(q, qd, qdd), pin_dyn.forward_dynamics(q, qd, qdd)) <= 1e-9
        assert rel(lag.regressor(q, qd, qdd), pin_dyn.regressor(q, qd, qdd)) <= 1e-9
        assert rel(lag.jacobian(q), pin_dyn.jacobian(q)) <= 1e-9
        assert rel(lag.frame_pose(q), pin_dyn.frame_pose(q)) <= 1e-9
        assert lag.kinetic_energy(q, qd) == pytest.approx(pin_dyn.kinetic_energy(q, qd), rel=1e-9)
        assert lag.potential_energy(q) == pytest.approx(pin_dyn.potential_energy(q), rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("name", ["planar_2r", "puma560"])
def test_rotor_coupling_is_the_only_difference(name: str) -> None:
    """M_lagrange − M_pinocchio = ΔM with ΔM_ij = ΔM_ji = k_r,i I_m,i z_m,iᵀ J_ω,j^(i−1) (j < i)."""
    m = model(name)
    pin_dyn = dynamics(name)
    lag = dynamics(name, "lagrange")  # coupling on (the default)
    pm = m.to_pinocchio()
    data = pm.createData()
    rng = np.random.default_rng(5)
    for _ in range(4):
        q, qd, qdd = rng.uniform(-2, 2, (3, m.n))
        pin.computeJointJacobians(pm, data, q)
        delta = np.zeros((m.n, m.n))
        for i, joint in enumerate(m.joints):
            if i == 0 or joint.motor is None:
                continue
            z_world = data.oMi[i].rotation @ joint.motor_axis  # Pinocchio joint id i is the i-th joint (1-based)
            j_omega = pin.getJointJacobian(pm, data, i, pin.LOCAL_WORLD_ALIGNED)[3:]
            row = joint.motor.gear_ratio * joint.motor.inertia * (z_world @ j_omega)
            delta[i, :i] += row[:i]
            delta[:i, i] += row[:i]
        assert np.abs(delta).max() > 1e-4  # the term is there
        diff = lag.mass_matrix(q) - pin_dyn.mass_matrix(q)
        assert np.allclose(diff, delta, rtol=1e-9, atol=1e-12)
        assert np.allclose(lag.rotor_coupling_matrix(q), delta, atol=1e-12)
        # and the identities still hold for the coupled model
        y = lag.regressor(q, qd, qdd)
        assert np.allclose(y @ m.parameters(), lag.inverse_dynamics(q, qd, qdd), atol=1e-9)


def test_pendulum_closed_form() -> None:
    """(I_c + m ℓ² + k_r² I_m) q̈ + F_v q̇ + m g ℓ sin q = τ for the geared pendulum."""
    m_link, length, i_m, k_r, f_v = 2.0, 0.5, 5e-5, 50.0, 0.05
    ell = length / 2
    inertia = m_link * length**2 / 12 + m_link * ell**2 + k_r**2 * i_m
    for backend in ("pinocchio", "lagrange"):
        dyn = dynamics("pendulum", backend)
        for q, qd, qdd in [(0.3, 0.2, -1.0), (-2.0, -1.5, 0.7), (math.pi / 2, 0.0, 0.0)]:
            expected = inertia * qdd + f_v * qd + m_link * G * ell * math.sin(q)
            assert dyn.inverse_dynamics([q], [qd], [qdd])[0] == pytest.approx(expected, rel=1e-12, abs=1e-12)
        assert dyn.mass_matrix([0.4])[0, 0] == pytest.approx(inertia, rel=1e-12)


def siciliano_2r(q: np.ndarray, qd: np.ndarray, coupling: bool) -> tuple[np.ndarray, ...]:
    """Siciliano et al., Robotics (2009), eqs. (7.82)–(7.83): the two-link arm with geared motors."""
    a1, l1, l2, m_l1, m_l2, i_l1, i_l2 = 1.0, 0.5, 0.5, 50.0, 50.0, 10.0, 10.0
    m_m2, i_m1, i_m2, k_r1, k_r2 = 5.0, 0.01, 0.01, 100.0, 100.0
    c2, s2 = math.cos(q[1]), math.sin(q[1])
    b11 = i_l1 + m_l1 * l1**2 + k_r1**2 * i_m1 + i_l2 + m_l2 * (a1**2 + l2**2 + 2 * a1 * l2 * c2) + i_m2 + m_m2 * a1**2
    b12 = i_l2 + m_l2 * (l2**2 + a1 * l2 * c2) + (k_r2 * i_m2 if coupling else 0.0)
    b22 = i_l2 + m_l2 * l2**2 + k_r2**2 * i_m2
    h = -m_l2 * a1 * l2 * s2
    c = np.array([[h * qd[1], h * (qd[0] + qd[1])], [-h * qd[0], 0.0]])
    c1, c12 = math.cos(q[0]), math.cos(q[0] + q[1])
    g = np.array([(m_l1 * l1 + m_m2 * a1 + m_l2 * a1) * G * c1 + m_l2 * l2 * G * c12, m_l2 * l2 * G * c12])
    return np.array([[b11, b12], [b12, b22]]), c, g


@pytest.mark.parametrize(("backend", "coupling"), [("pinocchio", False), ("lagrange", True), ("lagrange", False)])
def test_planar_2r_closed_form(backend: str, coupling: bool) -> None:
    dyn = (
        dynamics("planar_2r", backend)
        if backend == "pinocchio"
        else dynamics("planar_2r", backend, rotor_coupling=coupling)
    )
    rng = np.random.default_rng(11)
    for _ in range(10):
        q, qd = rng.uniform(-3, 3, (2, 2))
        b, c, g = siciliano_2r(q, qd, coupling)
        assert np.allclose(dyn.mass_matrix(q), b, rtol=1e-12, atol=1e-12)
        assert np.allclose(dyn.coriolis_matrix(q, qd), c, rtol=1e-12, atol=1e-10)
        assert np.allclose(dyn.gravity_torque(q), g, rtol=1e-12, atol=1e-10)


def test_puma560_published_gravity_load() -> None:
    """Corke's toolbox prints gravload(qn) = [0 31.6399 6.0351 0 0.0283 0] for the standard Puma 560."""
    from armctl.models import PUMA_QN

    for backend in ("pinocchio", "lagrange"):
        g = dynamics("puma560", backend).gravity_torque(PUMA_QN)
        assert np.allclose(g, [0, 31.6399, 6.0351, 0, 0.0283, 0], atol=6e-5)


def test_compiled_lagrange_matches_and_is_cached(tmp_path: Path) -> None:
    """Compiled C code gives the VM's τ; a payload variant (same kinematics) loads the same library instead
    of compiling another; a different arm is not cached."""
    from armctl.dynamics.lagrange import LagrangeDynamics

    m = model("planar_2r")
    assert not LagrangeDynamics.is_compiled_cached(m, cache_dir=str(tmp_path))
    a = armctl.Dynamics(m, backend="lagrange", compile=True, cache_dir=str(tmp_path))
    libs = list(tmp_path.rglob("*.so"))
    assert len(libs) == 1 and LagrangeDynamics.is_compiled_cached(m, cache_dir=str(tmp_path))
    built = libs[0].stat().st_mtime_ns
    b = armctl.Dynamics(
        m.with_payload(2.0, (0.1, 0, 0)), backend="lagrange", compile=True, cache_dir=str(tmp_path)
    )  # same kinematics
    assert list(tmp_path.rglob("*.so")) == libs and libs[0].stat().st_mtime_ns == built  # loaded, not rebuilt
    assert not LagrangeDynamics.is_compiled_cached(model("planar_3r"), cache_dir=str(tmp_path))
    ref_a, ref_b = (
        dynamics("planar_2r", "lagrange"),
        armctl.Dynamics(m.with_payload(2.0, (0.1, 0, 0)), backend="lagrange"),
    )
    rng = np.random.default_rng(2)
    q, qd, qdd = rng.uniform(-2, 2, (3, 2))
    assert np.allclose(a.inverse_dynamics(q, qd, qdd), ref_a.inverse_dynamics(q, qd, qdd), rtol=1e-12)
    assert np.allclose(b.inverse_dynamics(q, qd, qdd), ref_b.inverse_dynamics(q, qd, qdd), rtol=1e-12)
    assert not np.allclose(a.inverse_dynamics(q, qd, qdd), b.inverse_dynamics(q, qd, qdd))
    assert a.functions["tau"].is_a("External")


def test_compiled_libraries_with_and_without_rotor_coupling_are_kept_apart(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``compile=True`` with rotor_coupling True (cached in $ARMCTL_CACHE, the codegen module's default), then
    False (cache_dir: the same folder): two libraries, each giving its own model's M (Siciliano's closed form,
    with and without the k_r2 I_m2 coupling term)."""
    from armctl.dynamics.lagrange import LagrangeDynamics

    monkeypatch.setenv("ARMCTL_CACHE", str(tmp_path))
    m = model("planar_2r")
    assert not LagrangeDynamics.is_compiled_cached(m)
    coupled = armctl.Dynamics(m, backend="lagrange", compile=True)
    assert len(list(tmp_path.rglob("*.so"))) == 1 and LagrangeDynamics.is_compiled_cached(m)
    assert not LagrangeDynamics.is_compiled_cached(m, rotor_coupling=False)
    plain = armctl.Dynamics(m, backend="lagrange", compile=True, rotor_coupling=False, cache_dir=str(tmp_path))
    assert len(list(tmp_path.rglob("*.so"))) == 2
    assert coupled.functions["M"].is_a("External") and plain.functions["M"].is_a("External")
    for q in np.random.default_rng(6).uniform(-3.0, 3.0, (3, 2)):
        for dyn, coupling in ((coupled, True), (plain, False)):
            b, _, _ = siciliano_2r(q, np.zeros(2), coupling)
            np.testing.assert_allclose(dyn.mass_matrix(q), b, rtol=1e-12, atol=1e-12)


def test_a_non_gyroscopic_motor_adds_no_rotor_coupling() -> None:
    """planar_3r given rotor inertias through with_parameters gets motors without gyroscopic coupling: the
    coupled Lagrange model's M is then Pinocchio's (armature only), and rotor_coupling_matrix, by its docstring
    that difference, is zero."""
    m = model("planar_3r")
    theta = m.parameters().reshape(3, 13).copy()
    theta[:, 10] = [0.5, 0.3, 0.2]
    armature = m.with_parameters(theta.reshape(-1))
    assert all(j.motor is not None and not j.motor.gyroscopic for j in armature.joints)
    lag, pin_dyn = armctl.Dynamics(armature, backend="lagrange"), armctl.Dynamics(armature)
    for q in np.random.default_rng(9).uniform(-2.0, 2.0, (3, 3)):
        np.testing.assert_allclose(lag.mass_matrix(q), pin_dyn.mass_matrix(q), rtol=1e-12, atol=1e-12)
        assert not lag.rotor_coupling_matrix(q).any()


@pytest.mark.parametrize("name", ["pendulum", "planar_2r", "puma560", "panda", "ur5"])
def test_pinocchio_forward_dynamics_in_the_world_convention_is_abas_default_one(name: str) -> None:
    """The backend runs ABA in Pinocchio's WORLD convention (faster); its q̈ must be the LOCAL (default) one's,
    and M⁻¹(τ − h) formed from CRBA and RNEA, rotors (armature) included."""
    import pinocchio as pin

    dyn = dynamics(name, "pinocchio")
    pm = dyn.pin_model
    pd = pm.createData()
    rng = np.random.default_rng(11)
    for q, qd, tau in rng.uniform(-2.0, 2.0, (5, 3, dyn.n)):
        got = dyn.kernel.aba(q, qd, tau)
        local = pin.aba(pm, pd, q, qd, tau).copy()
        by_hand = np.linalg.solve(pin.crba(pm, pd, q).copy(), tau - pin.rnea(pm, pd, q, qd, np.zeros(dyn.n)))
        scale = max(1.0, float(np.abs(local).max()))
        assert np.abs(got - local).max() <= 1e-12 * scale
        assert np.abs(got - by_hand).max() <= 1e-10 * scale
