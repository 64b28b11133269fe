"""Evaluation of the Lagrange model: :class:`Dynamics` and its two backends."""

from armctl.dynamics.base import BACKENDS, Dynamics

__all__ = ["BACKENDS", "Dynamics"]
