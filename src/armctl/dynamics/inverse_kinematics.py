"""Inverse kinematics: a joint vector within the joint limits that puts a frame at a target pose or position, by
a damped least-squares (Levenberg–Marquardt) iteration on the library's own frame Jacobian.

With the target (p_t, R_t) and the frame's pose (p, R) at q, the residual and its Jacobian are::

    e(q) = [p_t − p;  log(R_t Rᵀ)]                  (6,), world axes [m; rad]
    ∂e/∂q = −[J_v;  J_log(R_t Rᵀ) J_ω]             J_v, J_ω: the frame Jacobian's rows [linear; angular]

(J_log the Jacobian of SO(3)'s logarithm: ``pinocchio.Jlog3``), only the position rows for a position target.
Each iteration solves

    (Aᵀ A + μ I) Δq = Aᵀ e,        A = −∂e/∂q restricted to the free joints

and takes q ← clip(q + Δq, lower, upper) if it lowers ‖e‖, with μ divided by 3 (a Gauss–Newton step as μ → 0);
otherwise it multiplies μ by 4 and tries again. A joint is free unless it sits at a limit and the step pushes it
beyond (an active set, updated every iteration), so the iterate never leaves the joint limits. It stops when
‖e_pos‖ and ‖e_rot‖ are both within the tolerance. A start that stalls (μ past 10⁸, or the iteration budget
spent) is followed by another from a random configuration within the limits (a seeded generator: the result is
repeatable); when every start fails, :class:`~armctl.errors.InverseKinematicsError` names the smallest residual
found.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, real_array, scalar, vector, whole_number
from armctl.errors import InvalidParameterError, InverseKinematicsError, ShapeError, UnknownNameError
from armctl.model.named_poses import zero_pose

if TYPE_CHECKING:
    from armctl.dynamics.base import Dynamics
    from armctl.dynamics.kernel import Kernel

#: the rows an inverse kinematics problem can ask for
ROWS = ("pose", "position")
#: the damping μ past which a start counts as stalled
_MU_MAX = 1e8


@dataclass
class _Best:
    """The smallest residual found so far, over every start."""

    q: FloatArray
    error: FloatArray
    size: float = math.inf


def _target(target_pose: ArrayLike) -> tuple[FloatArray, FloatArray | None]:
    """(p_t, R_t or None) of a 4×4 pose or a 3-vector position."""
    t = real_array(target_pose, "target_pose")
    if t.shape == (3,):
        p, rot = t, None
    elif t.shape == (4, 4):
        p, rot = t[:3, 3], t[:3, :3]
        if not np.allclose(t[3], (0.0, 0.0, 0.0, 1.0)) or not np.allclose(rot @ rot.T, np.eye(3), atol=1e-6):
            raise InvalidParameterError(
                "target_pose must be a homogeneous pose (an orthonormal rotation, last row [0, 0, 0, 1]) or a "
                f"position (3,), got {t.tolist()}",
                value=target_pose,
            )
        if np.linalg.det(rot) < 0.0:
            raise InvalidParameterError("target_pose's rotation is a reflection (det R = −1)", value=target_pose)
    else:
        raise ShapeError(
            f"target_pose must be a 4×4 pose or a position of shape (3,), got shape {t.shape}", value=target_pose
        )
    if not np.isfinite(t).all():
        raise InvalidParameterError("target_pose must be finite", value=target_pose)
    return np.array(p, dtype=float), None if rot is None else np.array(rot, dtype=float)


def _rows(rows: str | None, has_rotation: bool, n: int) -> bool:
    """Whether the rotation is solved for."""
    if rows is None:
        return has_rotation and n >= 6
    if rows not in ROWS:
        raise UnknownNameError("rows value", rows, ROWS)
    if rows == "pose" and not has_rotation:
        raise InvalidParameterError(
            "rows='pose' needs a 4×4 target_pose; a position (3,) gives the position rows only", value=rows
        )
    return rows == "pose"


def inverse_kinematics(
    dyn: Dynamics,
    target_pose: ArrayLike,
    q0: ArrayLike | None = None,
    frame: str | None = None,
    rows: str | None = None,
    tolerance: float = 1e-10,
    max_iterations: int = 100,
    restarts: int = 20,
    seed: int = 0,
) -> FloatArray:
    """A joint vector within the joint limits that puts ``frame`` at ``target_pose`` (see
    :mod:`armctl.dynamics.inverse_kinematics` for the iteration).

    Parameters
    ----------
    dyn : Dynamics
        The arm (its frame poses and Jacobians, its joint limits); the object itself when called as the method
        ``dyn.inverse_kinematics(target_pose, ...)``.
    target_pose : array_like, shape (4, 4) or (3,)
        The frame's target: a homogeneous pose in the world [m], or a position [m] alone.
    q0 : array_like, shape (n,), optional
        The first start [rad or m], clipped into the joint limits; None: the model's named pose ``"ready"`` if it
        has one, else ``"zero"``. A start near the wanted solution picks that solution among several (elbow up or
        down, wrist flipped).
    frame : str, optional
        The frame to place (None: the tool frame).
    rows : {"pose", "position"}, optional
        What to solve for: the whole pose (6 rows) or the position (3 rows, the orientation left free). None (the
        default): the pose for a 4×4 target on an arm of 6 joints or more, the position for a position target
        and on an arm of fewer than 6 joints, which cannot place a frame in an arbitrary pose (a 4×4 target's
        rotation is then ignored; ask ``rows="pose"`` to demand it, which only poses the arm can reach satisfy).
    tolerance : float, optional
        The largest position error [m] and rotation error [rad] accepted, > 0.
    max_iterations : int, optional
        Iterations per start, ≥ 1.
    restarts : int, optional
        Further starts from random configurations within the limits, ≥ 0.
    seed : int, optional
        Seed of the random starts.

    Returns
    -------
    ndarray, shape (n,)
        q within [lower, upper] with ‖p_t − p(q)‖ ≤ tolerance and (pose rows) ‖log(R_t R(q)ᵀ)‖ ≤ tolerance.

    Raises
    ------
    InverseKinematicsError
        No start reached the target: the error carries the smallest residual found (``.residual``, [m; rad]) and
        its q (``.q``); the target may be out of reach, or reachable only outside the joint limits.
    InvalidParameterError, ShapeError, UnknownNameError
        A target that is neither a pose nor a position, an unknown frame or ``rows``, q0 of the wrong size, a
        tolerance ≤ 0, a negative number of restarts.
    """
    model = dyn.model
    n = model.n
    model.frame(frame)  # raises UnknownNameError naming the frames
    p_t, rot_t = _target(target_pose)
    with_rotation = _rows(rows, rot_t is not None, n)
    tol = scalar(tolerance, "tolerance", positive=True)
    iterations = whole_number(max_iterations, "max_iterations", minimum=1)
    extra = whole_number(restarts, "restarts", minimum=0)
    lower, upper = np.asarray(model.lower, dtype=float), np.asarray(model.upper, dtype=float)
    if q0 is None:
        start = np.array(model.named_poses.get("ready", zero_pose(lower, upper)), dtype=float)
    else:
        start = np.clip(vector(q0, n, "q0"), lower, upper)
    rng = np.random.default_rng(whole_number(seed, "seed", minimum=0))
    # random starts: uniform within the limits, and within ±π where a joint turns without limits
    lo, hi = np.maximum(lower, -math.pi), np.minimum(upper, math.pi)
    kernel = dyn.kernel
    best = _Best(start, np.full(6 if with_rotation else 3, np.inf))
    for attempt in range(extra + 1):
        q = start if attempt == 0 else rng.uniform(lo, hi)
        found = _descend(kernel, frame, q, p_t, rot_t if with_rotation else None, lower, upper, tol, iterations, best)
        if found is not None:
            return found
    err = best.error
    rot_text = f" and {float(np.linalg.norm(err[3:])):.3g} rad in orientation" if with_rotation else ""
    raise InverseKinematicsError(
        f"no joint vector within the joint limits puts {frame or 'the tool frame'} at the target: the closest found "
        f"misses it by {float(np.linalg.norm(err[:3])):.3g} m in position{rot_text} (residual "
        f"{np.round(err, 6).tolist()} [m; rad], tolerance {tol:g}) after {extra + 1} starts of up to {iterations} "
        "iterations; the target may be out of reach or reachable only outside the joint limits — check it, give a "
        "q0 near a solution, raise restarts, or ask for the position alone (rows='position')",
        value=target_pose,
        residual=err,
        q=best.q,
    )


def _residual(
    kernel: Kernel, frame: str | None, q: FloatArray, p_t: FloatArray, rot_t: FloatArray | None
) -> tuple[FloatArray, FloatArray]:
    """e(q) and the frame's pose."""
    pose = kernel.frame_pose(q, frame)
    if rot_t is None:
        return p_t - pose[:3, 3], pose
    return np.concatenate((p_t - pose[:3, 3], pin.log3(rot_t @ pose[:3, :3].T))), pose


