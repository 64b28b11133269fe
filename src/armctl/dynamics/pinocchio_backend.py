"""The ``"pinocchio"`` backend: Pinocchio's RNEA, CRBA, ABA, Coriolis matrix and joint-torque regressor.

Rotors enter as reflected inertia k_r²·I_m on the diagonal (Pinocchio's armature); their gyroscopic coupling
with the previous link, k_r I_m q̇_i z_mᵀω_{i−1}, is not expressed (the ``"lagrange"`` backend has it).
"""

from __future__ import annotations

from functools import partial
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from armctl._checks import FloatArray
from armctl.dynamics.base import Dynamics
from armctl.model.robot import PARAMS_PER_JOINT, RobotModel


class PinocchioDynamics(Dynamics):
    """Dynamics evaluated by Pinocchio (see :class:`~armctl.dynamics.base.Dynamics` for the API)."""

    backend = "pinocchio"

    def __init__(self, model: RobotModel, backend: str | None = None, **options: Any) -> None:
        super().__init__(model, backend, **options)
        self.pin_model = model.to_pinocchio()
        self.pin_data = self.pin_model.createData()
        self._tool_id = self._frame_id(None)
        # hot primitives bound straight to Pinocchio (no Python frame in between); the methods below are
        # the same functions, kept for the interface and for readers
        pm, pd = self.pin_model, self.pin_data
        self._mass = partial(pin.crba, pm, pd)  # type: ignore[method-assign]
        self._gravity = partial(pin.computeGeneralizedGravity, pm, pd)  # type: ignore[method-assign]
        self._coriolis = partial(pin.computeCoriolisMatrix, pm, pd)  # type: ignore[method-assign]
        self._rigid_torque = partial(pin.rnea, pm, pd)  # type: ignore[method-assign]
        self._forward = partial(pin.aba, pm, pd)  # type: ignore[method-assign]
        self._raw_regressor = partial(pin.computeJointTorqueRegressor, pm, pd)
        # Y is built as its transpose, an (n, 13, n) block array: Yᵀ[j, c, i] = Y[i, 13 j + c], so that
        # Pinocchio's column-major (n, 10n) regressor copies in as one block; flat indices of the diagonals
        # of the rotor (c = 10), viscous (11) and Coulomb (12) columns
        j = np.arange(self.n)
        self._t_idx = np.concatenate([(PARAMS_PER_JOINT * j + c) * self.n + j for c in (10, 11, 12)])

    def _frame_id(self, frame: str | None) -> int:
        name = self.model.frame(frame).name
        if name == "world":
            return 0
        return int(self.pin_model.getFrameId(name))

    def _mass(self, q: FloatArray) -> FloatArray:
        return pin.crba(self.pin_model, self.pin_data, q)

    def _coriolis(self, q: FloatArray, qd: FloatArray) -> FloatArray:
        return pin.computeCoriolisMatrix(self.pin_model, self.pin_data, q, qd)

    def _gravity(self, q: FloatArray) -> FloatArray:
        return pin.computeGeneralizedGravity(self.pin_model, self.pin_data, q)

    def _rigid_torque(self, q: FloatArray, qd: FloatArray, qdd: FloatArray) -> FloatArray:
        return pin.rnea(self.pin_model, self.pin_data, q, qd, qdd)

    def _rigid_regressor(self, q: FloatArray, qd: FloatArray, qdd: FloatArray,
                         friction: tuple[FloatArray, FloatArray] | None = None) -> FloatArray:
        return self._assemble(self._raw_regressor(q, qd, qdd), qdd, friction)

    def _polarised_regressor(self, q: FloatArray, v1: FloatArray, a1: FloatArray, v2: FloatArray,
                             friction: tuple[FloatArray, FloatArray]) -> FloatArray:
        # combine Pinocchio's (n, 10n) outputs first, then assemble the (n, 13n) layout once
        raw = self._raw_regressor(q, v1, a1)
        raw *= 2.0
        raw -= self._raw_regressor(q, v2, self._zeros)
        return self._assemble(raw, 2.0 * a1, friction)

    def _assemble(self, raw: FloatArray, rotor: FloatArray,
                  friction: tuple[FloatArray, FloatArray] | None) -> FloatArray:
        """armctl's (n, 13n) regressor from Pinocchio's (n, 10n) one: Pinocchio's ten inertial parameters
        per body are armctl's first ten, in the same order; the rotor column is q̈ (diagonal)."""
        n = self.n
        yt = np.zeros((n, PARAMS_PER_JOINT, n))
        yt[:, :10, :] = raw.T.reshape(n, 10, n)
        if friction is None:
            yt.put(self._t_idx[:n], rotor)
        else:
            yt.put(self._t_idx, np.concatenate((rotor, *friction)))
        return yt.reshape(PARAMS_PER_JOINT * n, n).T  # (n, 13n), column-major

    def _forward(self, q: FloatArray, qd: FloatArray, tau_net: FloatArray) -> FloatArray:
        return pin.aba(self.pin_model, self.pin_data, q, qd, tau_net)

    def _jacobian(self, q: FloatArray, frame: str | None) -> FloatArray:
        fid = self._tool_id if frame is None else self._frame_id(frame)
        if fid == 0:
            return np.zeros((6, self.n))
        jac = pin.computeFrameJacobian(self.pin_model, self.pin_data, q, fid, pin.LOCAL_WORLD_ALIGNED)
        return jac.reshape(6, self.n)  # eigenpy squeezes a 6×1 result to (6,)

    def _kinetic(self, q: FloatArray, qd: FloatArray) -> float:
        # ½ q̇ᵀ M q̇ from CRBA: Pinocchio 4's computeKineticEnergy counts the armature for some joint types
        # (RX/RY/RZ) and not for others (RevoluteUnaligned), so it is not used
        return float(0.5 * qd @ pin.crba(self.pin_model, self.pin_data, q) @ qd)

    def _potential(self, q: FloatArray) -> float:
        return float(pin.computePotentialEnergy(self.pin_model, self.pin_data, q))

    def frame_pose(self, q: ArrayLike, frame: str | None = None) -> FloatArray:
        fid = self._frame_id(frame)
        qv = self._q(q)
        if fid == 0:
            return np.eye(4)
        pin.framesForwardKinematics(self.pin_model, self.pin_data, qv)
        return self.pin_data.oMf[fid].homogeneous.copy()
