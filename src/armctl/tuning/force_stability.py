"""Sampled-data stability of force control with an inner motion loop against a compliant environment: the critical
force gain as a function of the environment's stiffness.

Along the contact normal, with s the penetration [m] and f = k_e s + d_e ṡ the force the arm exerts (in contact),
the inner computed-torque loop (exact model, compensating the measured force, :class:`~armctl.controllers.ForceControl`)
leaves the frame with

    s̈ = a + (f_m − f) / Λ,      a = K_P (s_c − s_m) − K_D ṡ_m,      s_c = s_d + K_F (f_d − f_m)

where 1/Λ = (J M⁻¹ Jᵀ)_nn is the arm's mobility along the normal (how much a force there accelerates the frame),
and (s_m, ṡ_m, f_m) are measured at the samples t_k = kT, ``delay`` periods old, while (a, f_m) are held over each
period (zero-order hold). The continuous plant ẋ = A x + B (a, f_m), x = (s, ṡ),

    A = [[0, 1], [−k_e/Λ, −d_e/Λ]],     B = [[0, 0], [1, 1/Λ]],

is discretised exactly with python-control (ZOH), and the loop closed on the state augmented with the ``delay``
past samples. The loop gain is k_e K_F: the critical K_F* (spectral radius 1) falls as 1/k_e on soft surfaces, and
faster on stiff ones, where the held, delayed compensation f_m of a stiff spring acts as negative damping — beyond
a stiffness of about K_D Λ / ((delay + ½) T) no force gain is stable at all (K_F* = 0).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from armctl._checks import scalar, whole_number
from armctl.errors import InvalidParameterError
from armctl.tuning.sampled import delayed_loop_matrix


def _discrete_plant(stiffness: float, inertia: float, period: float, damping: float) -> tuple[Any, Any]:
    """(A_d, B_d) of the ZOH-sampled contact plant (python-control's ``c2d``)."""
    import control

    a = np.array([[0.0, 1.0], [-stiffness / inertia, -damping / inertia]])
    b = np.array([[0.0, 0.0], [1.0, 1.0 / inertia]])
    sys = control.c2d(control.ss(a, b, np.eye(2), np.zeros((2, 2))), period, method="zoh")
    return np.asarray(sys.A), np.asarray(sys.B)


def force_loop_matrix(
    stiffness: float,
    force_gain: float,
    kp: float,
    kd: float,
    inertia: float,
    period: float,
    delay: int = 1,
    damping: float = 0.0,
    compensate: bool = True,
) -> np.ndarray:
    """The closed loop's transition matrix on z_k = (x_k, x_{k−1}, …, x_{k−d}) (see the module).

    Parameters
    ----------
    stiffness : float
        k_e [N/m], > 0.
    force_gain : float
        K_F [m/N], ≥ 0.
    kp, kd : float
        The inner loop's K_P [1/s²] and K_D [1/s].
    inertia : float
        Λ [kg] along the normal, > 0.
    period : float
        T [s], > 0.
    delay : int, optional
        Periods of measurement delay d ≥ 0 (default 1).
    damping : float, optional
        d_e [N·s/m] of the environment, ≥ 0.
    compensate : bool, optional
        Whether the inner loop adds the measured force (default True, as ForceControl does).

    Returns
    -------
    ndarray, shape (2(d+1), 2(d+1))
    """
    k_e = scalar(stiffness, "stiffness", positive=True)
    k_f = scalar(force_gain, "force_gain", nonnegative=True)
    lam = scalar(inertia, "inertia", positive=True)
    t = scalar(period, "period", positive=True)
    d = whole_number(delay, "delay (in periods)")
    d_e = scalar(damping, "damping", nonnegative=True)
    ad, bd = _discrete_plant(k_e, lam, t, d_e)
    c_f = np.array([k_e, d_e])  # f = c_f x
    # u = (a, f_m) = G x_{k−d}:  a = −K_P (s + K_F f) − K_D ṡ  (deviations from the set-point)
    gain = np.vstack([-scalar(kp, "kp") * (np.array([1.0, 0.0]) + k_f * c_f) - np.array([0.0, scalar(kd, "kd")]),
                      c_f if compensate else np.zeros(2)])  # fmt: skip
    return delayed_loop_matrix(ad, bd @ gain, d)


def force_loop_radius(stiffness: float, force_gain: float, **loop: Any) -> float:
    """The spectral radius of :func:`force_loop_matrix` (< 1: stable).

    Parameters
    ----------
    stiffness : float
        k_e [N/m].
    force_gain : float
        K_F [m/N].
    **loop
        The other arguments of :func:`force_loop_matrix`.

    Returns
    -------
    float
    """
    return float(np.abs(np.linalg.eigvals(force_loop_matrix(stiffness, force_gain, **loop))).max())


def critical_force_gain(stiffness: float, rtol: float = 1e-6, **loop: Any) -> float:
    """K_F* [m/N]: the force gain at which the sampled force loop on an environment of stiffness k_e becomes
    unstable (0 if it is unstable at every gain, the inner loop included).

    Parameters
    ----------
    stiffness : float
        k_e [N/m].
    rtol : float, optional
        Relative tolerance of the bisection.
    **loop
        ``kp``, ``kd``, ``inertia``, ``period`` and optionally ``delay``, ``damping``, ``compensate``
        (:func:`force_loop_matrix`).

    Returns
    -------
    float

    Raises
    ------
    InvalidParameterError
        No instability up to a loop gain k_e K_F of 10⁶ (the loop is not the one modelled here).
    """
    k_e = scalar(stiffness, "stiffness", positive=True)
    if force_loop_radius(k_e, 0.0, **loop) >= 1.0:
        return 0.0
    lo, hi = 0.0, 1.0 / k_e
    while force_loop_radius(k_e, hi, **loop) < 1.0:
        lo, hi = hi, 2.0 * hi
        if hi * k_e > 1e6:
            raise InvalidParameterError(
                f"the force loop is stable up to a loop gain k_e K_F = 1e6 at k_e = {k_e:g} N/m: check the "
                f"inner loop's gains and the period",
                value=loop,
            )
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi)
        if force_loop_radius(k_e, mid, **loop) < 1.0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def normal_inertia(dynamics: Any, q: Any, normal: Any = (0.0, 0.0, 1.0), frame: str | None = None) -> float:
    """Λ [kg] along ``normal`` at q: 1 / (nᵀ J_v M⁻¹ J_vᵀ n), the inertia a force along n meets at the frame
    (J_v: the linear rows of the frame's Jacobian).

    Parameters
    ----------
    dynamics : Dynamics
        The arm's model.
    q : array_like
        The configuration [rad].
    normal : array_like, optional
        The direction (world axes; normalised).
    frame : str, optional
        The frame (None: the tool frame).

    Returns
    -------
    float
    """
    n = np.asarray(normal, dtype=float)
    n = n / np.linalg.norm(n)
    jv = dynamics.jacobian(q, frame)[:3]
    mobility = n @ jv @ np.linalg.solve(dynamics.mass_matrix(q), jv.T) @ n
    return float(1.0 / mobility)