def _descend(
    kernel: Kernel,
    frame: str | None,
    q: FloatArray,
    p_t: FloatArray,
    rot_t: FloatArray | None,
    lower: FloatArray,
    upper: FloatArray,
    tol: float,
    iterations: int,
    best: _Best,
) -> FloatArray | None:
    """One start's iteration: the solution, or None (``best`` updated with the closest point it reached)."""
    e, pose = _residual(kernel, frame, q, p_t, rot_t)
    size = float(e @ e)
    mu = 1e-3
    for _ in range(iterations):
        if size < best.size:
            best.q, best.error, best.size = q.copy(), e.copy(), size
        if np.linalg.norm(e[:3]) <= tol and (rot_t is None or np.linalg.norm(e[3:]) <= tol):
            return q
        jac = kernel.jacobian(q, frame)
        if rot_t is None:
            a = jac[:3]
        else:
            a = np.vstack((jac[:3], pin.Jlog3(rot_t @ pose[:3, :3].T) @ jac[3:]))
        g = a.T @ e
        # free joints: not at a limit with the step (its gradient direction) pushing beyond it
        free = ~(((q <= lower) & (g < 0.0)) | ((q >= upper) & (g > 0.0)))
        if not free.any():  # every joint pinned at a limit the target lies beyond
            return None
        af = a[:, free]
        h = af.T @ af
        while True:
            step = np.zeros_like(q)
            step[free] = np.linalg.solve(h + mu * np.eye(h.shape[0]), g[free])
            q_new = np.clip(q + step, lower, upper)
            e_new, pose_new = _residual(kernel, frame, q_new, p_t, rot_t)
            size_new = float(e_new @ e_new)
            if size_new < size:
                q, e, pose, size = q_new, e_new, pose_new, size_new
                mu = max(mu / 3.0, 1e-12)
                break
            mu *= 4.0
            if mu > _MU_MAX:  # stalled: no step lowers the residual
                return None
    if size < best.size:
        best.q, best.error, best.size = q.copy(), e.copy(), size
    if np.linalg.norm(e[:3]) <= tol and (rot_t is None or np.linalg.norm(e[3:]) <= tol):
        return q
    return None
