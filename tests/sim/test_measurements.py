"""What the controller is given in `simulate`: read-only measurements, reproducible noise, delays."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.controllers import PDGravity
from armctl.controllers.base import Controller
from armctl.errors import InvalidParameterError, SimulationWarning
from armctl.sim import Sensing
from armctl.sim.options import regroup


class _Subtracts(Controller):
    """Writes into its q: e = q − q_d in place."""

    def compute(self, t, q, qd, ref):  # type: ignore[no-untyped-def]
        q -= ref.q
        return -20.0 * q - 3.0 * qd


@pytest.mark.parametrize("options", [{}, {"noise_q": 1e-6, "seed": 0}, {"delay": 2}])
def test_a_controller_writing_into_its_measurements_gets_a_named_error(options: dict) -> None:
    # without noise or delay it got a bare numpy "output array is read-only"; with them, copies it could
    # change: the same rule now, read-only views, whatever the options
    dyn = armctl.Dynamics(armctl.models.pendulum())
    with pytest.raises(InvalidParameterError, match=r"wrote into a read-only array at t = 0 s .*\(q = q\.copy\(\)\)"):
        armctl.simulate(dyn, _Subtracts(dyn), armctl.Reference([0.1]), 0.01, **regroup(options))


def test_a_noisy_run_without_a_seed_records_the_one_it_drew() -> None:
    dyn = armctl.Dynamics(armctl.models.pendulum())
    ctrl = PDGravity(dyn, 50.0, 5.0)
    a = armctl.simulate(dyn, ctrl, armctl.Reference([0.1]), 0.05, sensing=Sensing(noise_q=1e-3))
    b = armctl.simulate(dyn, ctrl, armctl.Reference([0.1]), 0.05, sensing=Sensing(noise_q=1e-3, seed=a.info["seed"]))
    c = armctl.simulate(dyn, ctrl, armctl.Reference([0.1]), 0.05, sensing=Sensing(noise_q=1e-3))
    assert isinstance(a.info["seed"], int) and a.info["seed"] != c.info["seed"]
    np.testing.assert_array_equal(a.q_measured, b.q_measured)
    assert not np.array_equal(a.q_measured, c.q_measured)


def test_a_delay_as_long_as_the_run_is_warned_about() -> None:
    dyn = armctl.Dynamics(armctl.models.pendulum())
    with pytest.warns(SimulationWarning, match="sees only the first measurement"):
        armctl.simulate(dyn, PDGravity(dyn, 50.0, 5.0), armctl.Reference([0.1]), 0.01, sensing=Sensing(delay=10))


@pytest.mark.parametrize("n", [2.7, "2", True, -1, 0])
def test_a_controller_without_dynamics_needs_a_whole_number_of_joints(n: object) -> None:
    class Free(Controller):
        def compute(self, t, q, qd, ref):  # type: ignore[no-untyped-def]
            return -qd

    with pytest.raises(InvalidParameterError, match="n \\(the number of joints\\) must be a whole number >= 1"):
        Free(n=n)  # type: ignore[arg-type]
    assert Free(n=3.0).n == 3  # type: ignore[arg-type]
