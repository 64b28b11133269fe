"""`PostureTask`: the joints follow a joint-space reference (by default the controller's ``ref``)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, vector, whole_number
from armctl.controllers.osc.state import ModelState
from armctl.controllers.osc.tasks.base import MotionTask
from armctl.errors import ShapeError
from armctl.references import Reference


class PostureTask(MotionTask):
    """The joints of an n-joint arm follow a joint-space target: the controller's joint reference ``ref``, unless
    :meth:`set_target` fixes one.

    Parameters
    ----------
    n : int
        The number of joints (the model's: checked when the task is given to a controller).
    kp : array_like, optional
        K_p [1/s²]: a scalar, an (n,) diagonal or an n×n symmetric positive definite matrix.
    kd : array_like, optional
        K_d [1/s], likewise; None (the default): critical damping, 2 K_p^½.
    weight : array_like, optional
        The rows' weights w_i ≥ 0 (scalar or (n,)); light by default (1e-2), so that in a level shared with frame
        tasks it only takes up what they leave free.
    priority : int, optional
        Its level, 0 the most important.
    name : str, optional
        The task's name.

    Raises
    ------
    InvalidParameterError, ShapeError, NonFiniteError
        ``n`` not a whole number ≥ 1; a gain that is not symmetric positive definite, of the wrong size or not
        finite; a negative weight.

    Notes
    -----
    ::

        e = q_ref − q,   ė = q̇_ref − q̇,   J = I,   drift = 0,   feed-forward q̈_ref

    As the lowest-priority (or lightly weighted) task it resolves the redundancy of an arm with more joints than
    task rows.
    """

    identity_jacobian = True

    def __init__(
        self,
        n: int,
        kp: ArrayLike = 100.0,
        kd: ArrayLike | None = None,
        weight: ArrayLike = 1e-2,
        priority: int = 0,
        name: str = "posture",
    ) -> None:
        super().__init__(
            whole_number(n, f"{name}: n (the number of joints)", minimum=1), name, kp, kd, weight, priority
        )
        self._fixed: Reference | None = None

    def set_target(self, q: ArrayLike | None, qd: ArrayLike | None = None, qdd: ArrayLike | None = None) -> None:
        """Fix the target, or go back to following the controller's ``ref``.

        Parameters
        ----------
        q : array_like, shape (n,), or None
            q_ref [rad] (m for a prismatic joint); None: follow the controller's ``ref`` again (``qd`` and ``qdd``
            are then ignored).
        qd : array_like, shape (n,), optional
            q̇_ref [rad/s]; None (the default): zero.
        qdd : array_like, shape (n,), optional
            q̈_ref [rad/s²], the feed-forward; None (the default): zero.

        Raises
        ------
        ShapeError, NonFiniteError, InvalidParameterError
            A vector of the wrong size, not finite, or not of real numbers.
        """
        self._fixed = None if q is None else Reference(vector(q, self.dim, f"{self.name}: q"), qd, qdd)

    def reference(self, ref: Reference) -> Reference:
        """The joint target at this step.

        Parameters
        ----------
        ref : Reference
            The controller's joint reference.

        Returns
        -------
        Reference
            The fixed target (:meth:`set_target`), or else ``ref``.
        """
        return self._fixed or ref

    def check(self, evaluator: object, n: int, contacts: dict[str, int]) -> None:
        if self.dim != n:
            raise ShapeError(
                f"{self.name}: a posture task of {self.dim} joints on a model of {n} joints", value=self.dim
            )

    def kinematics(
        self, state: ModelState, t: float, ref: Reference
    ) -> tuple[None, None, FloatArray, FloatArray, FloatArray]:
        r = self._fixed or ref
        return None, None, r.q - state.q, r.qd - state.qd, r.qdd

    def _derive(self) -> None:
        super()._derive()
        # ẍ* with the errors inside the product: [I, K_d, −K_d, K_p, −K_p]·[q̈_ref; q̇_ref; q̇; q_ref; q]
        eye, kd, kp = np.eye(self.dim), self._kd_matrix, self._kp_matrix
        self._posture_law = np.hstack((eye, kd, -kd, kp, -kp))

    def residual(self, state: ModelState, t: float, ref: Reference) -> tuple[None, FloatArray]:
        # kinematics and the PD law in one product; a subclass that overrides kinematics gets the generic form
        if type(self).kinematics is not PostureTask.kinematics:
            return super().residual(state, t, ref)  # type: ignore[return-value]  # no Jacobian: None
        r = self._fixed or ref
        return None, self._posture_law.dot(np.concatenate((r.qdd, r.qd, state.qd, r.q, state.q)))
