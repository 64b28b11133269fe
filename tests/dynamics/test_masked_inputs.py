"""A masked array is not read through its mask: a masked entry is refused by name (before, the regressors and
the inverse dynamics used the hidden value)."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.errors import InvalidParameterError


def _masked() -> np.ma.MaskedArray:
    return np.ma.masked_array([0.1, 1e6], mask=[False, True])  # the hidden entry would be a wild value


@pytest.mark.parametrize("method", ["regressor", "passivity_regressor", "passivity_torque", "inverse_dynamics"])
def test_the_dynamics_refuse_a_masked_entry(method: str) -> None:
    dyn = armctl.Dynamics(armctl.models.planar_2r())
    z = np.zeros(2)
    args = [z] * (4 if method.startswith("passivity") else 3)
    args[1] = _masked()
    with pytest.raises(InvalidParameterError, match=r"^qd has masked entries"):
        getattr(dyn, method)(*args)
