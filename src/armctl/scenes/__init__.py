"""Standard closed-loop scenes, each modelling no more than it needs: ``pendulum``, ``planar_2r``,
``panda_topp``, ``panda_contact``. ``scene(name)`` builds one; ``SCENES`` lists them."""

from __future__ import annotations

from collections.abc import Callable

from armctl.errors import UnknownNameError
from armctl.scenes.base import JOINT_METHODS, Scene
from armctl.scenes.joint_scenes import pendulum, planar_2r
from armctl.scenes.panda_contact import ContactScene, PressAndSlide, panda_contact
from armctl.scenes.panda_topp import panda_topp

#: The standard scenes by name, each a function that builds it (:func:`scene` calls it).
SCENES: dict[str, Callable[[], Scene]] = {
    "pendulum": pendulum,
    "planar_2r": planar_2r,
    "panda_topp": panda_topp,
    "panda_contact": panda_contact,
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
    "ContactScene",
    "PressAndSlide",
    "Scene",
    "panda_contact",
    "panda_topp",
    "pendulum",
    "planar_2r",
    "scene",
]
