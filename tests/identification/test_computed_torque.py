"""Computed torque with the identified model tracks better than with the nominal perturbed model it
started from.

The plant is the true Puma 560 (published parameters, asymmetric Coulomb friction with stick–slip in the
simulator); both controllers use the same gains and the same fresh trajectory.
"""

from __future__ import annotations

import numpy as np

import armctl
from armctl.controllers import ComputedTorque
from armctl.sim import simulate
from tests.identification._cases import Case


def test_identified_model_tracks_better_than_the_nominal_one(puma_case: Case) -> None:
    traj = puma_case.validation
    errors = {}
    for name, model in (
        ("identified", puma_case.result.identified_model),
        ("nominal", puma_case.nominal),
        ("truth", puma_case.truth),
    ):
        controller = ComputedTorque(armctl.Dynamics(model), kp=25.0, kd=10.0)
        res = simulate(puma_case.truth, controller, traj, 4.0, control_dt=1e-3)
        assert not res.diverged, name
        e = res.q - traj.evaluate(res.t)[0]
        errors[name] = np.sqrt((e**2).mean(axis=0))
    ident, nominal, truth = errors["identified"], errors["nominal"], errors["truth"]
    msg = {k: np.round(v, 5) for k, v in errors.items()}
    assert np.linalg.norm(ident) < 0.5 * np.linalg.norm(nominal), msg
    assert np.all(ident < nominal), msg
    # and as well as a controller that knows the true model (friction stiction aside, which neither models)
    assert np.linalg.norm(ident) <= 1.25 * np.linalg.norm(truth), msg
