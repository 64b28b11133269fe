"""Bounds on the dynamic model over the joint ranges: the constants the classic stability proofs use.

For q in the joint ranges and any vectors (Kelly, Santibáñez & Loría, *Control of Robot Manipulators in Joint
Space*, Springer 2005, ch. 4; the inertia bounds also in Spong, Hutchinson & Vidyasagar, *Robot Modeling and
Control*, 2006, ch. 7):

    λ_m I ≤ M(q) ≤ λ_M I                                           λ_m, λ_M  [kg·m²]
    ‖g(x) − g(y)‖ ≤ k_g ‖x − y‖,   k_g ≥ sup ‖∂g/∂q‖              k_g       [N·m/rad]
    ‖C(q, x) y‖ ≤ k_C ‖x‖ ‖y‖                                      k_C       [kg·m²]
    ‖M(x) z − M(y) z‖ ≤ k_M ‖x − y‖ ‖z‖                            k_M       [kg·m²/rad]

(‖·‖ the Euclidean norm, and for matrices the spectral norm). :func:`model_bounds` finds them by two routes:

* ``"sampled"``: the extremes over a large sample of the ranges, refined by local optimisation
  (:mod:`armctl.tuning.bound_search`). Each value is attained at the point reported, so it is an estimate
  from inside: the true λ_m may be lower, the true λ_M, k_g, k_C, k_M higher.
* ``"certified"``, for arms whose joints are all revolute: M and the potential energy are trigonometric
  polynomials of the angles, known exactly from samples, and a branch and bound over boxes of the ranges
  turns them into rigorous bounds (:mod:`armctl.tuning.bound_certificate`). Each is reported with the sampled
  extreme beside it, so how loose it is shows: :attr:`Bound.looseness`.

A revolute joint without limits ranges over one turn; for a wider range the turn is enough (the model is
periodic in the angle). Prismatic joints need finite limits or ``joint_ranges``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, readonly, real_array, scalar, whole_number
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError, ShapeError
from armctl.tuning.bound_search import QUANTITIES, SENSE, search_extremes

METHODS = ("auto", "sampled", "certified")
#: ``method="auto"`` certifies when M depends on at most this many angles (the certificate splits boxes in as
#: many dimensions, and its cost grows quickly with them: the Puma 560's four take seconds, the Panda's six do
#: not converge within the default budget)
AUTO_CERTIFY_ANGLES = 4
_UNITS = {"lambda_min": "kg·m²", "lambda_max": "kg·m²", "k_g": "N·m/rad", "k_c": "kg·m²", "k_m": "kg·m²/rad"}
_LABELS = {"lambda_min": "λ_m", "lambda_max": "λ_M", "k_g": "k_g", "k_c": "k_C", "k_m": "k_M"}


@dataclass(frozen=True)
class Bound:
    """One constant over the ranges.

    Attributes
    ----------
    name : str
        Which constant (``"lambda_min"``, ``"lambda_max"``, ``"k_g"``, ``"k_c"``, ``"k_m"``).
    value : float
        The bound the conditions use — certified if :attr:`certified`, else the sampled estimate.
    estimate : float
        The most extreme value found at a point.
    attained_at : ndarray, shape (n,)
        That point [rad or m].
    certified : bool
        ``value`` is a certified bound.
    side : str
        ``"lower"`` (λ_m) or ``"upper"`` (the others).
    boxes : int
        Boxes the certificate evaluated (0 for an estimate).
    converged : bool
        The certificate reached the tolerance asked for within its budget.
    """

    name: str
    value: float
    estimate: float
    attained_at: FloatArray
    certified: bool
    side: str
    boxes: int = 0
    converged: bool = True

    @property
    def looseness(self) -> float:
        """|value − estimate| / |estimate|: how far a certified bound lies outside the extreme actually met
        (0 for an estimate; inf where the estimate is 0 and the bound is not)."""
        gap = abs(self.value - self.estimate)
        if gap == 0.0:
            return 0.0
        return gap / abs(self.estimate) if self.estimate != 0.0 else math.inf

    @property
    def informative(self) -> bool:
        """False for a lower bound of the inertia that is not positive (a certificate that ran out of boxes)."""
        return not (self.side == "lower" and self.value <= 0.0)


@dataclass(frozen=True)
class ModelBounds:
    """The constants of the textbook stability conditions of an arm over its joint ranges.

    Attributes
    ----------
    lambda_min, lambda_max : float
        λ_m, λ_M [kg·m²]: bounds on the eigenvalues of M(q).
    k_g : float
        [N·m/rad]: a bound on ‖∂g/∂q‖.
    k_c : float
        k_C [kg·m²]: ‖C(q, q̇)‖ ≤ k_C ‖q̇‖.
    k_m : float
        k_M [kg·m²/rad]: a Lipschitz constant of M(q).
    joint_ranges : ndarray, shape (n, 2)
        The ranges [rad or m].
    method : str
        ``"sampled"`` or ``"certified"``.
    model : str
        The arm's name.
    details : dict of str to Bound
        Each constant's :class:`Bound` (estimate, where it is attained, certified or not).
    """

    lambda_min: float
    lambda_max: float
    k_g: float
    k_c: float
    k_m: float
    joint_ranges: FloatArray
    method: str
    model: str
    details: dict[str, Bound] = field(repr=False)

    @property
    def certified(self) -> bool:
        """True if every constant is a certified bound."""
        return all(b.certified for b in self.details.values())

    def where(self, name: str) -> FloatArray:
        """The configuration at which the estimate of a constant is attained.

        Parameters
        ----------
        name : str
            ``"lambda_min"``, ``"lambda_max"``, ``"k_g"``, ``"k_c"`` or ``"k_m"``.

        Returns
        -------
        ndarray, shape (n,)

        Raises
        ------
        InvalidParameterError
            Another name.
        """
        if name not in self.details:
            raise InvalidParameterError(f"no constant {name!r}; the constants are {QUANTITIES}", value=name)
        return self.details[name].attained_at

    def summary(self) -> str:
        """A table: each constant, its bound, the extreme met and where, certified or estimated.

        Returns
        -------
        str
        """
        lines = [f"{self.model}: bounds over the joint ranges ({self.method})"]
        for name in QUANTITIES:
            b = self.details[name]
            kind = "certified" if b.certified else "estimate"
            extra = ""
            if b.certified:
                loose = b.looseness
                extra = f", extreme met {b.estimate:.5g}" + (f", {100 * loose:.2g} % looser" if loose < 1e3 else "")
                if not b.informative:
                    extra += "; not informative"
            if b.certified and not b.converged:
                extra += f" (budget of {b.boxes} boxes spent)"
            lines.append(
                f"  {_LABELS[name]:4s} = {b.value:.5g} {_UNITS[name]} ({kind}{extra}) at q = "
                f"{np.round(b.attained_at, 3).tolist()}"
            )
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.summary()


def joint_box(dyn: Dynamics, joint_ranges: ArrayLike | None) -> tuple[FloatArray, FloatArray]:
    """(lower, upper) of the ranges: ``joint_ranges`` (n×2) or the model's limits; a revolute joint without
    limits, or with a range over a turn, spans one turn."""
    n = dyn.n
    if joint_ranges is None:
        lo = np.array([j.limits.lower for j in dyn.model.joints], dtype=float)
        hi = np.array([j.limits.upper for j in dyn.model.joints], dtype=float)
    else:
        box = real_array(joint_ranges, "joint_ranges")
        if box.shape != (n, 2):
            raise ShapeError(
                f"joint_ranges must have shape ({n}, 2) (lower, upper per joint), got {box.shape}", value=box
            )
        if np.isnan(box).any() or (box[:, 0] > box[:, 1]).any():
            raise InvalidParameterError(
                f"joint_ranges must hold lower <= upper per joint, got {box.tolist()}", value=box
            )
        lo, hi = box[:, 0].copy(), box[:, 1].copy()
    for i, j in enumerate(dyn.model.joints):
        if j.kind == "revolute":
            if not np.isfinite(lo[i]) and not np.isfinite(hi[i]):
                lo[i], hi[i] = -math.pi, math.pi
            elif not np.isfinite(lo[i]):
                lo[i] = hi[i] - 2 * math.pi
            elif not np.isfinite(hi[i]):
                hi[i] = lo[i] + 2 * math.pi
            hi[i] = min(hi[i], lo[i] + 2 * math.pi)
        elif not (np.isfinite(lo[i]) and np.isfinite(hi[i])):
            raise InvalidParameterError(
                f"prismatic joint {j.name!r} has no finite range ({lo[i]}, {hi[i]}): give joint_ranges", value=j.name
            )
    return lo, hi


def model_bounds(
    dynamics: Dynamics,
    joint_ranges: ArrayLike | None = None,
    *,
    method: str = "auto",
    samples: int = 2000,
    refine: int = 3,
    seed: int = 0,
    tolerance: float = 0.02,
    max_boxes: int = 20000,
) -> ModelBounds:
    """λ_m, λ_M, k_g, k_C, k_M of ``dynamics`` over ``joint_ranges`` (n×2; default: the joint limits).

    Parameters
    ----------
    dynamics
        The arm's :class:`~armctl.Dynamics` (any backend).
    joint_ranges
        (n, 2) lower and upper bound per joint [rad or m]; None: the model's limits (see :func:`joint_box`).
    method
        ``"sampled"`` (estimates), ``"certified"`` (rigorous bounds; all-revolute arms), or ``"auto"``: certified
        for an all-revolute arm whose M depends on at most four angles (:data:`AUTO_CERTIFY_ANGLES`: the
        planar arms, the Puma 560), else sampled.
    samples, refine, seed
        The sampled route: ``samples`` configurations (uniform over the ranges, from ``seed``), then ``refine``
        local optimisations from the best of them per constant. The certified route runs it too, to report
        how loose each bound is.
    tolerance, max_boxes
        The certified route: stop splitting when each bound is within ``tolerance`` (relative) of the extreme
        met at a box centre, or after ``max_boxes`` boxes per constant; the bound holds either way, and
        :attr:`Bound.converged` says which.

    Returns
    -------
    ModelBounds

    Raises
    ------
    InvalidParameterError
        ``method="certified"`` on an arm with prismatic joints, or a model that is not the trigonometric
        polynomial of its angles that revolute joints give; unknown method; bad ranges.
    """
    if not isinstance(dynamics, Dynamics):
        raise InvalidParameterError(
            f"model_bounds needs an armctl.Dynamics, got {type(dynamics).__name__}", value=dynamics
        )
    if method not in METHODS:
        raise InvalidParameterError(f"method must be one of {METHODS}, got {method!r}", value=method)
    samples = whole_number(samples, "samples", 1)
    refine = whole_number(refine, "refine")
    tolerance = scalar(tolerance, "tolerance", positive=True)
    max_boxes = whole_number(max_boxes, "max_boxes", 1)
    seed = whole_number(seed, "seed")
    lo, hi = joint_box(dynamics, joint_ranges)
    revolute = all(j.kind == "revolute" for j in dynamics.model.joints)
    if method == "auto":
        method = "sampled"
        if revolute:
            from armctl.tuning.trig_poly import depends_on

            angles = depends_on(dynamics.mass_matrix, dynamics.n, np.random.default_rng(seed))
            method = "certified" if len(angles) <= AUTO_CERTIFY_ANGLES else "sampled"
    found = search_extremes(dynamics, lo, hi, samples, refine, seed)
    details: dict[str, Bound] = {}
    if method == "sampled":
        for name in QUANTITIES:
            value, q = found[name]
            side = "lower" if SENSE[name] < 0 else "upper"
            details[name] = Bound(name, value, value, readonly(q), False, side)
    else:
        details = _certified(dynamics, lo, hi, found, tolerance, max_boxes, seed)
    return ModelBounds(
        details["lambda_min"].value,
        details["lambda_max"].value,
        details["k_g"].value,
        details["k_c"].value,
        details["k_m"].value,
        joint_ranges=readonly(np.column_stack([lo, hi])),
        method=method,
        model=dynamics.model.name,
        details=details,
    )


def _certified(
    dyn: Dynamics,
    lo: FloatArray,
    hi: FloatArray,
    found: dict[str, tuple[float, FloatArray]],
    tolerance: float,
    max_boxes: int,
    seed: int,
) -> dict[str, Bound]:
    from armctl.tuning.bound_certificate import RevoluteModel

    arm = RevoluteModel(dyn, seed)
    certs: dict[str, Any] = {
        "lambda_min": arm.inertia(lo, hi, -1, found["lambda_min"][0], tolerance, max_boxes),
        "lambda_max": arm.inertia(lo, hi, 1, found["lambda_max"][0], tolerance, max_boxes),
        "k_g": arm.gravity(lo, hi, found["k_g"][0], tolerance, max_boxes),
        "k_c": arm.stacked_norm(lo, hi, "coriolis", tolerance, max_boxes),
        "k_m": arm.stacked_norm(lo, hi, "mass", tolerance, max_boxes),
    }
    out = {}
    for name in QUANTITIES:
        value, q = found[name]
        cert = certs[name]
        if (
            name in ("lambda_min", "lambda_max", "k_g")
            and cert.where is not None
            and SENSE[name] * (cert.best - value) > 0
        ):
            value, q = cert.best, cert.where  # a box centre beat the sampled search: report it
        bound = min(cert.bound, value) if SENSE[name] < 0 else max(cert.bound, value)
        side = "lower" if SENSE[name] < 0 else "upper"
        out[name] = Bound(
            name, float(bound), float(value), readonly(np.array(q)), True, side, cert.boxes, cert.converged
        )
    return out
