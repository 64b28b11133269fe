"""The built-in arms, ready to use: ``armctl.models.pendulum()``, ``planar_2r()``, ``planar_3r()``,
``puma560()``, ``panda()``, ``ur5()`` (each returns a :class:`~armctl.model.RobotModel`), the Puma's named poses
``PUMA_QZ``, ``PUMA_QR``, ``PUMA_QN``, and :func:`robot_description` (a file shipped by example-robot-data).

This is the public name of the built-in arms. They are defined in one place, :mod:`armctl.model.library`
(which says what each one models), next to the parts they are made of; :mod:`armctl.model` (singular) holds
those parts — :class:`~armctl.model.RobotModel`, ``Link``, ``Motor``, ``Joint``, ... — to describe an arm of
your own."""

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
