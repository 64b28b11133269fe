"""The ``"pinocchio"`` backend: Pinocchio's RNEA, CRBA, ABA, Coriolis matrix and joint-torque regressor.

Rotors enter as reflected inertia k_r²·I_m on the diagonal (Pinocchio's armature); their gyroscopic coupling
with the previous link, k_r I_m q̇_i z_mᵀω_{i−1}, is not expressed (the ``"lagrange"`` backend has it).
"""

from __future__ import annotations

import math
import os
from functools import partial
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from armctl._checks import FLOAT, FloatArray, boolean, check_cache_dir
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError
from armctl.model.robot import PARAMS_PER_JOINT, RobotModel

_crba = pin.crba
#: ABA in the WORLD convention: the same q̈ (to rounding, checked in tests/dynamics/test_backends.py) for 8–14 %
#: less time than the default LOCAL one on the Panda; None on a Pinocchio without conventions
_WORLD = getattr(getattr(pin, "Convention", None), "WORLD", None)


def _world_aba(pm: Any, pd: Any) -> Any:
    """q̈ = ABA(q, q̇, τ) on (pm, pd), bound (a plain function: cheaper to call than a partial with a keyword)."""
    aba, world = pin.aba, _WORLD
    if world is None:
        return partial(aba, pm, pd)

    def forward(q: FloatArray, qd: FloatArray, tau_net: FloatArray) -> FloatArray:
        return aba(pm, pd, q, qd, tau_net, world)  # type: ignore[no-any-return]

    return forward


