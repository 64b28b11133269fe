"""Paths: interpolation, derivatives against finite differences, chord-length knots, input checks."""

from __future__ import annotations

import numpy as np
import pytest

from armctl.errors import ArmctlError, InvalidParameterError, NonFiniteError, ShapeError
from armctl.planning import LinePath, SplinePath
from tests.planning.helpers import PANDA_WAYPOINTS


def test_spline_passes_through_waypoints_at_chord_length_knots() -> None:
    path = SplinePath(PANDA_WAYPOINTS)
    steps = np.linalg.norm(np.diff(PANDA_WAYPOINTS, axis=0), axis=1)
    expected = np.concatenate(([0.0], np.cumsum(steps) / steps.sum()))
    np.testing.assert_allclose(path.breakpoints, expected, atol=1e-15)
    np.testing.assert_allclose(path(path.breakpoints), PANDA_WAYPOINTS, atol=1e-12)
    assert path(0.5).shape == (7,)


@pytest.mark.parametrize("bc_type", ["not-a-knot", "natural", "clamped"])
def test_spline_derivatives_match_finite_differences(bc_type: str) -> None:
    path = SplinePath(PANDA_WAYPOINTS, bc_type=bc_type)
    s = np.linspace(0.05, 0.95, 37)
    h = 1e-5
    q, dq, ddq = path.derivatives(s)
    np.testing.assert_allclose(dq, (path(s + h) - path(s - h)) / (2 * h), atol=1e-6)
    np.testing.assert_allclose(ddq, (path(s + h, 1) - path(s - h, 1)) / (2 * h), atol=1e-5)
    np.testing.assert_allclose(q, path(s), atol=0)


def test_line_path_is_affine() -> None:
    a, b = np.array([0.1, -0.2, 0.3]), np.array([1.0, 0.5, -0.7])
    path = LinePath(a, b)
    s = np.array([0.0, 0.25, 1.0])
    np.testing.assert_allclose(path(s), a + s[:, None] * (b - a))
    np.testing.assert_allclose(path(s, 1), np.tile(b - a, (3, 1)))
    np.testing.assert_allclose(path(s, 2), 0.0)


def test_two_waypoints_give_the_straight_line() -> None:
    a, b = np.array([0.1, -0.2]), np.array([1.0, 0.5])
    s = np.linspace(0, 1, 11)
    np.testing.assert_allclose(SplinePath([a, b])(s), LinePath(a, b)(s), atol=1e-12)


@pytest.mark.parametrize(
    ("waypoints", "error"),
    [
        (np.zeros(7), ShapeError),  # a single configuration
        (np.zeros((1, 7)), ShapeError),  # one waypoint
        (np.array([[0.0, np.nan], [1.0, 1.0]]), NonFiniteError),  # NaN
        (np.array([[0.0, 0.0], [0.0, 0.0], [1.0, 1.0]]), InvalidParameterError),  # repeated waypoint
    ],
)
def test_bad_waypoints_raise(waypoints: np.ndarray, error: type[ArmctlError]) -> None:
    with pytest.raises(error):
        SplinePath(waypoints)


def test_bad_parameters_raise() -> None:
    path = SplinePath(PANDA_WAYPOINTS)
    with pytest.raises(InvalidParameterError):
        path(1.5)
    with pytest.raises(NonFiniteError):
        path(np.nan)
    with pytest.raises(InvalidParameterError):
        path(0.5, order=3)
    with pytest.raises(InvalidParameterError):
        SplinePath(PANDA_WAYPOINTS, bc_type="periodic-ish")
    with pytest.raises(InvalidParameterError):
        SplinePath(PANDA_WAYPOINTS, knots=[0.0, 0.5, 0.4, 0.8, 1.0])
    with pytest.raises(InvalidParameterError):
        LinePath([1.0, 2.0], [1.0, 2.0])
