"""The recursive algorithms of :mod:`armctl.dynamics.recursive` (CasADi SX, evaluated here by CasADi's virtual
machine) against Pinocchio's RNEA, CRBA and ABA — a second implementation, written by others — on every
built-in arm and on a hand-made arm with a prismatic joint, tilted placements and axes along no frame axis."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import armctl
from armctl.dynamics import recursive
from tests.dynamics.helpers import skewed_rpr


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
