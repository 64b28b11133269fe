"""The reference generators: the quintic's end points, midpoint and peak speed 15/8 Δ/T and its derivatives
against finite differences, the sinusoid at its peak, and the waypoint spline through its waypoints and against
scipy's CubicSpline, holding its end points outside the times."""

from __future__ import annotations

import numpy as np
import pytest

from armctl.errors import InvalidParameterError, ShapeError
from armctl.references import Quintic, Sinusoid, WaypointSpline


def test_references() -> None:
    mj = Quintic([0.0, 1.0], [1.0, -1.0], 2.0, t0=1.0)
    assert np.allclose(mj(0.0).q, [0, 1]) and np.allclose(mj(5.0).q, [1, -1])
    mid = mj(2.0)
    assert np.allclose(mid.q, [0.5, 0.0]) and np.allclose(mid.qd, [15 / 16, -15 / 8])  # peak speed 15/8 Δ/T
    h = 1e-6
    for t in (1.3, 2.7):
        assert np.allclose((mj(t + h).q - mj(t - h).q) / (2 * h), mj(t).qd, atol=1e-6)
        assert np.allclose((mj(t + h).qd - mj(t - h).qd) / (2 * h), mj(t).qdd, atol=1e-5)
    sine = Sinusoid([0.0, 0.0], [np.pi / 6, np.pi / 4], 1.0)
    assert np.allclose(sine(0.25).q, [np.pi / 6, np.pi / 4]) and np.allclose(sine(0.25).qd, 0, atol=1e-12)
    sp = WaypointSpline([0, 1, 3], [[0, 0], [1, 2], [0, 1]])
    assert np.allclose(sp(1.0).q, [1, 2]) and np.allclose(sp(0.0).qd, 0) and np.allclose(sp(3.0).qd, 0)
    with pytest.raises(InvalidParameterError, match="increasing"):
        WaypointSpline([0, 0, 1], [[0], [1], [2]])
    with pytest.raises(ShapeError):
        Quintic([0, 0], [1], 1.0)


@pytest.mark.parametrize("bc_type", ["clamped", "natural"])
def test_waypoint_spline_holds_its_end_points_outside_the_times(bc_type: str) -> None:
    """Inside [times[0], times[-1]] the reference is scipy's CubicSpline with the same end conditions (q, q̇, q̈);
    before and after, the first and last waypoints held at rest, q̇ = q̈ = 0 (the class docstring), although the
    clamped spline ends with q̈ ≠ 0 and the natural one with q̇ ≠ 0."""
    from scipy.interpolate import CubicSpline

    times, w = [0.5, 1.5, 3.0], np.array([[0.2, -0.1], [1.0, 2.0], [0.0, 1.0]])
    sp, ref_spline = WaypointSpline(times, w, bc_type=bc_type), CubicSpline(times, w, bc_type=bc_type, axis=0)
    for t in (0.5, 1.2, 2.9, 3.0):
        r = sp(t)
        for got, order in ((r.q, 0), (r.qd, 1), (r.qdd, 2)):
            np.testing.assert_allclose(got, ref_spline(t, order), rtol=1e-12, atol=1e-12)
    assert np.abs(ref_spline(3.0, 1)).max() + np.abs(ref_spline(3.0, 2)).max() > 0.1  # the end does move
    for t, end in ((-1.0, 0), (0.49, 0), (3.01, -1), (10.0, -1)):
        r = sp(t)
        np.testing.assert_allclose(r.q, w[end], rtol=0, atol=1e-12)
        assert not r.qd.any() and not r.qdd.any()
