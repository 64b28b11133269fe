"""Controllers: ``tau = controller(t, q, qd, ref)``."""

from armctl.controllers.base import Controller

__all__ = ["Controller"]
