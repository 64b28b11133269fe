"""`ContactForceTask`: regulate the force of a declared contact.

    r = f − f_ref   (on the contact's force variables, world axes)

f is the force of the environment on the robot (see :class:`~armctl.controllers.osc.contact.Contact`): to
press on a table with 10 N, ask for f_ref = (0, 0, 10). A weight of 0 on a row leaves that component free.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, vector
from armctl.controllers.osc.contact import Contact
from armctl.controllers.osc.state import ModelState
from armctl.controllers.osc.tasks.base import Task
from armctl.errors import InvalidParameterError, UnknownNameError
from armctl.reference import Reference


class ContactForceTask(Task):
    """Force of ``contact`` [N] towards ``force``: a (3,) vector or a callable t -> (3,)."""

    identity_jacobian = True

    def __init__(self, contact: Contact, force: ArrayLike | Callable[[float], ArrayLike] = (0.0, 0.0, 0.0),
                 weight: ArrayLike = 1e-3, priority: int = 0, name: str | None = None) -> None:
        if not isinstance(contact, Contact):
            raise InvalidParameterError(f"contact must be an osc.Contact, got {type(contact).__name__}",
                                        value=contact)
        super().__init__(contact.dim, name or f"force[{contact.name}]", weight, priority)
        self.contact = contact
        self.variable = contact.name
        self.set_target(force)

    def set_target(self, force: ArrayLike | Callable[[float], ArrayLike]) -> None:
        """Desired contact force [N]: a vector, or a callable of t [s] returning one."""
        if callable(force):
            self._fn: Callable[[float], ArrayLike] | None = force
        else:
            self._fn = None
            self._force = vector(force, self.dim, f"{self.name}: force")

    def target(self, t: float) -> FloatArray:
        return vector(self._fn(t), self.dim, f"{self.name}: force") if self._fn is not None else self._force

    def check(self, evaluator: object, n: int, contacts: dict[str, int]) -> None:
        if self.contact.name not in contacts:
            raise UnknownNameError("contact", self.contact.name, list(contacts))

    def residual(self, state: ModelState, t: float, ref: Reference) -> tuple[None, FloatArray]:
        return None, np.array(self.target(t), dtype=float)
