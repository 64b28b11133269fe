"""RobotModel variants: reduced(lock=...) against the full model with the locked joints held, and the argument
checks of perturbed() and with_friction(); what fingerprint() covers."""

from __future__ import annotations

import math
from dataclasses import replace
from functools import cache

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import armctl
from armctl.errors import ArmctlError, InvalidParameterError, NonFiniteError, ShapeError, UnknownNameError
from armctl.model import Joint, JointFriction, Link, Motor
from armctl.model.parts import Frame

# joint 2 prismatic; every motor has an explicit spin axis off the joint axis (a bevel gear), which is what
# the rotor coupling sees; gear ratios of both signs; asymmetric Coulomb friction on every joint
_N = 5
_PRISMATIC = 2


def _random_transform(rng: np.random.Generator, reach: float = 0.3) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3] = Rotation.from_rotvec(rng.uniform(-2.0, 2.0, 3)).as_matrix()
    t[:3, 3] = rng.uniform(-reach, reach, 3)
    return t


@cache
def _arm() -> armctl.RobotModel:
    rng = np.random.default_rng(7)
    joints = []
    for i in range(_N):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        a, b, c = rng.uniform(0.05, 0.4, 3)
        mass = rng.uniform(0.5, 3.0)
        r = Rotation.from_rotvec(rng.uniform(-2.0, 2.0, 3)).as_matrix()
        box = mass / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
        link = Link(mass, rng.uniform(-0.2, 0.2, 3), r @ box @ r.T)
        motor = Motor(rng.uniform(1e-4, 1e-3), (-1) ** i * rng.uniform(5.0, 50.0), rng.normal(size=3))
        friction = JointFriction(rng.uniform(0.1, 0.5), rng.uniform(0.1, 1.0), rng.uniform(0.1, 1.0))
        joints.append(
            Joint(
                f"j{i}",
                "prismatic" if i == _PRISMATIC else "revolute",
                axis,
                _random_transform(rng),
                link,
                motor,
                friction,
            )
        )
    frames = [Frame("target", 0, _random_transform(rng)), Frame("tool", _N, _random_transform(rng, 0.2))]
    frames += [Frame(f"on_link{i}", i, _random_transform(rng, 0.2)) for i in range(1, _N + 1)]
    return armctl.RobotModel(tuple(joints), name="bevel", frames=tuple(frames), tool_frame="tool")


def _hand_pose(model: armctl.RobotModel, q: np.ndarray, frame: str) -> np.ndarray:
    """World pose of a frame by composing the chain by hand: P_1 M_1(q_1) … P_k M_k(q_k) F."""
    f = model.frame(frame)
    t = np.eye(4)
    for j, qj in zip(model.joints[: f.joint], q[: f.joint], strict=True):
        motion = np.eye(4)
        if j.kind == "revolute":
            motion[:3, :3] = Rotation.from_rotvec(j.axis * qj).as_matrix()
        else:
            motion[:3, 3] = j.axis * qj
        t = t @ j.placement @ motion
    return t @ f.placement


LOCKS = [
    {"j1": 0.7},  # a revolute joint in the middle: joint 3's rotor rides on the merged link
    {"j0": -0.4},  # the first joint: link 1 (and joint 2's rotor) merge into the world
    {"j2": 0.15},  # a prismatic joint
    {"j1": 0.7, "j2": -0.1},  # two adjacent joints: placements compose over both
    {"j0": 0.3, "j1": -1.2},  # the first two
    {"j4": 0.9},  # the last joint, which carries the tool frame
]


def _states(lock: dict[str, float], rng: np.random.Generator) -> tuple[list[int], np.ndarray, np.ndarray, np.ndarray]:
    arm = _arm()
    idx = [arm.joint_index(name) for name in lock]
    keep = [i for i in range(arm.n) if i not in idx]
    q, qd, qdd = rng.uniform(-1.5, 1.5, (3, arm.n))
    for name, value in lock.items():
        k = arm.joint_index(name)
        q[k], qd[k], qdd[k] = value, 0.0, 0.0
    return keep, q, qd, qdd


