"""Standard closed-loop scenes, each modelling no more than it needs: ``pendulum``, ``planar_2r``,
``panda_topp``, ``panda_contact``, the interaction scenes ``panda_press`` and ``panda_wipe``, and
``panda_collision``. ``scene(name)`` builds one; ``SCENES`` lists them."""

from __future__ import annotations

from collections.abc import Callable

from armctl.errors import UnknownNameError
from armctl.scenes.base import JOINT_METHODS, Scene
from armctl.scenes.interaction import InteractionScene, normal_force
from armctl.scenes.joint_scenes import pendulum, planar_2r
from armctl.scenes.panda_collision import CollisionScene, panda_collision
from armctl.scenes.panda_contact import ContactScene, PressAndSlide, panda_contact
from armctl.scenes.panda_press import PressScene, panda_press
from armctl.scenes.panda_topp import panda_topp
from armctl.scenes.panda_wipe import WipeScene, panda_wipe

#: The standard scenes by name, each a function that builds it (:func:`scene` calls it).
SCENES: dict[str, Callable[[], Scene]] = {
    "pendulum": pendulum,
    "planar_2r": planar_2r,
    "panda_topp": panda_topp,
    "panda_contact": panda_contact,
    "panda_press": panda_press,
    "panda_wipe": panda_wipe,
    "panda_collision": panda_collision,
}


def scene(name: str) -> Scene:
    """A standard scene by name.

    Parameters
    ----------
    name : str
        One of :data:`SCENES`.

    Returns
    -------
    Scene

    Raises
    ------
    UnknownNameError
        Another name (the error lists them).
    """
    if name not in SCENES:
        raise UnknownNameError("scene", name, tuple(SCENES))
    return SCENES[name]()


__all__ = [
    "JOINT_METHODS",
    "SCENES",
    "CollisionScene",
    "ContactScene",
    "InteractionScene",
    "PressAndSlide",
    "PressScene",
    "Scene",
    "WipeScene",
    "normal_force",
    "panda_collision",
    "panda_contact",
    "panda_press",
    "panda_topp",
    "panda_wipe",
    "pendulum",
    "planar_2r",
    "scene",
]
