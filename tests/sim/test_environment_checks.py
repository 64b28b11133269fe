"""Contact, friction and disturbance parameters at the edges: named errors instead of silent nonsense."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.errors import InvalidParameterError
from armctl.sim import ContactPoint, ForceSensor, HuntCrossley, KelvinVoigt, Plane, simulate
from armctl.sim.friction import SmoothFriction, StickSlip


def test_a_huge_plane_normal_is_normalised_not_lost() -> None:
    """The norm of (1e300, 0, 0) overflows; the plane used to get the normal (0, 0, 0) and no force at all."""
    np.testing.assert_array_equal(Plane(KelvinVoigt(1e4), normal=(1e300, 0.0, 0.0)).normal, [1.0, 0.0, 0.0])
    np.testing.assert_allclose(Plane(KelvinVoigt(1e4), normal=(3e-300, 4e-300, 0.0)).normal, [0.6, 0.8, 0.0])


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: Plane(KelvinVoigt(1e4), normal="abc"), "plane normal must hold real numbers"),
        (lambda: Plane(KelvinVoigt(1e4), point=["a", "b", "c"]), "plane point must hold real numbers"),
        (lambda: Plane(KelvinVoigt(1e4), points=5), "points must be a non-empty sequence of ContactPoint"),
        (lambda: HuntCrossley.from_restitution(1e4, 2.0, 1.0), r"restitution must be in \[0, 1\].*got 2"),
        (lambda: KelvinVoigt(1e3).depth_at(-5.0), "force must be >= 0, got -5"),
        (lambda: HuntCrossley(1e3, exponent=1.5).depth_at(-5.0), "force must be >= 0, got -5"),
        (lambda: ForceSensor(world_axes="no"), "world_axes must be True or False, got 'no'"),
        (lambda: StickSlip(armctl.models.pendulum(), stribeck="no"), "stribeck must be True or False, got 'no'"),
    ],
)
def test_bad_environment_values_are_named(make: object, message: str) -> None:
    with pytest.raises(InvalidParameterError, match=message):
        make()  # type: ignore[operator]


def test_one_contact_point_need_not_be_in_a_list() -> None:
    point = ContactPoint(offset=(0.0, 0.0, 0.1))
    assert Plane(KelvinVoigt(1e4), points=point).points == (point,)


def test_a_tiny_stribeck_velocity_gives_a_finite_friction_slope() -> None:
    """exp(−(q̇/v_s)²) underflows to 0 where q̇/v_s overflows: the slope is then the viscous one, not 0·inf =
    NaN (implicit Euler, which uses it, reported such a run as diverged at t = 0); elsewhere it is the
    derivative of the torque (central differences)."""
    tiny = armctl.models.pendulum().with_friction(viscous=0.05, coulomb=0.3, static=0.45, stribeck_velocity=1e-200)
    sliding = (np.array([0.5]), np.array([1.0]))
    np.testing.assert_array_equal(StickSlip(tiny).slope(*sliding), [0.05])
    np.testing.assert_array_equal(SmoothFriction(tiny).slope(sliding[0]), [0.05])
    res = simulate(
        tiny, lambda t, q, qd, r: np.array([2.0]), armctl.Reference.hold([0.0]), 0.2, integrator="implicit-euler"
    )
    ref = simulate(tiny, lambda t, q, qd, r: np.array([2.0]), armctl.Reference.hold([0.0]), 0.2, integrator="rk4")
    assert not res.diverged and abs(res.q[-1, 0] - ref.q[-1, 0]) < 5e-3  # first order against fourth
    normal = armctl.models.pendulum().with_friction(viscous=0.05, coulomb=0.3, static=0.45, stribeck_velocity=0.1)
    for model in (StickSlip(normal), SmoothFriction(normal)):
        for v in (0.0, 0.03, 0.1, 0.4, -0.2):
            x, d, h = np.array([v]), np.array([1.0 if v >= 0 else -1.0]), 1e-7
            fd = (model.torque(x + h, d) - model.torque(x - h, d)) / (2 * h)
            np.testing.assert_allclose(model.slope(x, d), fd, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("returned", ["abc", {"a": 1.0}, ["1"] * 6, np.array([1j, 0, 0, 0, 0, 0])])
def test_a_disturbance_that_is_not_real_numbers_is_named(returned: object) -> None:
    with pytest.raises(InvalidParameterError, match=r"^disturbance\(t\) at t = 0 s must hold real numbers"):
        simulate(
            armctl.models.planar_2r(),
            lambda t, q, qd, r: np.zeros(2),
            armctl.Reference.hold([0.1, 0.2]),
            0.01,
            disturbance=lambda t: returned,
        )