@pytest.mark.parametrize("lock", LOCKS, ids=lambda d: "+".join(f"{k}={v}" for k, v in d.items()))
@pytest.mark.parametrize("backend", ["pinocchio", "lagrange"])
def test_locked_model_is_the_full_model_held_at_the_lock(lock: dict[str, float], backend: str) -> None:
    """M, C q̇ + g and τ (friction included) of the reduced arm equal the full arm's with the locked joints at
    their lock positions and at rest. On the Lagrange backend the rotors' gyroscopic coupling is on, so a
    motor spin axis left in the frame of a merged link shows in M and C."""
    arm = _arm()
    red = arm.reduced(lock=lock)
    opts = {"rotor_coupling": True} if backend == "lagrange" else {}
    full, r = armctl.Dynamics(arm, backend=backend, **opts), armctl.Dynamics(red, backend=backend, **opts)
    rng = np.random.default_rng(3)
    for _ in range(4):
        keep, q, qd, qdd = _states(lock, rng)
        ix = np.ix_(keep, keep)
        m_full = full.mass_matrix(q)
        assert np.allclose(r.mass_matrix(q[keep]), m_full[ix], rtol=0, atol=1e-12)
        h_full = full.coriolis_matrix(q, qd) @ qd + full.gravity_torque(q)
        h_red = r.coriolis_matrix(q[keep], qd[keep]) @ qd[keep] + r.gravity_torque(q[keep])
        assert np.allclose(h_red, h_full[keep], rtol=0, atol=1e-11)
        tau_full = full.inverse_dynamics(q, qd, qdd)
        assert np.allclose(r.inverse_dynamics(q[keep], qd[keep], qdd[keep]), tau_full[keep], rtol=0, atol=1e-11)
        if backend == "lagrange":
            coupling = full.rotor_coupling_matrix(q)
            assert np.abs(coupling[ix]).max() > 1e-4  # the term under test is there
            assert np.allclose(r.rotor_coupling_matrix(q[keep]), coupling[ix], rtol=0, atol=1e-12)


def test_locking_reexpresses_the_motor_axis_and_keeps_motor_and_friction() -> None:
    """Joint 3's rotor rides on link 2; with joint 2 locked at 0.7 link 2 is part of link 1, so the spin axis
    becomes R(P_2) R(axis_2, 0.7) z_m (hand computation). Gear ratio (sign included), rotor inertia,
    friction and limits of the kept joints are unchanged; the locked joint's motor and friction go."""
    arm = _arm()
    red = arm.reduced(lock={"j1": 0.7})
    j1, j2 = arm.joints[1], arm.joints[2]
    expected = j1.placement[:3, :3] @ Rotation.from_rotvec(j1.axis * 0.7).as_matrix() @ j2.motor.axis
    assert red.joint_names == ("j0", "j2", "j3", "j4")
    assert np.allclose(red.joints[1].motor.axis, expected, rtol=0, atol=1e-14)
    assert np.allclose(red.joints[2].motor.axis, arm.joints[3].motor.axis, rtol=0, atol=0)  # its link stays
    for new in red.joints:
        old = arm.joints[arm.joint_index(new.name)]
        assert new.motor.gear_ratio == old.motor.gear_ratio and new.motor.inertia == old.motor.inertia
        assert new.friction is old.friction and new.limits is old.limits
    assert sum(j.motor.reflected_inertia for j in red.joints) < sum(j.motor.reflected_inertia for j in arm.joints)
    # a motor without an explicit axis follows its joint axis, which the merge carries with the placement
    no_axis = tuple(replace(j, motor=Motor(1e-3, -20.0)) if i == 2 else j for i, j in enumerate(arm.joints))
    kept = armctl.RobotModel(no_axis).reduced(lock={"j1": 0.7}).joints[1]
    assert kept.motor.axis is None
    expected = j1.placement[:3, :3] @ Rotation.from_rotvec(j1.axis * 0.7).as_matrix() @ j2.placement[:3, :3] @ j2.axis
    assert np.allclose(kept.motor_axis, expected, rtol=0, atol=1e-14)


