"""`ContactForceTask`: regulate the force of a declared contact.

    r = f − f_ref                (3 rows, world axes), or
    r = nᵀf − f_n,ref            (1 row, ``normal_only``: the default for a sliding contact, whose tangential
                                  force Coulomb's law already fixes)

f is the force of the environment on the robot (see :class:`~armctl.controllers.osc.contact.Contact`): to
press on a table with 10 N, ask for f_ref = (0, 0, 10), or f_n,ref = 10. A weight of 0 on a row leaves that
component free.
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
from armctl.references import Reference

Force = ArrayLike | float | Callable[[float], ArrayLike]


class ContactForceTask(Task):
    """Force of ``contact`` [N] towards ``force``: a (3,) vector (world axes), or with ``normal_only`` the
    normal force f_n [N] (a scalar; a (3,) vector is projected on the normal); either may be a callable of
    t [s]. ``normal_only`` None: True for a sliding contact, False for a fixed one.

    The force is the one the environment exerts on the robot, so pressing means a positive normal component
    (the contact's normal points from the surface towards the robot): to press on a table with 10 N, ask
    for 10 (or (0, 0, 10)), not −10. A target with a negative normal component (a pull, which a contact
    cannot give) is refused with :class:`~armctl.errors.InvalidParameterError`."""

    def __init__(
        self,
        contact: Contact,
        force: Force = (0.0, 0.0, 0.0),
        weight: ArrayLike = 1e-3,
        priority: int = 0,
        name: str | None = None,
        normal_only: bool | None = None,
    ) -> None:
        if not isinstance(contact, Contact):
            raise InvalidParameterError(f"contact must be an osc.Contact, got {type(contact).__name__}", value=contact)
        self.normal_only = contact.mode == "sliding" if normal_only is None else bool(normal_only)
        self.identity_jacobian = not self.normal_only
        super().__init__(1 if self.normal_only else contact.dim, name or f"force[{contact.name}]", weight, priority)
        self.contact = contact
        self.variable = contact.name
        self._jac = contact.normal[None, :].copy()
        self.set_target(force)

    def _value(self, force: ArrayLike) -> FloatArray:
        a = np.asarray(force, dtype=float)
        if self.normal_only:
            a = np.atleast_1d(self.contact.normal @ a if a.shape == (3,) else a)
        a = vector(a, self.dim, f"{self.name}: force")
        normal = float(a[0]) if self.normal_only else float(self.contact.normal @ a)
        # round-off is not a pull: a tangential target on a tilted normal, a ramp ending at 0 (1 nN floor)
        if normal < -1e-9 * max(float(np.abs(a).max()), 1.0):
            raise InvalidParameterError(
                f"{self.name}: the target force {a.tolist()} has a normal component of {normal:g} N, a pull that a "
                f"contact cannot give. The force is the environment's on the robot, along the normal "
                f"{self.contact.normal.tolist()} (from the surface towards the robot) when pressing: to press with "
                f"{-normal:g} N, ask for {-normal:g}" + ("" if self.normal_only else " times the normal"),
                value=force,
            )
        return a

    def set_target(self, force: Force) -> None:
        """Desired contact force [N] (see the class): a value, or a callable of t [s] returning one."""
        if callable(force):
            self._fn: Callable[[float], ArrayLike] | None = force
        else:
            self._fn = None
            self._force = self._value(force)

    def target(self, t: float) -> FloatArray:
        """The desired force at time t: (3,) or (1,) with ``normal_only``."""
        return self._value(self._fn(t)) if self._fn is not None else self._force

    def check(self, evaluator: object, n: int, contacts: dict[str, int]) -> None:
        if self.contact.name not in contacts:
            raise UnknownNameError("contact", self.contact.name, list(contacts))

    def residual(self, state: ModelState, t: float, ref: Reference) -> tuple[FloatArray | None, FloatArray]:
        return (self._jac if self.normal_only else None), self.target(t)
