"""A masked array is not read through its mask: a masked entry is refused by name by the dynamics' regressors
and by every controller (before, the hidden value was used, and with ``ki=`` or ``Adaptive`` a bare TypeError
came from the controller's base class)."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.controllers import Adaptive, ComputedTorque, PassivityBased, PDGravity
from armctl.errors import InvalidParameterError

CONTROLLERS = {
    "ComputedTorque": lambda d: ComputedTorque(d, 100.0, 20.0),
    "PDGravity": lambda d: PDGravity(d, 100.0, 20.0),
    "PDGravity(ki=)": lambda d: PDGravity(d, 100.0, 20.0, ki=10.0),
    "PassivityBased": lambda d: PassivityBased(d, 5.0, 20.0),
    "Adaptive": lambda d: Adaptive(d, 5.0, 20.0, 0.1),
}


def _masked() -> np.ma.MaskedArray:
    return np.ma.masked_array([0.1, 1e6], mask=[False, True])  # the hidden entry would be a wild value


@pytest.mark.parametrize("make", sorted(CONTROLLERS))
@pytest.mark.parametrize("position", ["q", "qd"])
def test_controllers_refuse_a_masked_entry(make: str, position: str) -> None:
    dyn = armctl.Dynamics(armctl.models.planar_2r())
    ctrl = CONTROLLERS[make](dyn)
    z = np.zeros(2)
    args = {"q": z, "qd": z, position: _masked()}
    with pytest.raises(InvalidParameterError, match=rf"^{position} has masked entries"):
        ctrl(0.0, args["q"], args["qd"], armctl.Reference(z, z, z))
