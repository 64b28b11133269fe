"""A :class:`~armctl.RobotModel` from a parameter vector π: the inverse of ``RobotModel.parameters()``.

Per joint, π holds m, h = m c, the inertia I_O about the joint-frame origin, k_r² I_m, F_v, F_c. The link
is rebuilt as

    c = h / m,      I_C = I_O − m (cᵀc 𝟙 − c cᵀ)        (parallel-axis theorem, backwards)

and a massless link (m ≤ 10⁻⁹ kg) keeps I_C = I_O (its first moment must then be below 10⁻⁶ kg·m, and is
dropped). The rotor keeps the model's gear
ratio (I_m = π_rotor / k_r²) so the Lagrange backend's gyroscopic term stays consistent; a joint without a
motor gets an armature if π gives it a rotor inertia (a ``Motor`` with k_r = 1 and ``gyroscopic=False``: the
reflected inertia alone, as the regressor of a joint without a motor has it). Coulomb friction:
F_c⁺ = F_c + δ, F_c⁻ = F_c − δ with δ the asymmetry (default: the model's own).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, boolean, vector
from armctl.errors import InvalidParameterError
from armctl.model.parts import JointFriction, Link, Motor
from armctl.model.robot import PARAMS_PER_JOINT, RobotModel

_MASSLESS = 1e-9  # kg: below this a link counts as massless …
_NO_MOMENT = 1e-6  # kg·m: … and its first moment must be below this (it is dropped: g·1e-6 N·m at most)


def origin_inertia(p: FloatArray) -> FloatArray:
    """I_O (3×3) from one joint's entries (Ixx, Ixy, Iyy, Ixz, Iyz, Izz) = p[4:10]."""
    xx, xy, yy, xz, yz, zz = p[4:10]
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def link_from_parameters(p: ArrayLike, physical: bool = True, name: str = "link") -> Link:
    """The :class:`~armctl.model.parts.Link` of one joint's first ten parameters (m, h, I_O); raises
    :class:`~armctl.errors.InvalidParameterError` if they are not those of a body (negative mass, a first
    moment without mass, an inertia about the centre of mass that is not positive semi-definite or, with
    ``physical``, that violates the triangle inequality)."""
    p = np.asarray(p, dtype=float)
    m, h, io = float(p[0]), p[1:4], origin_inertia(p)
    if m < -_MASSLESS:
        raise InvalidParameterError(f"{name}: mass {m:g} kg is negative", value=m)
    if m <= _MASSLESS:
        if np.abs(h).max() > _NO_MOMENT:
            raise InvalidParameterError(f"{name}: first moment {h} kg·m without mass", value=h)
        m, c, ic = 0.0, np.zeros(3), io
    else:
        c = h / m
        ic = _round_off(
            io - m * (float(c @ c) * np.eye(3) - np.outer(c, c)), 1e-10 * max(float(np.abs(io).max()), m * float(c @ c))
        )
    try:
        return Link(m, c, ic, physical)
    except InvalidParameterError as e:
        raise InvalidParameterError(f"{name}: {e}", value=p) from None


def _round_off(ic: FloatArray, tol: float) -> FloatArray:
    """I_C with the round-off of the parallel-axis subtraction (of the order of ``tol``, set by I_O) removed:
    principal moments in [−tol, 0) become 0 and a triangle inequality missed by less than tol is met."""
    w, v = np.linalg.eigh(0.5 * (ic + ic.T))
    if w[0] < -tol:
        return ic
    w = np.maximum(w, 0.0)
    if w[2] - tol <= w[0] + w[1] < w[2]:
        w[2] = w[0] + w[1]
    return (v * w) @ v.T


def model_from_parameters(
    model: RobotModel,
    pi: ArrayLike,
    coulomb_offset: ArrayLike | None = None,
    physical: bool = True,
    name: str | None = None,
) -> RobotModel:
    """A model with its inertial, rotor and friction parameters replaced by π; kinematics, limits and frames
    unchanged. ``model_from_parameters(m, m.parameters())`` rebuilds ``m``'s dynamics exactly.

    Static friction is kept where it stays above the new Coulomb levels and dropped otherwise; the Stribeck velocity
    is kept.

    Parameters
    ----------
    model : RobotModel
        The model.
    pi : array_like, shape (13 n,)
        Laid out as :meth:`RobotModel.parameters` returns them.
    coulomb_offset : array_like, shape (n,), optional
        The asymmetry δ = ½(F_c⁺ − F_c⁻) [N·m] (default: the model's own ratio δ/F̄_c of the two levels applied to
        π's Coulomb entry F̄_c, as the regressor's Coulomb column carries it, so that
        ``Dynamics(model).regressor(x) @ pi`` is the new model's inverse dynamics); both levels must stay ≥ 0.
    physical : bool, optional
        Require every link inertia to satisfy the triangle inequality (False accepts, like the published Puma 560,
        positive semi-definite tensors that do not).
    name : str, optional
        The new model's name.

    Returns
    -------
    RobotModel

    Raises
    ------
    InvalidParameterError, ShapeError
        π of the wrong size or not that of physical bodies; Coulomb levels that would be negative.
    """
    n = model.n
    physical = boolean(physical, "physical")
    p = vector(pi, PARAMS_PER_JOINT * n, "pi").reshape(n, PARAMS_PER_JOINT)
    if coulomb_offset is None:  # the model's ratio ρ = δ / F̄_c (Dynamics.coulomb_column), scaled with π's F̄_c
        pos = np.array([j.friction.coulomb for j in model.joints])
        neg = np.array([j.friction.coulomb_neg for j in model.joints])
        ratio = np.divide(pos - neg, pos + neg, out=np.zeros(n), where=pos + neg > 0)
        delta = ratio * p[:, 12]
    else:
        delta = vector(coulomb_offset, n, "coulomb_offset")
    joints = []
    for i, (j, row) in enumerate(zip(model.joints, p, strict=True)):
        label = f"joint {j.name!r}"
        link = link_from_parameters(row, physical, label)
        rotor, fv, fc = (float(v) for v in row[10:13])
        if rotor < 0 or fv < 0:
            raise InvalidParameterError(
                f"{label}: rotor inertia {rotor:g} and viscous friction {fv:g} must be >= 0", value=row[10:12]
            )
        if j.motor is not None:
            motor: Motor | None = replace(j.motor, inertia=rotor / j.motor.gear_ratio**2)
        else:
            motor = Motor(rotor, 1.0, gyroscopic=False) if rotor > 0 else None
        fp, fn = fc + delta[i], fc - delta[i]
        if min(fp, fn) < -1e-12:
            raise InvalidParameterError(f"{label}: Coulomb levels F_c ± δ = {fp:g}, {fn:g} must be >= 0", value=fc)
        fp, fn = max(fp, 0.0), max(fn, 0.0)
        static = j.friction.static if j.friction.static is not None and j.friction.static >= max(fp, fn) else None
        friction = JointFriction(fv, fp, fn, static, j.friction.stribeck_velocity)
        joints.append(replace(j, link=link, motor=motor, friction=friction))
    return replace(model, joints=tuple(joints), name=name or f"{model.name}~identified")
