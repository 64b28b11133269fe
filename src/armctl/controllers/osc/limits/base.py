"""`Limit`: a bound l ≤ x_b ≤ u on one block of the QP's variables (q̈ or τ), one row per joint.

A limit has one method, :meth:`Limit.bounds`, returning (l, u) at the current state; the rows of C are the
identity on the block, so C is constant and only l, u change from step to step.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np
from numpy.typing import ArrayLike

from armctl import _checks
from armctl._checks import FloatArray
from armctl.controllers.osc.state import ModelState
from armctl.errors import InvalidParameterError, NonFiniteError
from armctl.model.robot import RobotModel


def per_joint(
    x: ArrayLike | None, default: FloatArray, n: int, name: str, positive: bool = True, finite: bool = False
) -> FloatArray:
    """``x`` as an (n,) vector (a scalar is broadcast; None takes ``default``), checked > 0 if ``positive``;
    ±inf (no limit) is allowed unless ``finite``."""
    a = np.array(_checks.per_joint(default if x is None else x, n, name))  # a copy: the limit's own
    if np.isnan(a).any() or (finite and not np.isfinite(a).all()):
        raise NonFiniteError(
            f"{name} must be {'finite' if finite else 'a number'} for every joint, got {a.tolist()}", value=x
        )
    if positive and (a <= 0).any():
        raise InvalidParameterError(f"{name} must be > 0, got {a.tolist()}", value=x)
    return a


class Limit(ABC):
    """Bounds l ≤ x_b ≤ u on one block of the QP's variables (q̈ or τ), one row per joint. Subclasses implement
    :meth:`bounds` (and :meth:`bind` to take defaults from the model).

    Attributes
    ----------
    variable : str
        The block: ``"qdd"`` (q̈ [rad/s²]) or ``"tau"`` (τ [N·m]).
    kind : str
        Names its rows, e.g. ``torque_limit[panda_joint1]``.
    constant : bool
        True if :meth:`bounds` does not depend on the state (it is then evaluated once).

    Notes
    -----
    The rows of C are the identity on the block, so C is constant and only l, u change from step to step.
    """

    variable: str = "qdd"
    kind: str = "limit"
    # True if :meth:`bounds` does not depend on the state (it is then evaluated once)
    constant: bool = False

    def bind(self, model: RobotModel) -> None:
        """Take defaults from the model and check the sizes; the controller calls it once, when it is made.

        Parameters
        ----------
        model : RobotModel
            The controller's model (its number of joints, joint names and limits).

        Raises
        ------
        ShapeError, InvalidParameterError, NonFiniteError
            A setting of the wrong size, out of its range, or NaN.
        """
        self.n = model.n
        self.row_names = [f"{self.kind}[{j}]" for j in model.joint_names]

    @abstractmethod
    def bounds(self, state: ModelState) -> tuple[FloatArray, FloatArray]:
        """The bounds at the current state.

        Parameters
        ----------
        state : ModelState
            The model terms at the measured (q, q̇) (not read by a ``constant`` limit, which may be given None).

        Returns
        -------
        l, u : ndarray, shape (n,)
            The lower and upper bounds on the block [rad/s² or N·m]; ±inf: no bound.
        """

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"
