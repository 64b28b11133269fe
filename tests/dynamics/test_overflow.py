"""Finite inputs too large for floats are named: the error says which input overflowed, on every method whose
result can overflow (before, kinetic energy, the Coriolis matrix, both regressors and the passivity torque came
back NaN or inf with no error, and a huge wrench was blamed on τ)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import armctl
from armctl.errors import NonFiniteError

BIG = 1e200  # finite; its square is not


def _cases(n: int) -> dict[str, tuple]:
    q, z = np.full(n, 0.3), np.zeros(n)
    big = np.full(n, BIG)
    return {
        "kinetic_energy": ("kinetic_energy", (q, big), "qd"),
        "regressor": ("regressor", (q, big, z), "qd"),
        "passivity_regressor": ("passivity_regressor", (q, big, z, z), "qd"),
        "passivity_torque": ("passivity_torque", (q, big, z, z), "qd"),
        "inverse_dynamics": ("inverse_dynamics", (q, big, z), "qd"),
        "forward_dynamics": ("forward_dynamics", (q, big, z), "qd"),
        "coriolis_matrix": ("coriolis_matrix", (q, np.full(n, 1e307)), "qd"),
    }


@pytest.mark.parametrize(
    ("backend", "options"), [("pinocchio", {}), ("pinocchio", {"compile": True}), ("lagrange", {})]
)
@pytest.mark.parametrize("case", sorted(_cases(2)))
def test_an_overflowing_input_is_named(backend: str, options: dict, case: str) -> None:
    model = armctl.models.planar_2r().with_friction(viscous=0.1, coulomb=0.2)
    dyn = armctl.Dynamics(model, backend=backend, **options)
    method, args, culprit = _cases(dyn.n)[case]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # NumPy may say "overflow" before the named error
        with pytest.raises(NonFiniteError, match=rf"overflowed .*{culprit}\[\d\] = 1e\+\d+ is too large") as info:
            getattr(dyn, method)(*args)
    assert np.array_equal(info.value.value, args[1])


@pytest.mark.parametrize(("backend", "options"), [("pinocchio", {}), ("lagrange", {"compile": True})])
@pytest.mark.parametrize("method", ["inverse_dynamics", "forward_dynamics"])
def test_a_huge_wrench_is_named_not_blamed_on_tau(backend: str, options: dict, method: str) -> None:
    dyn = armctl.Dynamics(armctl.models.planar_2r(), backend=backend, **options)
    q, z, wrench = np.array([0.3, 0.4]), np.zeros(2), np.full(6, 1.7e308)
    with np.errstate(over="ignore", invalid="ignore"):
        assert not np.isfinite(dyn.jacobian(q).T @ wrench).all()  # the premise: Jᵀh overflows
    with pytest.raises(NonFiniteError, match=r"overflowed .*wrench\[\d\] = 1\.7e\+308 is too large"):
        getattr(dyn, method)(q, z, z, wrench=wrench)


def test_large_but_representable_results_are_returned() -> None:
    dyn = armctl.Dynamics(armctl.models.panda())
    q, qd = np.full(7, 0.3), np.full(7, 1e120)  # quadratic terms ~1e240: finite
    y = dyn.regressor(q, qd, np.zeros(7))
    assert np.isfinite(y).all() and np.abs(y).max() > 1e200
    assert np.isfinite(dyn.kinetic_energy(q, qd))
