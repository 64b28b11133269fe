"""Model parameters that overflow are refused by name: a DH link of 1e308 kg used to build, and its π then
held inf (m·c and the inertia about the joint origin overflow); a payload of 1e308 kg gave a model whose weight
is inf; a rotor of 1e200 kg·m² behind a 1e60 gear a reflected inertia of inf."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.errors import InvalidParameterError
from armctl.model import DHLink, Link, Motor


def test_a_dh_link_whose_parameters_overflow_is_refused() -> None:
    links = [DHLink(a=0.5, mass=1.0), DHLink(a=2.0, mass=1e308, name="forearm")]
    with pytest.raises(
        InvalidParameterError,
        match=r"^DH row 1 \(forearm\), its body in the joint frame: link mass 1e\+308 kg with com \[2\.0, 0\.0, 0\.0\]"
        r" m overflows its parameters \(first moment m·c = \[inf",
    ):
        armctl.RobotModel.from_dh(links)


def test_a_link_whose_moments_overflow_is_refused() -> None:
    """m·c = 1e260 is finite, the inertia about the joint origin m|c|² = 1e320 is not."""
    with pytest.raises(
        InvalidParameterError, match=r"^link mass 1e\+200 kg with com \[1e\+60, 0\.0, 0\.0\] m overflows its parameters"
    ):
        Link(1e200, com=(1e60, 0.0, 0.0))


def test_a_rotor_whose_reflected_inertia_overflows_is_refused() -> None:
    with pytest.raises(InvalidParameterError, match=r"^rotor inertia 1e\+200 kg·m² and gear ratio 1e\+60 overflow"):
        Motor(1e200, 1e60)


def test_a_model_whose_weight_overflows_is_refused() -> None:
    """π of a 1e308 kg payload is finite, but the payload's weight is not: every gravity torque would be inf."""
    arm = armctl.models.planar_2r()
    assert np.isfinite(arm.parameters()).all()
    with pytest.raises(
        InvalidParameterError,
        match=r"^joint 'joint2': its link \(1e\+308 kg, centre of mass up to .* m from the joint axes\) overflows the "
        r"dynamics: gravity torques up to inf N·m",
    ):
        arm.with_payload(1e308)


def test_large_finite_models_still_build_and_evaluate() -> None:
    """The bounds refuse only what overflows: a 1e150 kg link builds, and its dynamics are finite and match the
    closed form of a point mass on a rod, M = m a² (about z, gravity along −z: no weight torque)."""
    m = armctl.RobotModel.from_dh([DHLink(a=2.0, mass=1e150)])
    assert np.isfinite(m.parameters()).all()
    dyn = armctl.Dynamics(m)
    np.testing.assert_allclose(dyn.mass_matrix([0.3]), [[1e150 * 2.0**2]], rtol=1e-12)
    assert Link(1e300, com=(1.0, 0.0, 0.0)).mass == 1e300
