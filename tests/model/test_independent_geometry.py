"""Model geometry against hand-written products and scipy's rotations (mutations of each survived the suite:
the inertia rotated as RᵀIR, the modified-DH offset's sign, the tool applied before the last link frame)."""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial.transform import Rotation

import armctl
from armctl.model.consistency import is_physical
from armctl.model.dh import DHLink


def _rx(a: float) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3] = Rotation.from_euler("x", a).as_matrix()
    return t


def _rz(a: float) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3] = Rotation.from_euler("z", a).as_matrix()
    return t


def _tr(x: float = 0.0, z: float = 0.0) -> np.ndarray:
    t = np.eye(4)
    t[0, 3], t[2, 3] = x, z
    return t


LINKS = [
    DHLink(d=0.3, a=0.4, alpha=0.7, offset=0.3, mass=2.0, com=(-0.1, 0.02, 0.03), inertia=(0.05, 0.02, 0.04)),
    DHLink(d=-0.1, a=0.25, alpha=-0.4, offset=-0.5, mass=1.0, com=(0.05, 0.0, 0.01), inertia=(0.01, 0.02, 0.015)),
]
TOOL = _rx(0.4) @ _tr(x=0.05, z=0.12)
Q = np.array([0.6, -0.9])


def test_standard_dh_tool_pose_is_the_written_product() -> None:
    # Corke's standard DH: A_i = Rz(θ_i + offset) Tz(d) Tx(a) Rx(α), then the tool
    model = armctl.RobotModel.from_dh(LINKS, tool=TOOL)
    want = np.eye(4)
    for link, q in zip(LINKS, Q, strict=True):
        want = want @ _rz(q + link.offset) @ _tr(z=link.d) @ _tr(x=link.a) @ _rx(link.alpha)
    np.testing.assert_allclose(armctl.Dynamics(model).frame_pose(Q), want @ TOOL, atol=1e-12)


def test_modified_dh_tool_pose_is_the_written_product() -> None:
    # Craig's modified DH: A_i = Rx(α_{i−1}) Tx(a_{i−1}) Rz(θ_i + offset) Tz(d_i), then the tool
    model = armctl.RobotModel.from_dh(LINKS, convention="modified", tool=TOOL)
    want = np.eye(4)
    for link, q in zip(LINKS, Q, strict=True):
        want = want @ _rx(link.alpha) @ _tr(x=link.a) @ _rz(q + link.offset) @ _tr(z=link.d)
    np.testing.assert_allclose(armctl.Dynamics(model).frame_pose(Q), want @ TOOL, atol=1e-12)


def test_a_rotated_link_inertia_enters_as_r_i_rt() -> None:
    # one revolute link (standard DH, α = 0.7, offset 0.3) with a full inertia tensor: M = I_zz of the body about
    # the joint axis, from the link frame's rotation R (scipy) as zᵀ R I Rᵀ z plus m·(distance of the com)²
    link = DHLink(
        a=0.3, alpha=0.7, offset=0.3, mass=2.0, com=(-0.1, 0.05, 0.02), inertia=(0.05, 0.01, -0.004, 0.03, 0.006, 0.04)
    )
    model = armctl.RobotModel.from_dh([link], gravity=(0.0, 0.0, 0.0))
    q = 0.4
    frame = _rz(q + 0.3) @ _tr(x=0.3) @ _rx(0.7)  # the link frame in the base
    rot, com = frame[:3, :3], (frame @ np.r_[link.com, 1.0])[:3]
    xx, xy, xz, yy, yz, zz = 0.05, 0.01, -0.004, 0.03, 0.006, 0.04
    inertia = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    z = np.array([0.0, 0.0, 1.0])
    want = z @ rot @ inertia @ rot.T @ z + 2.0 * (com[0] ** 2 + com[1] ** 2)
    assert math.isclose(float(armctl.Dynamics(model).mass_matrix([q])[0, 0]), want, rel_tol=1e-12)


def test_negative_friction_is_not_physical() -> None:
    pi = armctl.models.planar_2r().parameters().copy()
    assert is_physical(pi)
    for col in (11, 12):  # viscous, Coulomb of the first joint
        bad = pi.copy()
        bad[col] = -0.5
        assert not is_physical(bad)
