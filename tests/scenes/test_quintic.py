"""The scenes' minimum-jerk move: the polynomial 10s³ − 15s⁴ + 6s⁵ and its derivatives at points worked out by
hand, held before and after, on floats (floats out) and on arrays."""

from __future__ import annotations

import pytest

from armctl.scenes.base import quintic

#: (s, shape, d shape/ds, d² shape/ds²) of 10s³ − 15s⁴ + 6s⁵
POINTS = [(0.0, 0.0, 0.0, 0.0), (0.25, 0.103515625, 1.0546875, 5.625), (0.5, 0.5, 1.875, 0.0), (1.0, 1.0, 0.0, 0.0)]


@pytest.mark.parametrize(("s", "shape", "rate", "accel"), POINTS)
def test_a_move_on_floats_and_on_arrays(s: float, shape: float, rate: float, accel: float) -> None:
    t0, duration, a, b = 0.5, 2.0, 0.1, -0.3
    on_floats = quintic(a, b, t0, duration)(t0 + s * duration)
    assert all(type(v) is float for v in on_floats)
    want = (a + (b - a) * shape, (b - a) * rate / duration, (b - a) * accel / duration**2)
    assert on_floats == pytest.approx(want, abs=1e-15)
    on_arrays = quintic([a, 2 * a], [b, 2 * b], t0, duration)(t0 + s * duration)
    for got, expected in zip(on_arrays, want, strict=True):
        assert got.shape == (2,)
        assert got == pytest.approx([expected, 2 * expected], abs=1e-15)


def test_held_before_and_after() -> None:
    move = quintic(1.0, 2.0, 1.0, 0.5)
    assert move(0.0) == (1.0, 0.0, 0.0)
    assert move(10.0) == (2.0, 0.0, 0.0)
