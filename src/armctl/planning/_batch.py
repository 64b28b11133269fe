"""Rigid-body inverse dynamics M q̈ + C(q, q̇) q̇ + g at many states at once (private).

On the Pinocchio backend: Pinocchio's ``rneaInParallel`` (one thread, a pool built from the backend's own
model) when this Pinocchio has it; else the kernel's ``rnea`` state by state. The tests check both against
``dyn.inverse_dynamics``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from armctl._checks import FloatArray
from armctl.dynamics.base import Dynamics
from armctl.dynamics.pinocchio_backend import PinocchioKernel


def rigid_torques(dyn: Dynamics, q: FloatArray, qd: FloatArray, qdd: FloatArray) -> FloatArray:
    """(m, n) torques of the rigid-body dynamics (rotors included, no friction) at the m rows of q, q̇, q̈."""
    m, n = q.shape
    kernel = dyn.kernel
    if isinstance(kernel, PinocchioKernel) and hasattr(pin, "rneaInParallel") and hasattr(pin, "ModelPool"):
        tau = np.zeros((n, m), order="F")
        cols = [np.asfortranarray(a.T) for a in (q, qd, qdd)]
        pin.rneaInParallel(1, pin.ModelPool(kernel.pin_model, 1), *cols, tau)
        return tau.T
    q, qd, qdd = (np.ascontiguousarray(a, dtype=float) for a in (q, qd, qdd))
    return np.array([kernel.rnea(q[k], qd[k], qdd[k]) for k in range(m)]).reshape(m, n)


def friction_torques(dyn: Dynamics, qd: FloatArray, direction: FloatArray | None = None) -> FloatArray:
    """(m, n) joint friction F_v q̇ + F_c(sgn q̇) at the rows of q̇ (as ``dyn.friction_torque``); where a row
    of q̇ is zero and ``direction`` is given, the Coulomb part takes the sign of ``direction`` (the motion about
    to start or just ended)."""
    fr = [j.friction for j in dyn.model.joints]
    fv = np.array([f.viscous for f in fr])
    fc_pos, fc_neg = np.array([f.coulomb for f in fr]), np.array([f.coulomb_neg for f in fr])
    sign = np.sign(qd)
    if direction is not None:
        sign = np.where(qd == 0.0, np.sign(direction), sign)
    return fv * qd + np.where(sign > 0, fc_pos, np.where(sign < 0, -fc_neg, 0.0))
