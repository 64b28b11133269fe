"""The dynamic model of a frame in the operational space, and its dynamic manipulability ellipsoid.

For a frame with geometric Jacobian J (rows picked from [linear; angular], world-aligned axes at the frame
origin, as :meth:`~armctl.Dynamics.jacobian`) and the joint-space model M q̈ + C q̇ + g = τ, the frame's
acceleration ẍ = J q̈ + J̇ q̇ obeys (Khatib 1987; Siciliano, Sciavicco, Villani & Oriolo, *Robotics: Modelling,
Planning and Control*, 2009, §7.8)

    Λ(q) ẍ + μ(q, q̇) + p(q) = F,        τ = Jᵀ F,

    Λ = (J M⁻¹ Jᵀ)⁻¹,   J̄ = M⁻¹ Jᵀ Λ,   μ = J̄ᵀ C q̇ − Λ J̇ q̇,   p = J̄ᵀ g.

J̄ is the dynamically consistent generalised inverse of J (J J̄ = I). For any joint torque τ (a redundant arm's
null-space torques included), Λ ẍ + μ + p = J̄ᵀ τ: J̄ᵀ τ is the force that τ is worth at the frame.

The dynamic manipulability ellipsoid (Yoshikawa 1985; Siciliano et al. §7.9) is the set of frame accelerations
that joint torques of unit norm produce once gravity and the velocity terms are compensated, ẍ = J M⁻¹ τ with
‖τ‖ ≤ 1: the image of the unit ball under J M⁻¹. Its axes are the left singular vectors of J M⁻¹ and their
lengths the singular values; Yoshikawa's measure is their product, √det(J M⁻¹ M⁻¹ Jᵀ). With ``torque_scale`` the
torques are scaled first (τ = diag(s) τ̃, ‖τ̃‖ ≤ 1), e.g. by the joints' effort limits, so that the ellipsoid
compares joints of different strength.

Only the public API of :class:`~armctl.Dynamics` is used, and Pinocchio for J̇ q̇ (the frame's classical
acceleration at q̈ = 0), on the Pinocchio model the dynamics evaluate (``pin_model``) or on the model's own
(:meth:`RobotModel.to_pinocchio`) for other backends.
"""

from __future__ import annotations

import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import lapack

from armctl._checks import FloatArray, nonnegative_vector, readonly, scalar, vector
from armctl.errors import InvalidParameterError, SingularConfigurationError

if TYPE_CHECKING:
    from armctl.dynamics.base import Dynamics
    from armctl.model.robot import RobotModel

#: names of the six rows of a frame Jacobian (linear velocity, then angular velocity, world-aligned axes)
ROW_NAMES = ("x", "y", "z", "wx", "wy", "wz")
_ROW_SETS = {"pose": (0, 1, 2, 3, 4, 5), "position": (0, 1, 2), "orientation": (3, 4, 5)}
#: default ratio σ_min/σ_max of the task Jacobian below which a configuration counts as singular
SINGULAR_TOLERANCE = 1e-6


def task_rows(rows: str | Sequence[int | str]) -> tuple[int, ...]:
    """The Jacobian rows a task uses: ``"pose"`` (all six), ``"position"``, ``"orientation"``, position axes
    such as ``"xz"`` (an arm in the x–z plane), or a sequence of row indices 0–5 or names among
    :data:`ROW_NAMES`."""
    if isinstance(rows, str):
        if rows in _ROW_SETS:
            return _ROW_SETS[rows]
        if rows in ROW_NAMES:
            return (ROW_NAMES.index(rows),)
        if rows and set(rows) <= set("xyz") and len(set(rows)) == len(rows):  # "xz": position rows x and z
            return tuple(ROW_NAMES.index(c) for c in rows)
        raise InvalidParameterError(
            f"rows must be 'pose', 'position', 'orientation' or a sequence of rows among {ROW_NAMES} "
            f"(or indices 0–5), got {rows!r}",
            value=rows,
        )
    out: list[int] = []
    try:
        items = list(rows)
    except TypeError:
        raise InvalidParameterError(f"rows must be a name or a sequence of rows, got {rows!r}", value=rows) from None
    for r in items:
        if isinstance(r, str) and r in ROW_NAMES:
            out.append(ROW_NAMES.index(r))
        elif isinstance(r, int | np.integer) and not isinstance(r, bool) and 0 <= int(r) < 6:
            out.append(int(r))
        else:
            raise InvalidParameterError(
                f"each row must be one of {ROW_NAMES} or an index 0–5, got {r!r} in {rows!r}", value=rows
            )
    if not out or len(set(out)) != len(out):
        raise InvalidParameterError(f"rows must name at least one row, each once, got {rows!r}", value=rows)
    return tuple(out)


