"""The built-in arms: ``armctl.models.pendulum()``, ``planar_2r()``, ``planar_3r()``, ``puma560()``,
``panda()``, ``ur5()``, and the Puma's named poses ``PUMA_QZ``, ``PUMA_QR``, ``PUMA_QN``. See
:mod:`armctl.model.library` for what each one models."""

from armctl.model.library import (
    PUMA_QN,
    PUMA_QR,
    PUMA_QZ,
    panda,
    pendulum,
    planar_2r,
    planar_3r,
    puma560,
    robot_description,
    ur5,
)

__all__ = [
    "PUMA_QN",
    "PUMA_QR",
    "PUMA_QZ",
    "panda",
    "pendulum",
    "planar_2r",
    "planar_3r",
    "puma560",
    "robot_description",
    "ur5",
]
