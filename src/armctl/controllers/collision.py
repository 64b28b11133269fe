"""What the observer's residual tells: the collision (which link, when) and the wrench at a frame that explains it.

Isolation: an external wrench on link i gives joint torques Jᵢᵀ h on joints 1..i only (the joints beyond do not
carry it), so the last joint whose residual exceeds its threshold names the link that was hit (or one beyond it,
when the torque on the link's own joint is below its threshold).

The wrench: Jᵀ h = r has the minimum-norm solution h = (Jᵀ)⁺ r = U S⁻¹ Vᵀ r (J = U S Vᵀ); where J loses rank, a
wrench along the lost direction gives no joint torque and cannot be estimated.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armctl._checks import FloatArray, readonly
from armctl.errors import SingularConfigurationError


@dataclass(frozen=True)
class Collision:
    """A detected collision: truthy, so that ``if obs.collision:`` reads as it says.

    Attributes
    ----------
    t : float
        The update time it was detected at [s].
    joint : int
        The last joint (0-based) whose residual exceeded its threshold: the collision is on the link it moves or
        beyond.
    link : str
        That joint's name (the name of the link frame it moves).
    residual : ndarray, shape (n,)
        The residual at detection [N·m].
    """

    t: float
    joint: int
    link: str
    residual: FloatArray


def isolate(t: float, r: FloatArray, thresholds: FloatArray, names: list[str]) -> Collision | None:
    """The collision the residual shows at t (None: every |r_j| within its threshold).

    Parameters
    ----------
    t : float
        The time [s].
    r : ndarray, shape (n,)
        The residual [N·m].
    thresholds : ndarray, shape (n,)
        θ [N·m].
    names : list of str
        The joints' names.

    Returns
    -------
    Collision or None
    """
    above = np.flatnonzero(np.abs(r) > thresholds)
    if not above.size:
        return None
    j = int(above[-1])
    return Collision(t=t, joint=j, link=names[j], residual=readonly(r.copy()))


def explaining_wrench(
    jacobian: FloatArray, r: FloatArray, rcond: float, frame: str | None = None, q: FloatArray | None = None
) -> FloatArray:
    """h = (Jᵀ)⁺ r [N; N·m], the minimum-norm wrench at the frame of ``jacobian`` (6×n) whose joint torques are r.

    Parameters
    ----------
    jacobian : ndarray, shape (6, n)
        J of the frame, world-aligned axes.
    r : ndarray, shape (n,)
        The joint torques [N·m].
    rcond : float
        Singularity threshold on σ_min / σ_max over J's min(6, n) largest singular values.
    frame : str, optional
        The frame's name, for the message.
    q : ndarray, optional
        The configuration, for the message.

    Returns
    -------
    ndarray, shape (6,)

    Raises
    ------
    SingularConfigurationError
        J loses rank (the error carries σ_min and the lost direction).
    """
    u, s, vt = np.linalg.svd(jacobian, full_matrices=False)  # J = U S Vᵀ
    m = min(6, jacobian.shape[1])
    if s[m - 1] <= rcond * s[0]:
        where = "" if q is None else f" at q = {q.tolist()}"
        raise SingularConfigurationError(
            f"the Jacobian of {frame or 'the tool frame'} is singular{where} (σ_min/σ_max = {s[m - 1] / s[0]:.2e} "
            f"<= {rcond:g}): the wrench along the lost direction does not reach the joints and cannot be estimated "
            f"there; read the joint torques (obs.residual) instead",
            value=q,
            sigma_min=float(s[m - 1]),
            direction=u[:, m - 1].copy(),
        )
    return np.asarray(u[:, :m] @ ((vt[:m] @ r) / s[:m]), dtype=float)