@dataclass(frozen=True)
class OperationalSpaceModel:
    """Λ ẍ + μ + p = F for the frame ``frame`` along the Jacobian rows ``rows`` (see the module docstring).

    ``Lambda`` (m×m) [kg, kg·m, kg·m²], ``mu`` (m,) and ``p`` (m,) [N; N·m], ``Jbar`` (n×m) the dynamically
    consistent inverse M⁻¹ Jᵀ Λ, ``jacobian`` (m×n) the task Jacobian J and ``drift`` (m,) J̇ q̇ [m/s²; rad/s²]
    at (q, q̇). Every array is read-only."""

    Lambda: FloatArray
    mu: FloatArray
    p: FloatArray
    Jbar: FloatArray
    jacobian: FloatArray
    drift: FloatArray
    rows: tuple[int, ...]
    frame: str

    def acceleration(self, force: ArrayLike) -> FloatArray:
        """ẍ = Λ⁻¹ (F − μ − p): the frame's acceleration under the task force F [N; N·m] alone (τ = Jᵀ F)."""
        f = vector(force, len(self.rows), "force")
        return cast(FloatArray, np.linalg.solve(self.Lambda, f - self.mu - self.p))

    def task_force(self, tau: ArrayLike) -> FloatArray:
        """J̄ᵀ τ: the force that the joint torque τ [N·m] is worth at the frame (Λ ẍ + μ + p = J̄ᵀ τ)."""
        t = vector(tau, self.Jbar.shape[0], "tau")
        return self.Jbar.T @ t


@dataclass(frozen=True)
class DynamicManipulability:
    """The dynamic manipulability ellipsoid of a frame at q (see the module docstring).

    ``axes`` (m×m): unit principal axes as columns, longest first; ``lengths`` (m,): their semi-axis lengths
    [m/s² or rad/s² per unit torque norm]; ``measure``: Yoshikawa's √det(J M⁻¹ M⁻¹ Jᵀ), the product of the lengths
    (0 at a singular configuration); ``rows``, ``frame``: the task; ``center`` (3,): the frame's position [m]."""

    axes: FloatArray
    lengths: FloatArray
    measure: float
    rows: tuple[int, ...]
    frame: str
    center: FloatArray

    @property
    def isotropy(self) -> float:
        """Shortest over longest semi-axis, in [0, 1]: 1 for a sphere, 0 at a singularity."""
        top = float(self.lengths[0])
        return float(self.lengths[-1]) / top if top > 0 else 0.0


# per RobotModel, a Pinocchio model and its workspace for J̇ q̇ when the dynamics hold none (other backends)
_PIN_CACHE: weakref.WeakKeyDictionary[RobotModel, tuple[Any, Any]] = weakref.WeakKeyDictionary()


def _pinocchio_pair(dyn: Dynamics) -> tuple[Any, Any]:
    pm = getattr(dyn, "pin_model", None)
    model = dyn.model
    if pm is not None:
        cached = _PIN_CACHE.get(model)
        if cached is None or cached[0] is not pm:
            cached = _PIN_CACHE[model] = (pm, pm.createData())  # own workspace: the dynamics' is theirs
        return cached
    cached = _PIN_CACHE.get(model)
    if cached is None:
        pm = model.to_pinocchio()
        cached = _PIN_CACHE[model] = (pm, pm.createData())
    return cached


def frame_drift(dyn: Dynamics, q: FloatArray, qd: FloatArray, frame: str | None = None) -> FloatArray:
    """J̇ q̇ (6,) of ``frame``: its classical acceleration at q̈ = 0, [linear; angular] in world-aligned axes
    [m/s²; rad/s²], so that d/dt (J q̇) = J q̈ + J̇ q̇."""
    import pinocchio as pin

    name = dyn.model.frame(frame).name
    if name == "world":
        return np.zeros(6)
    pm, pd = _pinocchio_pair(dyn)
    pin.forwardKinematics(pm, pd, q, qd, np.zeros(dyn.n))
    fid = pm.getFrameId(name)
    return np.array(pin.getFrameClassicalAcceleration(pm, pd, fid, pin.LOCAL_WORLD_ALIGNED).vector)


