"""`Kernel`: the unchecked float64 primitives of one arm's dynamics, on one workspace.

A :class:`~armctl.dynamics.base.Dynamics` checks its inputs and hands them to its kernel
(``dyn.kernel``). Code that has checked its inputs already — a controller's ``compute`` after
``Controller.__call__``, the simulator's plant, a planner's inner loop — calls the kernel directly:

    k = dyn.kernel
    tau = k.rnea(q, qd, qdd)            # M q̈ + C q̇ + g
    qdd = k.aba(q, qd, tau_net)         # M⁻¹ (τ_net − C q̇ − g)

Contract: every array argument is a native float64 NumPy array of the right shape; results are new arrays
unless a method says otherwise. Nothing is checked: a wrong length may raise ``ValueError`` (Pinocchio checks
lengths) or give garbage, a NaN gives NaN. A kernel owns a workspace and is not thread-safe; ``dyn.kernel``
gives each thread its own.

``nan_propagates`` says whether NaN or inf in any entry of any input reaches the results of ``rnea``, ``aba``,
``coriolis`` and the regressors (true of Pinocchio's numerical algorithms, where NaN·0 = NaN, and of the generated
code, which carries each input into each output); then checking those results is enough to know the inputs were
finite. (Not ``mass``: M(q) does not depend on the first joint's position.)
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import cast

import numpy as np

from armctl._checks import FloatArray
from armctl.dynamics.friction_terms import FrictionTerms
from armctl.errors import ArmctlError, InvalidParameterError, NonFiniteError
from armctl.model.robot import PARAMS_PER_JOINT, RobotModel

_SQRT_HALF = math.sqrt(0.5)


class Kernel(ABC):
    """The primitives of one arm's dynamics (see the module for the contract).

    Parameters
    ----------
    model : RobotModel
        The arm; ``friction`` is made from its joints.
    """

    #: NaN or inf in any input reaches every result (see the module)
    nan_propagates: bool = False

    def __init__(self, model: RobotModel) -> None:
        self.model = model
        self.n = n = model.n
        self.friction = FrictionTerms(model)
        self.zeros = np.zeros(n)
        self.zeros.flags.writeable = False
        self._halves = np.full(n, 0.5)
        k, rows = PARAMS_PER_JOINT, np.arange(n)
        # flat indices of Y[i, 13 i + c] for the rotor (c = 10), viscous (11) and Coulomb (12) columns of a
        # C-ordered (n, 13n) regressor
        self._diag_idx = np.concatenate([rows * k * n + k * rows + c for c in (10, 11, 12)])

    # The primitives a backend provides, set as attributes in its __init__ (bound straight to the library's
    # functions where it can: no Python frame in between).
    #: M(q) (n×n)
    mass: Callable[[FloatArray], FloatArray]
    #: C(q, q̇) (n×n), from the Christoffel symbols
    coriolis: Callable[[FloatArray, FloatArray], FloatArray]
    #: g(q) (n,)
    gravity: Callable[[FloatArray], FloatArray]
    #: M(q) q̈ + C(q, q̇) q̇ + g(q) (n,), no friction: (q, q̇, q̈) → τ
    rnea: Callable[[FloatArray, FloatArray, FloatArray], FloatArray]
    #: q̈ = M(q)⁻¹ (τ − C q̇ − g) (n,), no friction: (q, q̇, τ) → q̈
    aba: Callable[[FloatArray, FloatArray, FloatArray], FloatArray]
    #: U [J] (see :meth:`armctl.Dynamics.potential_energy`)
    potential: Callable[[FloatArray], float]

    def kinetic(self, q: FloatArray, qd: FloatArray) -> float:
        """T = ½ q̇ᵀ M(q) q̇ [J] (links and rotors)."""
        return float(0.5 * qd @ self.mass(q) @ qd)

    def solve_aba(self, q: FloatArray, qd: FloatArray, tau: FloatArray) -> FloatArray:
        """q̈ by a linear solve with M(q): the forward dynamics of a backend without a better algorithm."""
        return cast(FloatArray, np.linalg.solve(self.mass(q), tau - self.rnea(q, qd, self.zeros)))

    @abstractmethod
    def jacobian(self, q: FloatArray, frame: str | None = None) -> FloatArray:
        """Geometric Jacobian (6×n) of ``frame`` (None: the tool frame; a name the model has), world-aligned
        axes, rows [linear; angular]."""

    @abstractmethod
    def frame_pose(self, q: FloatArray, frame: str | None = None) -> FloatArray:
        """4×4 pose of ``frame`` in the world."""

    # ----------------------------------------------------------------------------------- friction
    def friction_torque(self, qd: FloatArray, viscous_at: FloatArray | None = None) -> FloatArray:
        """τ_f(q̇) (see :class:`~armctl.dynamics.friction_terms.FrictionTerms`)."""
        return self.friction.torque(qd, viscous_at)

    def inverse_dynamics(self, q: FloatArray, qd: FloatArray, qdd: FloatArray) -> FloatArray:
        """M q̈ + C q̇ + g + τ_f(q̇)."""
        tau = self.rnea(q, qd, qdd)
        if self.friction.any:
            tau += self.friction.torque(qd)
        return tau

    # --------------------------------------------------------------------------------- regressors
    @abstractmethod
    def regressor(
        self, q: FloatArray, qd: FloatArray, qdd: FloatArray, friction: tuple[FloatArray, FloatArray] | None = None
    ) -> FloatArray:
        """Y (n × 13n) of M q̈ + C q̇ + g, a new array; the friction columns hold ``friction`` = (v, w): the
        viscous column's diagonal v and the Coulomb column's κ(w) (:meth:`FrictionTerms.coulomb_column`), or
        zeros."""

    def polarisation(self, qd: FloatArray, qd_r: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(a, w) = (q̇_r + s/2, s/2) with s = q̇ − q̇_r: the velocities of the passivity primitives."""
        w = qd - qd_r
        w *= self._halves
        return qd_r + w, w

    def passivity_regressor(
        self,
        q: FloatArray,
        qd: FloatArray,
        qd_r: FloatArray,
        qdd_r: FloatArray,
        a: FloatArray,
        w: FloatArray,
        copy: bool = True,
    ) -> FloatArray:
        """Y with Y π = M q̈_r + C(q, q̇) q̇_r + g + F_v q̇_r + τ_c(q̇), given (a, w) = :meth:`polarisation`.

        By polarisation of the velocity terms h(v) = C(q, v) v, with R(q, v, a) = M a + h(v) + g:
        Y = 2 R(q, a/√2, q̈_r/2) − R(q, w, 0). ``copy=False`` may return a workspace that the next regressor
        call overwrites."""
        y = self.regressor(q, a * _SQRT_HALF, 0.5 * qdd_r)
        y *= 2.0
        y -= self.regressor(q, w, self.zeros)
        y.put(self._diag_idx[self.n :], np.concatenate((qd_r, self.friction.coulomb_column(qd))))
        return y

    def passivity_torque(
        self, q: FloatArray, qd: FloatArray, qd_r: FloatArray, qdd_r: FloatArray, a: FloatArray, w: FloatArray
    ) -> FloatArray:
        """M q̈_r + C(q, q̇) q̇_r + g + F_v q̇_r + τ_c(q̇) from two inverse-dynamics evaluations (the
        polarisation of :meth:`passivity_regressor`)."""
        tau = self.rnea(q, a * _SQRT_HALF, 0.5 * qdd_r)
        tau *= 2.0
        tau -= self.rnea(q, w, self.zeros)
        return self.add_passivity_friction(tau, qd, qd_r)

    def add_passivity_friction(self, tau: FloatArray, qd: FloatArray, qd_r: FloatArray) -> FloatArray:
        """τ + F_v q̇_r + τ_c(q̇), in place."""
        if self.friction.any:
            tau += self.friction.torque(qd, qd_r)
        return tau

    # ---------------------------------------------------------------------------------- failures
    def nonfinite_error(self, q: FloatArray, out: FloatArray | None = None) -> ArmctlError:
        """The error for a result that is not finite (or could not be computed) from finite inputs: a mass
        matrix that is not positive definite at q is named as such, with the joint of least inertia."""
        m = self.mass(q)
        if not np.isfinite(m).all():  # the configuration itself is beyond floats (a prismatic joint's position)
            return NonFiniteError(f"the mass matrix is not finite at q = {q}", value=q)
        try:
            np.linalg.cholesky(m)
        except np.linalg.LinAlgError:
            d = np.diag(m)
            k = int(np.argmin(d))
            name = self.model.joints[k].name
            return InvalidParameterError(
                f"the mass matrix of {self.model.name!r} is not positive definite at q = {q} (smallest "
                f"eigenvalue {np.linalg.eigvalsh(m).min():.3g}); joint {name!r} moves the least inertia (M_kk = "
                f"{d[k]:.3g}): give the links it carries mass and inertia, or its motor a rotor inertia",
                value=q,
            )
        return NonFiniteError(f"result is not finite although every input is: {out!r}", value=out)
