"""The recursive algorithms of :mod:`armctl.dynamics.recursive` (CasADi SX, evaluated here by CasADi's virtual
machine) against Pinocchio's RNEA, CRBA and ABA — a second implementation, written by others — on every
built-in arm and on a hand-made arm with a prismatic joint, tilted placements and axes along no frame axis."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import armctl
from armctl.dynamics import recursive
from armctl.model.parts import Frame, Joint, Link, Motor


def _placement(rpy: tuple[float, float, float], xyz: tuple[float, float, float]) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3] = pin.rpy.rpyToMatrix(*rpy)
    t[:3, 3] = xyz
    return t


def skewed_rpr() -> armctl.RobotModel:
    """Revolute–prismatic–revolute arm with tilted placements, axes along no frame axis, off-axis centres of
    mass, full inertia tensors and armatures."""
    link = [
        Link(1.5, (0.1, -0.05, 0.2), np.array([[0.04, 0.002, -0.001], [0.002, 0.05, 0.003], [-0.001, 0.003, 0.03]])),
        Link(0.8, (0.02, 0.03, -0.1), np.diag([0.01, 0.02, 0.015])),
        Link(0.5, (0.0, 0.08, 0.05), np.array([[0.006, 0.0, 0.001], [0.0, 0.005, 0.0], [0.001, 0.0, 0.004]])),
    ]
    joints = (
        Joint(
            "j1",
            "revolute",
            (0.0, 0.6, 0.8),
            _placement((0.1, -0.2, 0.3), (0.0, 0.0, 0.3)),
            link[0],
            motor=Motor(2e-4, 50.0, gyroscopic=False),
        ),
        Joint("j2", "prismatic", (0.48, 0.6, 0.64), _placement((0.5, 0.0, -0.4), (0.2, 0.1, 0.0)), link[1]),
        Joint(
            "j3",
            "revolute",
            (1.0, 0.0, 0.0),
            _placement((0.0, 0.7, 0.2), (0.0, 0.3, 0.1)),
            link[2],
            motor=Motor(1e-4, 30.0, gyroscopic=False),
        ),
    )
    return armctl.RobotModel(joints, name="skewed_rpr", frames=(Frame("tool", 3, np.eye(4)),), tool_frame="tool")


def _value(fn, *args: np.ndarray) -> np.ndarray:
    """A CasADi function's value (CasADi's virtual machine, nothing compiled), as NumPy; a vector raveled."""
    out = np.array(fn(*args))
    return out if fn.name() == "M" else out.ravel()


MODELS = {
    "pendulum": armctl.models.pendulum,
    "planar_2r": armctl.models.planar_2r,
    "planar_3r": armctl.models.planar_3r,
    "puma560": armctl.models.puma560,
    "panda": armctl.models.panda,
    "ur5": armctl.models.ur5,
    "skewed_rpr": skewed_rpr,
}


@pytest.mark.parametrize("name", list(MODELS))
def test_recursions_agree_with_pinocchio(name: str) -> None:
    model = MODELS[name]()
    if name != "skewed_rpr":  # the built-ins' rotors as armatures: the model Pinocchio expresses
        model = model.reduced(friction=False)
    pm = model.to_pinocchio()
    pd = pm.createData()
    fns = recursive.functions(model)
    rng = np.random.default_rng(11)
    for _ in range(4):
        q, qd, qdd = rng.uniform(-2.0, 2.0, (3, model.n))
        tau = pin.rnea(pm, pd, q, qd, qdd).copy()
        np.testing.assert_allclose(_value(fns["tau"], q, qd, qdd), tau, rtol=1e-11, atol=1e-11 * np.abs(tau).max())
        mass = pin.crba(pm, pd, q).copy()
        mass = np.triu(mass) + np.triu(mass, 1).T  # Pinocchio fills the upper triangle
        np.testing.assert_allclose(_value(fns["M"], q), mass, rtol=1e-11, atol=1e-11 * np.abs(mass).max())
        np.testing.assert_allclose(
            _value(fns["qdd"], q, qd, tau), pin.aba(pm, pd, q, qd, tau), rtol=1e-9, atol=1e-9 * np.abs(qdd).max()
        )


def test_recursions_take_the_gyroscopic_rotor_as_its_armature_only() -> None:
    """A motor with ``gyroscopic=True`` enters as k_r²I_m on M's diagonal, as in the 'pinocchio' backend."""
    model = armctl.models.planar_2r()
    assert any(j.motor is not None and j.motor.gyroscopic and j.motor.inertia > 0 for j in model.joints)
    dyn = armctl.Dynamics(model)
    q = np.array([0.4, -1.1])
    np.testing.assert_allclose(_value(recursive.functions(model)["M"], q), dyn.mass_matrix(q), rtol=1e-12)
