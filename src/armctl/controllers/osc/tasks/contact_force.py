"""`ContactForceTask`: regulate the force of a declared contact."""

from __future__ import annotations

import math
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
    """The force of a declared contact follows a target.

    The force is the one the environment exerts on the robot, so pressing means a positive normal component
    (the contact's normal points from the surface towards the robot): to press on a table with 10 N, ask for 10
    (or (0, 0, 10)), not −10. A simulated run reports the same force, in the same sense, as
    ``SimResult.contact_force_on_robot``.

    Parameters
    ----------
    contact : Contact
        The contact whose force the task is on (it must be one of the controller's contacts).
    force : array_like, float or callable, optional
        The target [N]: a (3,) vector (world axes), or with ``normal_only`` the normal force f_n,ref (a scalar; a
        (3,) vector is projected on the normal); or a callable of t [s] returning one. Default: zero.
    weight : array_like, optional
        The rows' weights w_i ≥ 0 (scalar, or (3,) without ``normal_only``); a weight of 0 leaves that component
        free. Light by default (1e-3): a force target gives way to the motion tasks of its level.
    priority : int, optional
        Its level, 0 the most important.
    name : str, optional
        The task's name; None (the default): ``"force[CONTACT]"``.
    normal_only : bool, optional
        Regulate only the normal component nᵀf (1 row) instead of f (3 rows). None (the default): True for a
        sliding contact (whose tangential force Coulomb's law already fixes), False for a fixed one.

    Raises
    ------
    InvalidParameterError
        ``contact`` is not a Contact; a target with a negative normal component (a pull, which a contact cannot
        give); a negative weight.
    ShapeError, NonFiniteError
        A target or weight of the wrong size or not finite.

    Notes
    -----
    ::

        r = f − f_ref                (3 rows, world axes), or
        r = nᵀf − f_n,ref            (1 row, normal_only)

    f is the force of the environment on the robot (see :class:`~armctl.controllers.osc.Contact`). A target
    given as a callable is checked at every step it is read.
    """

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
        if self.normal_only and type(force) is float and 0.0 <= force < math.inf:  # a press: nothing to refuse
            return np.array([force])
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
        """Set the desired contact force.

        Parameters
        ----------
        force : array_like, float or callable
            The target [N] (see the class): a value, or a callable of t [s] returning one (checked when read).

        Raises
        ------
        InvalidParameterError, ShapeError, NonFiniteError
            A value with a negative normal component (a pull), of the wrong size or not finite.
        """
        if callable(force):
            self._fn: Callable[[float], ArrayLike] | None = force
        else:
            self._fn = None
            self._force = self._value(force)

    def target(self, t: float) -> FloatArray:
        """The desired force at time t.

        Parameters
        ----------
        t : float
            Time [s].

        Returns
        -------
        ndarray, shape (3,) or (1,)
            f_ref [N] (world axes), or f_n,ref with ``normal_only``.

        Raises
        ------
        InvalidParameterError, ShapeError, NonFiniteError
            The callable's value is a pull, of the wrong size or not finite.
        """
        return self._value(self._fn(t)) if self._fn is not None else self._force

    def check(self, evaluator: object, n: int, contacts: dict[str, int]) -> None:
        if self.contact.name not in contacts:
            raise UnknownNameError("contact", self.contact.name, list(contacts))

    def residual(self, state: ModelState, t: float, ref: Reference) -> tuple[FloatArray | None, FloatArray]:
        """The rows of the residual on the contact's force at this step.

        Parameters
        ----------
        state : ModelState
            The model terms at the measured (q, q̇) (not used).
        t : float
            Time [s].
        ref : Reference
            The controller's joint reference (not used).

        Returns
        -------
        J : ndarray, shape (1, 3), or None
            nᵀ with ``normal_only``, else None (the identity on f).
        b : ndarray, shape (1,) or (3,)
            The target force [N].
        """
        return (self._jac if self.normal_only else None), self.target(t)
