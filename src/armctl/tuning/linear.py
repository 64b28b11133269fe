"""Linear models and gains on python-control.

* :func:`linearize`: the arm about an equilibrium (q₀, q̇ = 0, τ₀ = g(q₀)) as a ``control.StateSpace`` with
  state (δq, δq̇) and input δτ: A = [[0, 1], [−M⁻¹ ∂g/∂q, −M⁻¹ F_v]], B = [[0], [M⁻¹]] (Coriolis terms are
  quadratic in q̇ and vanish to first order).
* :func:`pd_from_bandwidth`: K_p = ω_n², K_d = 2ζω_n for the decoupled error dynamics ë + K_d ė + K_p e = 0
  that computed torque produces.
* :func:`lqr_gains`: LQR gains (K_p, K_d) for the same double-integrator error dynamics.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from armctl._checks import scalar, vector
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError


def linearize(dyn: Dynamics, q0: ArrayLike, step: float = 1e-6) -> Any:
    """The arm linearised about q₀ at rest, as a ``control.StateSpace``: state x = (δq, δq̇), input δτ, output δq,

        A = [[0, I], [−M⁻¹ ∂g/∂q, −M⁻¹ F_v]],   B = [0; M⁻¹],   C = [I, 0],   D = 0

    (M at q₀, F_v the joints' viscous friction; Coulomb friction has no linearisation at rest).

    Parameters
    ----------
    dyn : Dynamics
        The arm.
    q0 : array_like, shape (n,)
        The pose [rad or m].
    step : float, optional
        The central-difference step of ∂g/∂q [rad].

    Returns
    -------
    control.StateSpace
    """
    import control

    q0 = vector(q0, dyn.n, "q0")
    step = scalar(step, "step", positive=True)
    if not 1e-10 <= step <= 0.1:  # below: q₀ ± step rounds to q₀ (∂g/∂q = 0); above: not a derivative
        raise InvalidParameterError(
            f"step must be in [1e-10, 0.1] rad for central differences of g, got {step:g}", value=step
        )
    n = dyn.n
    dyn.check_mass_matrix(q0)  # names a singular mass matrix
    m_inv = np.linalg.inv(dyn.mass_matrix(q0))
    dg = np.empty((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = step
        dg[:, j] = (dyn.gravity_torque(q0 + e) - dyn.gravity_torque(q0 - e)) / (2 * step)
    fv = np.diag([jt.friction.viscous for jt in dyn.model.joints])
    a = np.block([[np.zeros((n, n)), np.eye(n)], [-m_inv @ dg, -m_inv @ fv]])
    b = np.vstack([np.zeros((n, n)), m_inv])
    c = np.hstack([np.eye(n), np.zeros((n, n))])
    return control.ss(a, b, c, np.zeros((n, n)))


def pd_from_bandwidth(omega_n: float, zeta: float = 1.0) -> tuple[float, float]:
    """(K_p, K_d) = (ω_n², 2ζω_n): poles of s² + K_d s + K_p at natural frequency ω_n and damping ratio ζ.

    Parameters
    ----------
    omega_n : float
        ω_n [rad/s], > 0.
    zeta : float, optional
        ζ, > 0.

    Returns
    -------
    tuple of float
        (K_p [1/s²], K_d [1/s]).
    """
    w = scalar(omega_n, "omega_n", positive=True)
    z = scalar(zeta, "zeta", positive=True)
    kp, kd = w * w, 2 * z * w
    if not (0.0 < kp < math.inf and 0.0 < kd < math.inf):
        raise InvalidParameterError(
            f"omega_n = {w:g} rad/s with zeta = {z:g} gives gains beyond floating point (K_p = {kp:g}, K_d = {kd:g})",
            value=(omega_n, zeta),
        )
    return kp, kd


def lqr_gains(position_weight: float, velocity_weight: float = 0.0, effort_weight: float = 1.0) -> tuple[float, float]:
    """(K_p, K_d) minimising ∫ q_p e² + q_v ė² + r v² dt for ë = v (one joint; the same for every joint of a
    computed-torque loop).

    For the double integrator the Riccati equation solves in closed form: with P = [[p₁, p₂], [p₂, p₃]] and
    K = [p₂, p₃]/r, its entries give p₂² = q_p r and p₃² = r (q_v + 2 p₂), so

        K_p = √(q_p / r),   K_d = √(q_v / r + 2 K_p)

    — exact at any scale of the weights, where a general Riccati solver loses the answer (python-control's
    ``lqr`` returns K = 0 for r = 1e-16 and q_p = 1; the tests compare the two where both hold).

    Parameters
    ----------
    position_weight : float
        q_p, > 0.
    velocity_weight : float, optional
        q_v, ≥ 0.
    effort_weight : float, optional
        r, > 0.

    Returns
    -------
    tuple of float
        (K_p [1/s²], K_d [1/s]).

    Raises
    ------
    InvalidParameterError
        A weight out of range, or ratios of the weights beyond floating point.
    """
    qp = scalar(position_weight, "position_weight", positive=True)
    qv = scalar(velocity_weight, "velocity_weight", nonnegative=True)
    r = scalar(effort_weight, "effort_weight", positive=True)
    kp = math.sqrt(qp / r)
    kd = math.sqrt(qv / r + 2.0 * kp)
    if not (math.isfinite(kd) and kp > 0.0):
        raise InvalidParameterError(
            f"the weights' ratios are beyond floating point: q_p/r = {qp / r:g}, "
            f"q_v/r = {qv / r:g}; rescale position_weight, velocity_weight and "
            "effort_weight together (only their ratios matter)",
            value=(qp, qv, r),
        )
    return kp, kd


def closed_loop_poles(kp: float, kd: float) -> NDArray[np.inexact[Any]]:
    """Roots of s² + K_d s + K_p (real, or a complex pair).

    Parameters
    ----------
    kp : float
        K_p [1/s²].
    kd : float
        K_d [1/s].

    Returns
    -------
    ndarray, shape (2,)
        The poles [1/s].
    """
    return np.roots([1.0, scalar(kd, "kd"), scalar(kp, "kp")])
