"""An arm whose mass matrix is singular (here the second joint moves no inertia at all: a massless last
link, no rotor) cannot have its accelerations computed. Everything that needs M⁻¹ says so by name (the
joint, the model), on both backends, instead of returning NaN or raising a bare LinAlgError."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl import RobotModel
from armctl.controllers.osc import ClosedFormOSC, FramePositionTask
from armctl.errors import InvalidParameterError
from armctl.model import DHLink
from armctl.tuning import linearize

SINGULAR = RobotModel.from_dh([DHLink(a=1.0, mass=1.0, com=(-0.5, 0.0, 0.0)), DHLink(a=1.0, mass=0.0)])
MESSAGE = r"mass matrix of 'dh_robot' is not positive definite at q = .*joint 'joint2' moves the least inertia"


def test_the_model_really_is_singular() -> None:
    m = armctl.Dynamics(SINGULAR).mass_matrix(np.array([0.3, 0.4]))
    assert m[1, 1] == 0.0 and m[0, 1] == 0.0  # nothing for joint 2 to move


@pytest.mark.parametrize("backend", ["pinocchio", "lagrange"])
@pytest.mark.parametrize("friction", [False, True])
def test_forward_dynamics_names_the_singular_mass_matrix(backend: str, friction: bool) -> None:
    model = SINGULAR.with_friction(viscous=0.1) if friction else SINGULAR
    dyn = armctl.Dynamics(model, backend=backend)
    with pytest.raises(InvalidParameterError, match=MESSAGE):
        dyn.forward_dynamics(np.zeros(2), np.zeros(2), np.array([1.0, 1.0]))
    # what does not need M⁻¹ still works
    assert np.isfinite(dyn.inverse_dynamics(np.zeros(2), np.zeros(2), np.ones(2))).all()


@pytest.mark.parametrize("backend", ["pinocchio", "lagrange"])
def test_simulation_linearisation_and_closed_form_osc_name_it(backend: str) -> None:
    dyn = armctl.Dynamics(SINGULAR, backend=backend)
    z = np.zeros(2)
    with pytest.raises(InvalidParameterError, match=MESSAGE):
        armctl.simulate(dyn, lambda t, q, qd, r: z, armctl.Reference(z), 0.01)
    with pytest.raises(InvalidParameterError, match=MESSAGE):
        linearize(dyn, z)
    task = FramePositionTask()
    task.set_target([1.5, 0.2, 0.0])
    with pytest.raises(InvalidParameterError, match=MESSAGE):
        ClosedFormOSC(dyn, task)(0.0, np.array([0.3, 0.4]), z, armctl.Reference(z))
