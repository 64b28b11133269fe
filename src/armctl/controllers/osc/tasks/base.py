"""Task base classes: a task is a least-squares objective on one block of the QP's variables (:class:`Task`); a
:class:`MotionTask` is one on q̈, defined by its error, Jacobian and drift and turned into a PD law.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, gain_matrix, nonnegative_vector, whole_number
from armctl.controllers.gains import GainSet, gain
from armctl.controllers.osc.docstrings import step_parameters
from armctl.controllers.osc.state import ModelState
from armctl.references import Reference


class Task(ABC):
    """A least-squares objective of the operational-space QP on one block of its variables.

    Subclasses implement :meth:`residual` (and :meth:`check` if they must fit the controller's model).

    Parameters
    ----------
    dim : int
        m, the number of rows of the residual.
    name : str
        The task's name, unique in a controller: the key of its residual in ``OSCSolution.residuals`` and of its
        slack.
    weight : array_like, optional
        The rows' weights w_i ≥ 0 (a scalar, or one per row, (dim,)): the trade-off against the other tasks of
        its level; a weight of 0 leaves its row free. May be reassigned between control periods.
    priority : int, optional
        Its level, a whole number ≥ 0; 0 is the most important, and the levels are strict (see
        :class:`~armctl.controllers.OperationalSpaceQP`).

    Attributes
    ----------
    variable : str
        The block x_b of the variables the task is on: ``"qdd"`` (q̈) or a contact's name (its force).
    identity_jacobian : bool
        True if the Jacobian is always the identity on its block (:meth:`residual` then gives None for it).
    revision : int
        Counts the changes of the weight (and a motion task's gains), so that what a controller derives from them
        is refreshed.

    Raises
    ------
    InvalidParameterError, ShapeError, NonFiniteError
        A weight that is negative, of the wrong size or not finite; a priority that is not a whole number ≥ 0.

    Notes
    -----
    A task of dimension m contributes the residual r = J x_b − b on its block x_b of the decision variables
    (q̈, or a contact's force f) and the cost ½ Σ_i w_i r_i² to its priority level. Weights trade tasks off inside
    a level; ``priority`` (0 = most important) orders levels strictly.
    """

    variable: str = "qdd"
    # True if the task's Jacobian is always the identity on its block (``residual`` then returns None for it)
    identity_jacobian: bool = False

    def __init__(self, dim: int, name: str, weight: ArrayLike = 1.0, priority: int = 0) -> None:
        self.dim = int(dim)
        self.name = str(name)
        # counts the changes of this task's weight (and a motion task's gains): what a controller derives from
        # them (stacked weights, generated code's parameters) is refreshed when it changes
        self.revision = 0
        self.weight = weight  # checked by the property
        self.priority = whole_number(priority, f"{name}: priority")

    @property
    def weight(self) -> FloatArray:
        """Weights w_i ≥ 0 of the rows (dim,)."""
        return self._weight

    @weight.setter
    def weight(self, value: ArrayLike) -> None:
        self._weight = nonnegative_vector(value, self.dim, f"{self.name}: weight")
        self.sqrt_weight = np.sqrt(self._weight)
        self.revision += 1

    def check(self, evaluator: Any, n: int, contacts: dict[str, int]) -> None:
        """Check that the task fits the controller's model (its frames, its size); the base class accepts any.

        Parameters
        ----------
        evaluator : ModelEvaluator
            The controller's evaluator of the model terms (``evaluator.check_frame(name)`` checks a frame).
        n : int
            The model's number of joints.
        contacts : dict of str to int
            The controller's contacts, name → number of force variables.

        Raises
        ------
        ArmctlError
            A subclass of it (UnknownNameError, ShapeError, ...) if the task does not fit.
        """
        return None

    @abstractmethod
    @step_parameters
    def residual(self, state: ModelState, t: float, ref: Reference) -> tuple[FloatArray | None, FloatArray]:
        """The rows of the residual r = J x_b − b at this step.

        (the Parameters section of a control step's state, t, ref)

        Returns
        -------
        J : ndarray, shape (dim, size of the block), or None
            The Jacobian on the block; None means the identity.
        b : ndarray, shape (dim,)
            The target of J x_b [the block's units: rad/s² for q̈ rows of a posture task, m/s² or rad/s² for a
            frame's, N for a force].
        """

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name!r}, dim={self.dim}, priority={self.priority})"


class MotionTask(GainSet, Task):
    """A task on q̈ defined by its error e, its Jacobian J and the drift J̇ q̇ (the pink / TSID way); the class
    turns them into the desired task acceleration of a PD law. Subclasses implement :meth:`kinematics`.

    Parameters
    ----------
    dim, name
        As for :class:`Task`.
    kp : array_like
        K_p [1/s²]: a scalar, a (dim,) diagonal or a dim×dim symmetric positive definite matrix. May be
        reassigned between control periods (checked again).
    kd : array_like, optional
        K_d [1/s], likewise; None (the default): critical damping K_d = 2 K_p^½ (the symmetric square root; 2√k_p
        for a scalar or each entry of a vector).
    weight, priority : optional
        As for :class:`Task`.

    Raises
    ------
    InvalidParameterError, ShapeError, NonFiniteError
        A gain that is not symmetric positive definite, of the wrong size or not finite; a weight or priority as
        in :class:`Task`.

    Notes
    -----
    The desired task acceleration and the residual on q̈::

        ẍ* = ẍ_ref + K_d (ẋ_ref − J q̇) + K_p e,      r = J q̈ + J̇ q̇ − ẍ*

    so that a zero residual gives the error dynamics ë + K_d ė + K_p e = 0.
    """

    # assigning a gain rebuilds the law's matrices [I, K_d, K_p] (_derive), which every step then uses
    gain_names: ClassVar[dict[str, bool]] = {"kp": False, "kd": False}
    kp = gain("kp", "K_p (dim×dim); may be reassigned between control periods (checked again).")
    kd = gain("kd", "K_d (dim×dim); may be reassigned between control periods (checked again).")
    _kp_matrix: FloatArray  # (set_gains keeps the matrices, and their compact forms in _kp, _kd)
    _kd_matrix: FloatArray

    def __init__(
        self,
        dim: int,
        name: str,
        kp: ArrayLike,
        kd: ArrayLike | None = None,
        weight: ArrayLike = 1.0,
        priority: int = 0,
    ) -> None:
        super().__init__(dim, name, weight, priority)
        if kd is None:  # critical damping: K_d = 2 K_p^½ (the symmetric square root; 2√k_p for a scalar)
            lam, vec = np.linalg.eigh(gain_matrix(kp, *self._gain_spec("kp")))
            kd = 2.0 * (vec * np.sqrt(lam)) @ vec.T
        self.set_gains(kp=kp, kd=kd)

    def _gain_spec(self, name: str) -> tuple[int, str]:
        return self.dim, f"{self.name}: {name}"

    @abstractmethod
    @step_parameters
    def kinematics(
        self, state: ModelState, t: float, ref: Reference
    ) -> tuple[FloatArray | None, FloatArray | None, FloatArray, FloatArray, FloatArray]:
        """The task's kinematics at this step.

        (the Parameters section of a control step's state, t, ref)

        Returns
        -------
        J : ndarray, shape (dim, n), or None
            The task Jacobian; None means the identity (dim = n).
        drift : ndarray, shape (dim,), or None
            J̇ q̇ [m/s² or rad/s² per row]; None means zero.
        e : ndarray, shape (dim,)
            The error [m or rad].
        ed : ndarray, shape (dim,)
            The velocity error ė [m/s or rad/s].
        acc : ndarray, shape (dim,)
            The feed-forward acceleration ẍ_ref [m/s² or rad/s²].
        """

    def _derive(self) -> None:
        self.revision += 1
        # ẍ* = [I, K_d, K_p]·[ẍ_ref; ė; e] and ẍ* − J̇q̇ = [I, K_d, K_p, −I]·[ẍ_ref; ė; e; J̇q̇]: one
        # concatenation and one product each (the term by term form takes five array operations)
        eye = np.eye(self.dim)
        self._law = np.hstack((eye, self._kd_matrix, self._kp_matrix))
        self._law_drift = np.hstack((self._law, -eye))

    @step_parameters
    def desired_acceleration(
        self, state: ModelState, t: float, ref: Reference
    ) -> tuple[FloatArray | None, FloatArray, FloatArray]:
        """The desired task acceleration ẍ* = ẍ_ref + K_d ė + K_p e at this step.

        (the Parameters section of a control step's state, t, ref)

        Returns
        -------
        J : ndarray, shape (dim, n), or None
            The task Jacobian; None means the identity.
        drift : ndarray, shape (dim,)
            J̇ q̇ [m/s² or rad/s²] (zeros where the task has none).
        xdd : ndarray, shape (dim,)
            ẍ* [m/s² or rad/s²].
        """
        jac, drift, e, ed, acc = self.kinematics(state, t, ref)
        return (jac, np.zeros(self.dim) if drift is None else drift, self._law.dot(np.concatenate((acc, ed, e))))

    def residual(self, state: ModelState, t: float, ref: Reference) -> tuple[FloatArray | None, FloatArray]:
        jac, drift, e, ed, acc = self.kinematics(state, t, ref)
        if drift is None:
            return jac, self._law.dot(np.concatenate((acc, ed, e)))
        return jac, self._law_drift.dot(np.concatenate((acc, ed, e, drift)))

    @step_parameters
    def error(self, state: ModelState, t: float, ref: Reference) -> FloatArray:
        """The task error e at this state (for logs and tests).

        (the Parameters section of a control step's state, t, ref)

        Returns
        -------
        ndarray, shape (dim,)
            e [m or rad].
        """
        return self.kinematics(state, t, ref)[2]