@pytest.mark.parametrize("lock", LOCKS, ids=lambda d: "+".join(f"{k}={v}" for k, v in d.items()))
def test_locking_keeps_every_frame_where_it_was(lock: dict[str, float]) -> None:
    """Every frame of the full arm (the world-attached one, those on merged links, the locked joints' own
    frames) is in the reduced arm at the world pose it had in the full arm (composed by hand)."""
    arm = _arm()
    red = arm.reduced(lock=lock)
    assert set(red.frame_names) == set(arm.frame_names)
    assert red.tool_frame == "tool"
    assert red.frame("target").joint == 0
    dyns = [armctl.Dynamics(red, backend=b) for b in ("pinocchio", "lagrange")]
    rng = np.random.default_rng(5)
    for _ in range(3):
        keep, q, _, _ = _states(lock, rng)
        for name in arm.frame_names:
            expected = _hand_pose(arm, q, name) if name != "world" else np.eye(4)
            for d in dyns:
                assert np.allclose(d.frame_pose(q[keep], name), expected, rtol=0, atol=1e-12), (name, d.backend)
        assert np.allclose(dyns[0].frame_pose(q[keep]), _hand_pose(arm, q, "tool"), rtol=0, atol=1e-12)


def test_locking_the_last_joint_keeps_the_default_tool_frame() -> None:
    """With tool_frame=None the tool is the last joint's frame: locking that joint must not move it."""
    arm = replace(_arm(), tool_frame=None)
    red = arm.reduced(lock={"j4": 0.9})
    assert red.tool_frame == "j4"
    q = np.array([0.2, -0.3, 0.05, 0.8, 0.9])
    assert np.allclose(armctl.Dynamics(red).frame_pose(q[:4]), _hand_pose(arm, q, "j4"), rtol=0, atol=1e-12)


def test_bad_lock_arguments() -> None:
    arm = _arm()
    with pytest.raises(UnknownNameError, match=r"'j9'.*'j0'"):
        arm.reduced(lock=["j9"])
    with pytest.raises(NonFiniteError, match=r"'j1'.*nan"):
        arm.reduced(lock={"j1": math.nan})
    with pytest.raises(InvalidParameterError, match=r"'j1'.*'up'"):
        arm.reduced(lock={"j1": "up"})
    with pytest.raises(InvalidParameterError, match="at least one free joint"):
        arm.reduced(lock=list(arm.joint_names))
    assert arm.reduced(lock="j1").joint_names == ("j0", "j2", "j3", "j4")  # one name, not its letters


@pytest.mark.parametrize("arg", ["mass", "inertia", "com_offset", "friction", "rotor", "noise"])
@pytest.mark.parametrize("value", [math.nan, math.inf, -0.1, "0.1", 1j])
def test_perturbed_rejects_bad_factors(arg: str, value: object) -> None:
    """noise=nan used to scale every mass by 0.05 (max(0.05, nan)), negative noise and offsets passed."""
    with pytest.raises(InvalidParameterError, match=f"perturbed\\(\\): {arg} must be finite and >= 0"):
        armctl.models.planar_2r().perturbed(**{arg: value}, seed=0)


def test_perturbed_noise_keeps_masses_near_nominal() -> None:
    """Statistics of the noise factor (closed form: mean 1, sd = noise) over many links of a chain."""
    joints = tuple(Joint(f"j{i}", "revolute", (0, 0, 1), np.eye(4), Link(2.0)) for i in range(400))
    masses = np.array([j.link.mass for j in armctl.RobotModel(joints).perturbed(noise=0.1, seed=1).joints])
    assert abs(masses.mean() - 2.0) < 4 * 0.2 / math.sqrt(400)
    assert 0.15 < masses.std() < 0.25