class PinocchioDynamics(Dynamics):
    """Dynamics evaluated by Pinocchio (see :class:`~armctl.dynamics.base.Dynamics` for the API).

    ``pin_model`` is the Pinocchio model; ``pin_data`` is this object's workspace, whose contents after a call
    are unspecified (the passivity regressor, for one, leaves R − h₀ in ``jointTorqueRegressor``): create
    your own ``pin_model.createData()`` to call Pinocchio directly."""

    backend = "pinocchio"
    _nan_propagates = True  # checked entry by entry in tests/dynamics/test_input_checks.py
    _option_names = ("compile", "cache_dir")
    #: True for :class:`~armctl.dynamics.compiled.CompiledDynamics` (``compile=True``)
    _compiled = False

    def __init__(
        self,
        model: RobotModel,
        backend: str | None = None,
        compile: bool = False,
        cache_dir: str | os.PathLike[str] | None = None,
        **options: Any,
    ) -> None:
        if boolean(compile, "compile") != self._compiled:
            raise InvalidParameterError(
                f"{type(self).__name__} is not made with compile={compile}: use "
                f"armctl.Dynamics(model, compile={compile})",
                value=compile,
            )
        check_cache_dir(cache_dir, compile)
        super().__init__(model, backend, **options)
        self._cache_dir = cache_dir
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
        self._forward = _world_aba(pm, pd)  # type: ignore[method-assign]
        self._raw_regressor = partial(pin.computeJointTorqueRegressor, pm, pd)
        # the same model without gravity, for the velocity terms h(v) = C(q, v) v alone
        self.pin_model_free = pin.Model(pm)
        self.pin_model_free.gravity = pin.Motion.Zero()
        self.pin_data_free = self.pin_model_free.createData()
        self._rigid_torque_free = partial(pin.rnea, self.pin_model_free, self.pin_data_free)
        self._raw_regressor_free = partial(pin.computeJointTorqueRegressor, self.pin_model_free, self.pin_data_free)
        self._init_regressor_workspace()

    def _init_regressor_workspace(self) -> None:
        """Y is assembled in a workspace holding its transpose as an (n, 13, n) block array, Yᵀ[j, c, i] =
        Y[i, 13 j + c]: Pinocchio's own (column-major) regressor, seen transposed, is a C-contiguous (10n, n)
        array whose (n, 10, n) view copies into the first ten rows of every block in n contiguous pieces. The
        rotor (c = 10), viscous (11) and Coulomb (12) columns have Y[i, 13 i + c] as their only non-zero, a
        strided view of the workspace. Each call returns a copy of the workspace."""
        n = self.n
        self._yt = np.zeros((n, PARAMS_PER_JOINT, n))
        self._yt_rigid = self._yt[:, :10, :]
        flat = self._yt.reshape(-1)
        self._yt_rotor, self._yt_viscous, self._yt_coulomb = (
            flat[c * n :: PARAMS_PER_JOINT * n + 1] for c in (10, 11, 12)
        )
        self._y = self._yt.reshape(PARAMS_PER_JOINT * n, n).T  # (n, 13n), column-major view
        # Y[0, 13(n−1) + c], c < 10: the first joint's torque per inertial parameter of the last link, which
        # every input reaches (see Dynamics._regressor_probe)
        self._regressor_probe = self._yt[n - 1, :10, 0]
        # Pinocchio keeps its regressor in Data.jointTorqueRegressor, which eigenpy hands out as a view; the
        # views are used only if they really are views (checked here), else the returned copies are read
        rng = np.random.default_rng(0)
        args = rng.uniform(-1.0, 1.0, (3, n))
        shared = True
        for data, fn in ((self.pin_data, self._raw_regressor), (self.pin_data_free, self._raw_regressor_free)):
            view = data.jointTorqueRegressor
            out = fn(*args)
            shared &= bool(
                np.shares_memory(view, data.jointTorqueRegressor)
                and np.array_equal(view, out)
                and view.T.flags.c_contiguous
            )
        self._raw_t = self.pin_data.jointTorqueRegressor.T.reshape(n, 10, n) if shared else None
        self._raw_t_free = self.pin_data_free.jointTorqueRegressor.T.reshape(n, 10, n) if shared else None

    def _raw_blocks(self, q: FloatArray, qd: FloatArray, qdd: FloatArray) -> FloatArray:
        """Pinocchio's regressor at (q, q̇, q̈) as (n, 10, n) blocks, Yᵀ layout (a view when it can be)."""
        out = self._raw_regressor(q, qd, qdd)
        if self._raw_t is not None:
            return self._raw_t
        return out.T.reshape(self.n, 10, self.n)  # type: ignore[no-any-return]

    def _frame_id(self, frame: str | None) -> int:
        name = self.model.frame(frame).name
        if name == "world":
            return 0
        return int(self.pin_model.getFrameId(name))

    def mass_matrix(self, q: ArrayLike) -> FloatArray:
        """M(q) (n×n, symmetric positive definite) [kg·m² / kg]."""
        # Dynamics.mass_matrix with CRBA called here rather than through the bound partial: one call layer
        # less, ~0.15 µs of ~2 µs (benchmarked: python -m armctl.bench.dynamics_speed)
        try:
            if q.dtype is FLOAT and math.isfinite(sum(q.tolist())):  # type: ignore[union-attr]
                return _crba(self.pin_model, self.pin_data, q)  # type: ignore[no-any-return]
        except Exception:  # as in Dynamics.mass_matrix, whose slow path names the input
            pass
        return super().mass_matrix(q)

    def _mass(self, q: FloatArray) -> FloatArray:
        return pin.crba(self.pin_model, self.pin_data, q)

    def _coriolis(self, q: FloatArray, qd: FloatArray) -> FloatArray:
        return pin.computeCoriolisMatrix(self.pin_model, self.pin_data, q, qd)

    def _gravity(self, q: FloatArray) -> FloatArray:
        return pin.computeGeneralizedGravity(self.pin_model, self.pin_data, q)

    def _rigid_torque(self, q: FloatArray, qd: FloatArray, qdd: FloatArray) -> FloatArray:
        return pin.rnea(self.pin_model, self.pin_data, q, qd, qdd)

    def _rigid_regressor(
        self, q: FloatArray, qd: FloatArray, qdd: FloatArray, friction: tuple[FloatArray, FloatArray] | None = None
    ) -> FloatArray:
        out = self._raw_regressor(q, qd, qdd)  # _raw_blocks, inlined
        self._yt_rigid[...] = self._raw_t if self._raw_t is not None else out.T.reshape(self.n, 10, self.n)
        self._yt_rotor[...] = qdd
        return self._finish_regressor(friction)

    # Polarisation with a gravity-free twin of the model: with R(q, v, a) = M a + h(v) + g and
    # h₀(v) = h(v) = C(q, v) v evaluated without gravity, and s = q̇ − q̇_r,
    #     M q̈_r + C(q, q̇) q̇_r + g = R(q, q̇_r + s/2, q̈_r) − h₀(s/2)
    # since h(u + v) − h(u − v) = 4 C(q, u) v with u ± v = (q̇ ± q̇_r)/2: one subtraction of two evaluations.
    # The primitives take a = q̇_r + s/2 and w = s/2 (see Dynamics).
    def _passivity_regressor(
        self,
        q: FloatArray,
        qd: FloatArray,
        qd_r: FloatArray,
        qdd_r: FloatArray,
        a: FloatArray,
        w: FloatArray,
        copy: bool = True,
    ) -> FloatArray:
        if self._raw_t is not None:  # both regressors stay in Pinocchio's workspaces: subtract them there
            self._raw_regressor(q, a, qdd_r)
            self._raw_regressor_free(q, w, self._zeros)
            # in place in Pinocchio's (contiguous) workspace, then one block copy: half the cost of a
            # subtraction into the strided block view. Safe: Pinocchio rewrites every entry it ever writes
            # at each call, and the entries it never writes are zero in both workspaces.
            np.subtract(self._raw_t, self._raw_t_free, out=self._raw_t)
            self._yt_rigid[...] = self._raw_t
        else:
            self._yt_rigid[...] = self._raw_blocks(q, a, qdd_r)
            self._yt_rigid -= self._raw_regressor_free(q, w, self._zeros).T.reshape(self.n, 10, self.n)
        self._yt_rotor[...] = qdd_r  # and _finish_regressor, inlined
        self._yt_viscous[...] = qd_r
        self._coulomb_column(qd, self._yt_coulomb)
        return self._y.copy(order="K") if copy else self._y  # type: ignore[no-any-return]

    def _passivity_torque(
        self, q: FloatArray, qd: FloatArray, qd_r: FloatArray, qdd_r: FloatArray, a: FloatArray, w: FloatArray
    ) -> FloatArray:
        tau = self._rigid_torque(q, a, qdd_r)
        tau -= self._rigid_torque_free(q, w, self._zeros)
        return self._add_passivity_friction(tau, qd, qd_r)

    def _finish_regressor(self, friction: tuple[FloatArray, FloatArray] | None, copy: bool = True) -> FloatArray:
        if friction is None:
            self._yt_viscous[...] = 0.0
            self._yt_coulomb[...] = 0.0
        else:
            self._yt_viscous[...] = friction[0]
            self._coulomb_column(friction[1], self._yt_coulomb)
        return self._y.copy(order="K") if copy else self._y  # type: ignore[no-any-return]

    def _forward(self, q: FloatArray, qd: FloatArray, tau_net: FloatArray) -> FloatArray:  # (see __init__)
        if _WORLD is None:
            return pin.aba(self.pin_model, self.pin_data, q, qd, tau_net)  # type: ignore[no-any-return]
        return pin.aba(self.pin_model, self.pin_data, q, qd, tau_net, _WORLD)  # type: ignore[no-any-return]

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
