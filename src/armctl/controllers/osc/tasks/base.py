"""Task base classes: a task is a least-squares objective on one block of the QP's variables.

A task of dimension m contributes the residual r = J x_b − b on a block x_b of the decision variables
(q̈, or a contact's force f) and the cost ½ Σ_i w_i r_i² to its priority level. Weights w_i ≥ 0 (a scalar or
one per row) trade tasks off inside a level; ``priority`` (0 = most important) orders levels strictly.

A :class:`MotionTask` is defined by its error e, its Jacobian J and the drift J̇ q̇ (the pink / TSID way); the
base class turns them into the desired task acceleration of a PD law and the residual on q̈:

    ẍ* = ẍ_ref + K_d (ẋ_ref − J q̇) + K_p e,      r = J q̈ + J̇ q̇ − ẋ*

so that a zero residual gives the error dynamics ë + K_d ė + K_p e = 0.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, Gain, nonnegative_vector, whole_number
from armctl.controllers.osc.state import ModelState
from armctl.reference import Reference


class Task(ABC):
    """A least-squares objective of dimension ``dim`` on the variable block ``variable`` ("qdd" or a contact
    name). ``weight`` w ≥ 0: scalar or (dim,). ``priority``: integer level, 0 the most important."""

    variable: str = "qdd"
    #: True if the task's Jacobian is always the identity on its block (``residual`` then returns None for it)
    identity_jacobian: bool = False

    def __init__(self, dim: int, name: str, weight: ArrayLike = 1.0, priority: int = 0) -> None:
        self.dim = int(dim)
        self.name = str(name)
        #: counts the changes of this task's weight (and a motion task's gains): what a controller derives from
        #: them (stacked weights, generated code's parameters) is refreshed when it changes
        self.revision = 0
        self.weight = weight  # type: ignore[assignment]  (checked by the property)
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
        """Validate against the controller's model (frames, sizes); raise an ArmctlError if it does not fit."""
        return None

    @abstractmethod
    def residual(self, state: ModelState, t: float, ref: Reference) -> tuple[FloatArray | None, FloatArray]:
        """(J, b) of the residual r = J x_b − b; J None means the identity."""

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name!r}, dim={self.dim}, priority={self.priority})"


def _dim(task: Task) -> int:
    return task.dim


def _label(task: Task, gain: str) -> str:
    return f"{task.name}: {gain}"


class MotionTask(Task):
    """A task on q̈ with PD gains ``kp`` [1/s²] and ``kd`` [1/s] (each a scalar, a (dim,) vector or a
    dim×dim matrix, symmetric positive definite; ``kd=None``: critical damping K_d = 2 K_p^½, 2√k_p for
    a scalar or each entry of a vector)."""

    # the hot path uses the law's matrices built from the gains in _gains_changed
    kp = Gain("K_p (dim×dim); may be reassigned between control periods (checked again).", size=_dim, label=_label)
    kd = Gain("K_d (dim×dim); may be reassigned between control periods (checked again).", size=_dim, label=_label)

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
        self.kp = kp
        if kd is None:  # critical damping: K_d = 2 K_p^½ (the symmetric square root; 2√k_p for a scalar)
            lam, vec = np.linalg.eigh(self.kp)
            kd = 2.0 * (vec * np.sqrt(lam)) @ vec.T
        self.kd = kd

    @abstractmethod
    def kinematics(
        self, state: ModelState, t: float, ref: Reference
    ) -> tuple[FloatArray | None, FloatArray | None, FloatArray, FloatArray, FloatArray]:
        """(J, drift J̇q̇, error e, velocity error ė, feed-forward acceleration ẍ_ref); J None: the identity,
        drift None: zero."""

    def _gains_changed(self) -> None:
        self.revision += 1
        if hasattr(self, "_kd"):  # both gains set
            # ẍ* = [I, K_d, K_p]·[ẍ_ref; ė; e] and ẍ* − J̇q̇ = [I, K_d, K_p, −I]·[ẍ_ref; ė; e; J̇q̇]: one
            # concatenation and one product each (the term by term form takes five array operations)
            eye = np.eye(self.dim)
            self._law = np.hstack((eye, self._kd_matrix, self._kp_matrix))
            self._law_drift = np.hstack((self._law, -eye))

    def desired_acceleration(
        self, state: ModelState, t: float, ref: Reference
    ) -> tuple[FloatArray | None, FloatArray, FloatArray]:
        """(J, J̇q̇, ẍ*) with ẍ* = ẍ_ref + K_d ė + K_p e."""
        jac, drift, e, ed, acc = self.kinematics(state, t, ref)
        return (jac, np.zeros(self.dim) if drift is None else drift, self._law.dot(np.concatenate((acc, ed, e))))

    def residual(self, state: ModelState, t: float, ref: Reference) -> tuple[FloatArray | None, FloatArray]:
        """(J, ẍ* − J̇q̇)."""
        jac, drift, e, ed, acc = self.kinematics(state, t, ref)
        if drift is None:
            return jac, self._law.dot(np.concatenate((acc, ed, e)))
        return jac, self._law_drift.dot(np.concatenate((acc, ed, e, drift)))

    def error(self, state: ModelState, t: float, ref: Reference) -> FloatArray:
        """The task error e at this state (for logs and tests)."""
        return self.kinematics(state, t, ref)[2]