def _task_jacobian(dyn: Dynamics, q: FloatArray, frame: str | None, rows: tuple[int, ...], tolerance: float) -> Any:
    """J (rows of the frame Jacobian at q), checked for full row rank: σ_min/σ_max ≥ ``tolerance``."""
    jac = dyn.jacobian(q, frame)[list(rows)]
    u, s, _ = np.linalg.svd(jac)
    smax = float(s[0]) if s.size else 0.0
    smin = float(s[-1]) if len(s) == len(rows) else 0.0
    if len(rows) > dyn.n or smax == 0.0 or smin < tolerance * smax:
        names = [ROW_NAMES[r] for r in rows]
        direction = u[:, -1]
        worst = ", ".join(f"{c:+.2f} {nm}" for c, nm in zip(direction, names, strict=True) if abs(c) > 0.05)
        rank = int(np.count_nonzero(s > tolerance * smax)) if smax > 0 else 0
        lost = len(rows) - rank
        which = f"({worst})" if lost == 1 else f"{lost} directions, among them ({worst})"
        name = dyn.model.frame(frame).name
        raise SingularConfigurationError(
            f"the Jacobian of frame {name!r} along rows {names} is singular at q = {np.round(q, 4).tolist()}: "
            f"smallest singular value {smin:.3g} (largest {smax:.3g}, rank {rank} of {len(rows)}); the arm cannot "
            f"accelerate the frame along {which}. Move q away from the singularity, ask for fewer rows "
            "(rows='position', or the rows the arm can move, e.g. rows='xz' for an arm in the x–z plane), or "
            "lower singular_tolerance to accept an ill-conditioned Λ",
            value=q,
            sigma_min=smin,
            direction=direction,
        )
    return jac


