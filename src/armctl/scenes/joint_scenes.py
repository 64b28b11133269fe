"""The joint-space scenes: ``pendulum`` and ``planar_2r``."""

from __future__ import annotations

from armctl import models
from armctl.references import Quintic, Sinusoid
from armctl.scenes.base import Scene


def pendulum() -> Scene:
    """The geared single joint swinging through a minimum-jerk move and back. The plant has viscous and
    Coulomb friction with stiction; the exact model knows the friction (kinetic part), the reduced one
    drops rotor and friction — what a controller tuned on the link alone believes.

    Returns
    -------
    Scene
    """
    plant = models.pendulum().with_friction(viscous=0.05, coulomb=0.3, static=0.45)
    move = Quintic([0.0], [1.2], 1.5, t0=0.2)
    back = Quintic([1.2], [0.0], 1.5, t0=2.2)

    def reference(t: float):
        return move(t) if t < 2.2 else back(t)

    return Scene(
        "pendulum",
        "geared single joint: out-and-back minimum-jerk move with stick–slip friction",
        plant=plant,
        exact=plant,
        reduced=plant.reduced(rotors=False, friction=False),
        reference=reference,
        duration=4.0,
    )


def planar_2r(payload: float = 10.0) -> Scene:
    """Siciliano's two-link arm tracking sinusoids while carrying a ``payload`` [kg] at the tool. The exact
    model (pd_gravity, computed_torque, passivity) knows it; the reduced model, the nominal arm without it, is
    what computed_torque_reduced uses and what adaptive starts from and learns the payload.

    Parameters
    ----------
    payload : float, optional
        [kg].

    Returns
    -------
    Scene
    """
    nominal = models.planar_2r()
    plant = nominal.with_payload(payload)
    ref = Sinusoid([0.3, -0.4], [0.4, 0.5], [0.5, 0.7])
    return Scene(
        "planar_2r",
        f"two-link arm tracking sinusoids with a {payload:g} kg payload, unknown to the "
        "reduced model (computed_torque_reduced, adaptive)",
        plant=plant,
        exact=plant,
        reduced=nominal,
        reference=ref,
        duration=5.0,
    )
