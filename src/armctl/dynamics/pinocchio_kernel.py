"""The ``"pinocchio"`` backend's kernel: Pinocchio's RNEA, CRBA, ABA, Coriolis matrix and joint-torque regressor on
checked inputs (:class:`PinocchioKernel`, one ``pin.Data`` workspace each).

Rotors enter as reflected inertia k_r²·I_m on the diagonal (Pinocchio's armature); their gyroscopic coupling
with the previous link, k_r I_m q̇_i z_mᵀω_{i−1}, is not expressed (the ``"lagrange"`` backend has it).
"""

from __future__ import annotations

from functools import partial
from typing import Any

import numpy as np
import pinocchio as pin

from armctl._checks import FloatArray
from armctl.dynamics.kernel import Kernel
from armctl.model.robot import PARAMS_PER_JOINT, RobotModel

#: ABA in the WORLD convention: the same q̈ (to rounding, checked in tests/dynamics/test_backends.py) for less
#: time than the default LOCAL one; None on a Pinocchio without conventions
_WORLD = getattr(getattr(pin, "Convention", None), "WORLD", None)


class PinocchioKernel(Kernel):
    """The primitives on Pinocchio's algorithms, with a ``pin.Data`` workspace of its own.

    Parameters
    ----------
    model : RobotModel
        The arm.
    pin_model : pinocchio.Model
        Its Pinocchio model (shared by every kernel of one :class:`PinocchioDynamics`; only read).

    Attributes
    ----------
    pin_model, pin_data : pinocchio.Model, pinocchio.Data
        The model and this kernel's workspace, whose contents after a call are unspecified.
    """

    nan_propagates = True  # relied on, and checked entry by entry through the API, in tests/dynamics/test_validation.py

    def __init__(self, model: RobotModel, pin_model: Any) -> None:
        super().__init__(model)
        self.pin_model = pm = pin_model
        self.pin_data = pd = pm.createData()
        self.mass = partial(pin.crba, pm, pd)
        self.gravity = partial(pin.computeGeneralizedGravity, pm, pd)
        self.coriolis = partial(pin.computeCoriolisMatrix, pm, pd)
        self.rnea = partial(pin.rnea, pm, pd)
        self.aba = partial(pin.aba, pm, pd) if _WORLD is None else _world_aba(pm, pd)
        self.potential = partial(pin.computePotentialEnergy, pm, pd)
        self._raw_regressor = partial(pin.computeJointTorqueRegressor, pm, pd)
        # the same model without gravity, for the velocity terms h(v) = C(q, v) v alone
        free = pin.Model(pm)
        free.gravity = pin.Motion.Zero()
        self._free_data = free.createData()
        self._rnea_free = partial(pin.rnea, free, self._free_data)
        self._raw_regressor_free = partial(pin.computeJointTorqueRegressor, free, self._free_data)
        self._pin_free = free
        self._frame_ids: dict[str | None, int] = {}
        self._init_regressor_workspace()

    def frame_id(self, frame: str | None) -> int:
        """Pinocchio's id of ``frame`` (None: the tool frame; 0 for the world)."""
        fid = self._frame_ids.get(frame)
        if fid is None:
            name = self.model.frame(frame).name
            fid = self._frame_ids[frame] = 0 if name == "world" else int(self.pin_model.getFrameId(name))
        return fid

    def jacobian(self, q: FloatArray, frame: str | None = None) -> FloatArray:
        fid = self.frame_id(frame)
        if fid == 0:
            return np.zeros((6, self.n))
        jac = pin.computeFrameJacobian(self.pin_model, self.pin_data, q, fid, pin.LOCAL_WORLD_ALIGNED)
        return jac.reshape(6, self.n)  # eigenpy squeezes a 6×1 result to (6,)

    def frame_pose(self, q: FloatArray, frame: str | None = None) -> FloatArray:
        fid = self.frame_id(frame)
        if fid == 0:
            return np.eye(4)
        pin.framesForwardKinematics(self.pin_model, self.pin_data, q)
        return self.pin_data.oMf[fid].homogeneous.copy()

    # ------------------------------------------------------------------------------------ regressors
    def _init_regressor_workspace(self) -> None:
        """Y is assembled in a workspace holding its transpose as an (n, 13, n) block array, Yᵀ[j, c, i] =
        Y[i, 13 j + c]: Pinocchio's own (column-major) regressor, seen transposed, is a C-contiguous (10n, n)
        array whose (n, 10, n) view copies into the first ten rows of every block. The rotor (c = 10),
        viscous (11) and Coulomb (12) columns have Y[i, 13 i + c] as their only non-zero, a strided view of
        the workspace. Each call returns a copy of the workspace unless told otherwise."""
        n = self.n
        self._yt = np.zeros((n, PARAMS_PER_JOINT, n))
        self._yt_rigid = self._yt[:, :10, :]
        flat = self._yt.reshape(-1)
        self._yt_rotor, self._yt_viscous, self._yt_coulomb = (
            flat[c * n :: PARAMS_PER_JOINT * n + 1] for c in (10, 11, 12)
        )
        self._y = self._yt.reshape(PARAMS_PER_JOINT * n, n).T  # (n, 13n), column-major view
        # Pinocchio keeps its regressor in Data.jointTorqueRegressor, which eigenpy hands out as a view; the
        # views are used only if they really are views (checked here), else the returned copies are read
        rng = np.random.default_rng(0)
        args = rng.uniform(-1.0, 1.0, (3, n))
        shared = True
        for data, fn in ((self.pin_data, self._raw_regressor), (self._free_data, self._raw_regressor_free)):
            view = data.jointTorqueRegressor
            out = fn(*args)
            shared &= bool(
                np.shares_memory(view, data.jointTorqueRegressor)
                and np.array_equal(view, out)
                and view.T.flags.c_contiguous
            )
        self._raw_t = self.pin_data.jointTorqueRegressor.T.reshape(n, 10, n) if shared else None
        self._raw_t_free = self._free_data.jointTorqueRegressor.T.reshape(n, 10, n) if shared else None

    def _blocks(self, out: FloatArray, view: FloatArray | None) -> FloatArray:
        """Pinocchio's regressor ``out`` as (n, 10, n) blocks, Yᵀ layout (its workspace ``view`` if shared)."""
        return view if view is not None else out.T.reshape(self.n, 10, self.n)

    def regressor(
        self, q: FloatArray, qd: FloatArray, qdd: FloatArray, friction: tuple[FloatArray, FloatArray] | None = None
    ) -> FloatArray:
        self._yt_rigid[...] = self._blocks(self._raw_regressor(q, qd, qdd), self._raw_t)
        self._yt_rotor[...] = qdd
        if friction is None:
            self._yt_viscous[...] = 0.0
            self._yt_coulomb[...] = 0.0
        else:
            self._yt_viscous[...] = friction[0]
            self.friction.coulomb_column(friction[1], self._yt_coulomb)
        return self._y.copy(order="K")

    # Polarisation with a gravity-free twin of the model: with R(q, v, a) = M a + h(v) + g and h₀(v) = h(v) =
    # C(q, v) v evaluated without gravity, M q̈_r + C(q, q̇) q̇_r + g = R(q, a, q̈_r) − h₀(w) for (a, w) of
    # Kernel.polarisation, since h(u + v) − h(u − v) = 4 C(q, u) v: one subtraction of two evaluations.
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
        out = self._raw_regressor(q, a, qdd_r)
        if self._raw_t is not None and self._raw_t_free is not None:
            self._raw_regressor_free(q, w, self.zeros)
            # in place in Pinocchio's (contiguous) workspace, then one block copy: Pinocchio rewrites every
            # entry it ever writes at each call, and the entries it never writes are zero in both workspaces
            np.subtract(self._raw_t, self._raw_t_free, out=self._raw_t)
            self._yt_rigid[...] = self._raw_t
        else:
            self._yt_rigid[...] = self._blocks(out, None)
            self._yt_rigid -= self._blocks(self._raw_regressor_free(q, w, self.zeros), None)
        self._yt_rotor[...] = qdd_r
        self._yt_viscous[...] = qd_r
        self.friction.coulomb_column(qd, self._yt_coulomb)
        return self._y.copy(order="K") if copy else self._y

    def passivity_torque(
        self, q: FloatArray, qd: FloatArray, qd_r: FloatArray, qdd_r: FloatArray, a: FloatArray, w: FloatArray
    ) -> FloatArray:
        tau = self.rnea(q, a, qdd_r)
        tau -= self._rnea_free(q, w, self.zeros)
        return self.add_passivity_friction(tau, qd, qd_r)


def _world_aba(pm: Any, pd: Any) -> Any:
    """q̈ = ABA(q, q̇, τ) on (pm, pd) in the WORLD convention, bound."""
    aba, world = pin.aba, _WORLD

    def forward(q: FloatArray, qd: FloatArray, tau: FloatArray) -> FloatArray:
        return aba(pm, pd, q, qd, tau, world)

    return forward