def operational_space_terms(
    mass: FloatArray,
    jacobian: FloatArray,
    drift: FloatArray,
    coriolis: FloatArray,
    gravity: FloatArray,
    damping: float = 0.0,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """(Λ, J̄, μ, p) from the joint-space terms at one state: M (n×n), the task Jacobian J (m×n, full row rank),
    J̇ q̇ (m,), C q̇ (n,) and g (n,). Unchecked (for a controller that has these terms already and calls it at
    every step); raises ``numpy.linalg.LinAlgError`` if M is not positive definite, or J M⁻¹ Jᵀ is singular.

    ``damping`` δ² ≥ 0 [the units of J M⁻¹ Jᵀ] gives the damped inverse Λ = (J M⁻¹ Jᵀ + δ² I)⁻¹ (still
    J̄ = M⁻¹ Jᵀ Λ, μ and p from it), bounded by 1/δ² where J loses rank; then J J̄ = I − δ² Λ instead of I, and
    the task's equation holds only along the directions whose eigenvalue of J M⁻¹ Jᵀ is large against δ²."""
    # LAPACK directly: one Cholesky factor M = L Lᵀ gives both J M⁻¹ Jᵀ and M⁻¹ Jᵀ by triangular solves (which
    # NumPy's linalg does not offer), and the info codes say which of M and J M⁻¹ Jᵀ failed
    chol, info = lapack.dpotrf(mass, lower=1, clean=1)  # M = L Lᵀ
    if info:
        raise np.linalg.LinAlgError("the mass matrix is not positive definite")
    a, _ = lapack.dtrtrs(chol, jacobian.T, lower=1)  # L⁻¹ Jᵀ, so that J M⁻¹ Jᵀ = aᵀ a
    lam_inv = a.T.dot(a)
    if damping:
        lam_inv.flat[:: lam_inv.shape[0] + 1] += damping
    _, _, lam, info = lapack.dgesv(lam_inv, np.eye(lam_inv.shape[0]))  # LU: fails only if singular outright
    if info:
        raise np.linalg.LinAlgError("J M⁻¹ Jᵀ is singular")
    lam = 0.5 * (lam + lam.T)
    minv_jt, _ = lapack.dtrtrs(chol, a, lower=1, trans=1)  # L⁻ᵀ L⁻¹ Jᵀ = M⁻¹ Jᵀ
    jbar = minv_jt.dot(lam)  # M⁻¹ Jᵀ Λ
    return lam, jbar, jbar.T.dot(coriolis) - lam.dot(drift), jbar.T.dot(gravity)


def operational_space_model(
    dyn: Dynamics,
    q: ArrayLike,
    qd: ArrayLike,
    frame: str | None = None,
    rows: str | Sequence[int | str] = "pose",
    singular_tolerance: float = SINGULAR_TOLERANCE,
) -> OperationalSpaceModel:
    """Λ, μ, p and J̄ of ``frame`` (default: the tool frame) at (q, q̇) [rad, rad/s] along ``rows`` (see
    :func:`task_rows`; ``"position"`` gives the 3×3 model of the frame origin).

    Raises
    ------
    SingularConfigurationError
        if the task Jacobian's σ_min/σ_max is below ``singular_tolerance`` (or it has more rows than the arm has
        joints): the error gives the smallest singular value and the direction the arm cannot accelerate in.
    """
    q = vector(q, dyn.n, "q")
    qd = vector(qd, dyn.n, "qd")
    rws = task_rows(rows)
    tol = scalar(singular_tolerance, "singular_tolerance", nonnegative=True)
    jac = _task_jacobian(dyn, q, frame, rws, tol)
    mass = dyn.mass_matrix(q)
    drift = frame_drift(dyn, q, qd, frame)[list(rws)]
    try:
        lam, jbar, mu, p = operational_space_terms(
            mass, jac, drift, dyn.coriolis_matrix(q, qd) @ qd, dyn.gravity_torque(q)
        )
    except np.linalg.LinAlgError:
        raise InvalidParameterError(
            f"the mass matrix of {dyn.model.name!r} is not positive definite at q = {q.tolist()} (smallest "
            f"eigenvalue {np.linalg.eigvalsh(mass).min():.3g}): give every moving link mass and inertia",
            value=q,
        ) from None
    name = dyn.model.frame(frame).name
    return OperationalSpaceModel(
        readonly(lam), readonly(mu), readonly(p), readonly(jbar), readonly(jac), readonly(drift), rws, name
    )


def dynamic_manipulability(
    dyn: Dynamics,
    q: ArrayLike,
    frame: str | None = None,
    rows: str | Sequence[int | str] = "pose",
    torque_scale: ArrayLike | str | None = None,
) -> DynamicManipulability:
    """The dynamic manipulability ellipsoid of ``frame`` at q along ``rows`` (see the module docstring). Along
    rows the arm cannot move the frame (the six rows of a planar arm) the ellipsoid is flat: zero lengths and a
    zero measure; pick the rows it can move (``rows="xz"``).

    ``torque_scale``: None (unit-norm torques, as Siciliano), ``"limits"`` (the joints' effort limits [N·m]), or
    a scalar or (n,) vector of scales s > 0: the ellipsoid is then the image of ‖diag(s)⁻¹ τ‖ ≤ 1.
    """
    q = vector(q, dyn.n, "q")
    rws = task_rows(rows)
    if isinstance(torque_scale, str):
        if torque_scale != "limits":
            raise InvalidParameterError(
                f"torque_scale must be None, 'limits' or positive scales, got {torque_scale!r}", value=torque_scale
            )
        scale = np.array([j.limits.effort for j in dyn.model.joints])
        if not np.isfinite(scale).all():
            missing = [j.name for j in dyn.model.joints if not np.isfinite(j.limits.effort)]
            raise InvalidParameterError(
                f"torque_scale='limits' needs effort limits, and joints {missing} have none: give the scales "
                "explicitly or set JointLimits(effort=...)",
                value=torque_scale,
            )
    elif torque_scale is None:
        scale = np.ones(dyn.n)
    else:
        scale = nonnegative_vector(torque_scale, dyn.n, "torque_scale")
        if (scale <= 0).any():
            raise InvalidParameterError(f"torque_scale must be > 0, got {scale.tolist()}", value=torque_scale)
    jac = dyn.jacobian(q, frame)[list(rws)]
    a = jac @ np.linalg.solve(dyn.mass_matrix(q), np.diag(scale))  # J M⁻¹ diag(s)
    u, s, _ = np.linalg.svd(a)
    lengths = np.zeros(len(rws))
    lengths[: len(s)] = s[: len(rws)]
    axes = u[:, : len(rws)]
    for k in range(axes.shape[1]):  # a sign convention: each axis points to its largest entry's positive side
        if axes[np.argmax(np.abs(axes[:, k])), k] < 0:
            axes[:, k] = -axes[:, k]
    center = dyn.frame_pose(q, frame)[:3, 3].copy()
    name = dyn.model.frame(frame).name
    return DynamicManipulability(
        readonly(axes), readonly(lengths), float(np.prod(lengths)), rws, name, readonly(center)
    )