def test_perturbed_com_offset_moves_every_com_by_that_distance() -> None:
    """com_offset: every centre of mass moves by com_offset metres along a random direction (the docstring's
    definition: the norm of each shift, by hand), directions differing between links; nothing else changes."""
    arm = _arm()
    for seed in range(3):
        p = arm.perturbed(com_offset=0.02, seed=seed)
        shifts = np.array([b.link.com - a.link.com for a, b in zip(arm.joints, p.joints, strict=True)])
        np.testing.assert_allclose(np.linalg.norm(shifts, axis=1), 0.02, rtol=1e-12)
        assert np.linalg.matrix_rank(shifts, tol=1e-3) == 3  # not one direction for all links
        for a, b in zip(arm.joints, p.joints, strict=True):
            assert b.link.mass == a.link.mass and np.array_equal(b.link.inertia, a.link.inertia)


def test_perturbed_noise_scales_each_link_as_a_whole() -> None:
    """noise: one random factor per link (docstring), on its mass and on its inertia about the centre of mass
    alike, on top of the mass and inertia factors; the com stays. Reference: the factor read off the mass."""
    arm = _arm()
    p = arm.perturbed(mass=1.2, inertia=0.8, noise=0.3, seed=4)
    factors = []
    for a, b in zip(arm.joints, p.joints, strict=True):
        f = b.link.mass / (1.2 * a.link.mass)
        np.testing.assert_allclose(b.link.inertia, 0.8 * f * a.link.inertia, rtol=1e-12, atol=0)
        np.testing.assert_array_equal(b.link.com, a.link.com)
        factors.append(f)
    assert np.std(factors) > 0.05  # the factors are there and differ between links


