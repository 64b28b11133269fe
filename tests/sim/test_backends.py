"""The simulator on both Dynamics backends: with no rotors (where both express the same model) a scene with
stick–slip friction and a wall gives the same trajectory whether Pinocchio or the CasADi Lagrange
formulation evaluates the plant — which also checks the simulator's generic (non-Pinocchio) paths."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.sim import Forces, KelvinVoigt, Plane, simulate
from tests.sim.helpers import PDGravity


@pytest.mark.parametrize("integrator", ["rk4", "semi-implicit-euler", "implicit-euler"])
def test_pinocchio_and_lagrange_plants_give_the_same_run(integrator: str) -> None:
    model = armctl.models.planar_2r().reduced(rotors=False).with_friction(viscous=5.0, coulomb=20.0, static=30.0)
    ctrl = PDGravity(armctl.Dynamics(model.reduced(friction=False)), 2000.0, 300.0)
    wall = Plane(KelvinVoigt(1e5, 1e3), normal=(-1.0, 0.0, 0.0), point=(1.6, 0.0, 0.0), friction=0.3)
    runs = [
        simulate(
            armctl.Dynamics(model, backend=b),
            ctrl,
            armctl.Reference.hold([0.4, -0.2]),
            0.5,
            q0=[1.0, -0.5],
            integrator=integrator,
            forces=Forces(environment=wall),
        )
        for b in ("pinocchio", "lagrange")
    ]
    assert runs[0].contact_force_on_environment[:, 0, 0].max() > 1000.0 and runs[0].info["stick_events"] > 0
    np.testing.assert_allclose(runs[1].q, runs[0].q, atol=1e-10)
    np.testing.assert_allclose(runs[1].contact_force_on_environment, runs[0].contact_force_on_environment, atol=1e-6)
    np.testing.assert_allclose(runs[1].energy, runs[0].energy, atol=1e-8)
