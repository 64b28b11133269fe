"""The built-in arms: ``armctl.models.pendulum()``, ``planar_2r()``, ``planar_3r()``, ``puma560()``,
``panda()``, ``ur5()``. See :mod:`armctl.model.library` for what each one models."""

from armctl.model.library import panda, pendulum, planar_2r, planar_3r, puma560, robot_description, ur5

__all__ = ["panda", "pendulum", "planar_2r", "planar_3r", "puma560", "robot_description", "ur5"]