def _frame_jacobians(
    arm: armctl.RobotModel, q: np.ndarray, frame: str, point: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(R, J_v, J_ω) of a frame composed by hand: its world rotation R, the Jacobian of the world position of
    ``point`` (given in the frame) and the angular-velocity Jacobian, by central differences (ω^ = Ṙ Rᵀ)."""
    h, n = 1e-6, arm.n
    rot = _hand_pose(arm, q, frame)[:3, :3]
    jv, jw = np.zeros((3, n)), np.zeros((3, n))
    for k in range(n):
        e = h * np.eye(n)[k]
        plus, minus = _hand_pose(arm, q + e, frame), _hand_pose(arm, q - e, frame)
        jv[:, k] = (plus - minus)[:3] @ np.r_[point, 1.0] / (2 * h)
        w = (plus[:3, :3] - minus[:3, :3]) / (2 * h) @ rot.T
        jw[:, k] = w[2, 1], w[0, 2], w[1, 0]
    return rot, jv, jw


@pytest.mark.parametrize("frame", [None, "on_link3"])
def test_payload_is_a_body_given_in_the_frames_axes(frame: str | None) -> None:
    """with_payload(m, c, I, frame): a rigid body with its com c and inertia I about it in the axes of a
    rotated frame (default: the tool). It adds m J_vᵀJ_v + J_ωᵀ R I Rᵀ J_ω to M and −m J_vᵀ g₀ to the gravity
    torque, J_v of the com's world position, J_ω and R of the frame, from the pose composed by hand."""
    arm = _arm()
    mass, com = 1.3, np.array([0.08, -0.05, 0.12])
    r = Rotation.from_rotvec([0.3, -0.5, 0.8]).as_matrix()
    inertia = r @ np.diag([0.004, 0.006, 0.008]) @ r.T
    heavy = arm.with_payload(mass, com, inertia, frame=frame)
    q = np.array([0.4, -0.7, 0.12, 1.1, -0.5])
    rot, jv, jw = _frame_jacobians(arm, q, frame or "tool", com)
    d0, d1 = armctl.Dynamics(arm), armctl.Dynamics(heavy)
    np.testing.assert_allclose(
        d1.mass_matrix(q) - d0.mass_matrix(q), mass * jv.T @ jv + jw.T @ rot @ inertia @ rot.T @ jw, rtol=0, atol=1e-8
    )
    np.testing.assert_allclose(
        d1.gravity_torque(q) - d0.gravity_torque(q), -mass * jv.T @ arm.gravity, rtol=0, atol=1e-8
    )


def test_with_parameters_keeps_static_friction_only_above_both_new_levels() -> None:
    """model_from_parameters' docstring: static friction is kept where it stays above the new Coulomb levels
    and dropped otherwise (not an error). New levels F̄_c (1 ± ρ), ρ = (F_c⁺ − F_c⁻)/(F_c⁺ + F_c⁻) the model's:
    joint 1 (ρ = ½, F̄_c = 1.5) 2.25/0.75 and joint 2 (ρ = −½) 0.75/2.25 straddle the static 2.0; joint 3
    (ρ = ½, F̄_c = 1.2) 1.8/0.6 stays below it."""
    base = armctl.models.planar_3r().with_friction(
        coulomb=[1.5, 0.5, 1.5], coulomb_negative=[0.5, 1.5, 0.5], static=2.0
    )
    pi = base.parameters().copy()
    pi[[12, 25, 38]] = 1.5, 1.5, 1.2
    new = [j.friction for j in base.with_parameters(pi).joints]
    want = [(2.25, 0.75, None), (0.75, 2.25, None), (1.8, 0.6, 2.0)]
    for f, (pos, neg, static) in zip(new, want, strict=True):
        assert math.isclose(f.coulomb, pos, rel_tol=1e-12) and math.isclose(f.coulomb_neg, neg, rel_tol=1e-12)
        assert f.static == static


@pytest.mark.parametrize(
    "kwargs",
    [
        {"viscous": [1.0, 2.0, 3.0]},
        {"coulomb": [[1.0, 2.0]]},
        {"static": [5.0]},
        {"stribeck_velocity": np.zeros((2, 2))},
    ],
)
def test_with_friction_wrong_length_is_a_shape_error(kwargs: dict) -> None:
    (arg,) = kwargs
    with pytest.raises(ShapeError, match=rf"with_friction\(\): {arg} must be a scalar or an \(2,\) vector"):
        armctl.models.planar_2r().with_friction(**kwargs)


def test_with_friction_bad_values() -> None:
    m = armctl.models.planar_2r()
    with pytest.raises(InvalidParameterError, match="coulomb must hold real numbers, got 'high'"):
        m.with_friction(coulomb="high")
    with pytest.raises(ArmctlError, match="viscous"):
        m.with_friction(viscous=[0.5, -1.0])
    f = m.with_friction(viscous=[0.5, 0.25], coulomb=2.0)
    assert [j.friction.viscous for j in f.joints] == [0.5, 0.25]
    assert [j.friction.coulomb for j in f.joints] == [2.0, 2.0]


def test_fingerprint_keys_generated_code_not_friction() -> None:
    """What the docstring says: friction and (with inertial=False) inertial parameters are not covered, the
    kinematics, gravity, motors and tool frame are."""
    m = armctl.models.planar_3r()
    k = m.fingerprint(inertial=False)
    assert m.with_friction(viscous=2.0, coulomb=1.0).fingerprint() == m.fingerprint()
    assert m.with_payload(1.0).fingerprint(inertial=False) == k
    assert m.perturbed(mass=1.3, rotor=0.5).fingerprint(inertial=False) == k
    assert m.with_payload(1.0).fingerprint() != m.fingerprint()
    assert m.reduced(lock={"joint2": 0.3}).fingerprint(inertial=False) != k
    assert replace(m, gravity=np.array([0.0, -9.81, 0.0])).fingerprint(inertial=False) != k
    assert replace(m, tool_frame="joint3").fingerprint(inertial=False) != k
    # code of joint-space terms only (compiled dynamics, compiled simulator step) does not depend on the tool frame
    assert replace(m, tool_frame="joint3").fingerprint(tool=False) == m.fingerprint(tool=False)
    assert m.with_payload(1.0).fingerprint(tool=False) != m.fingerprint(tool=False)
