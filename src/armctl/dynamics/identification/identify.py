"""`identify`: the whole offline identification of an arm, and its named results.

    data ──► build_problem (W θ = y on the base parameters) ──► solve_least_squares (OLS / WLS, σ_θ)
                                                          └──► consistent_estimate (full π, a RobotModel)

``identify(model, data)`` runs the chain; the steps are public for anyone who wants to look at a problem
before solving it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, boolean, readonly, real_array
from armctl.dynamics.base import Dynamics
from armctl.dynamics.identification.base_parameters import BaseParameters, find_base_parameters
from armctl.dynamics.identification.consistency import ConsistentEstimate, check_prior_weight, consistent_estimate
from armctl.dynamics.identification.data import IdentificationData
from armctl.dynamics.identification.least_squares import LeastSquaresEstimate, excitation_rtol, solve_least_squares
from armctl.dynamics.identification.problem import IdentificationProblem, build_problem, problem_regressor
from armctl.errors import InvalidParameterError, NonFiniteError, ShapeError
from armctl.model.robot import RobotModel

if TYPE_CHECKING:
    from matplotlib.figure import Figure


@dataclass(frozen=True)
class ValidationResult:
    """Torques predicted by an identified model against measured ones, per joint (``rms_error``,
    ``rms_torque``, ``relative_error`` = rms_error / rms_torque and ``max_error``, each (n,) [N·m], are derived).

    Attributes
    ----------
    t : ndarray, shape (S,)
        [s].
    predicted, measured : ndarray, shape (S, n)
        [N·m].
    """

    t: FloatArray
    predicted: FloatArray
    measured: FloatArray

    def __post_init__(self) -> None:
        for k in ("t", "predicted", "measured"):
            a = np.array(real_array(getattr(self, k), k))
            if not np.isfinite(a).all():
                raise NonFiniteError(f"{k} holds NaN or inf", value=a)
            object.__setattr__(self, k, readonly(a))
        m = self.measured
        if (
            m.ndim != 2
            or self.predicted.shape != m.shape
            or self.t.shape != m.shape[:1]
            or m.shape[0] < 1
            or m.shape[1] < 1
        ):
            raise ShapeError(
                f"t (S,), predicted (S, n) and measured (S, n) must match with S >= 1 samples and "
                f"n >= 1 joints; got t {self.t.shape}, predicted {self.predicted.shape}, measured "
                f"{m.shape}",
                value=(self.t.shape, self.predicted.shape, m.shape),
            )

    @property
    def rms_error(self) -> FloatArray:
        return readonly(np.sqrt(((self.predicted - self.measured) ** 2).mean(axis=0)))

    @property
    def rms_torque(self) -> FloatArray:
        return readonly(np.sqrt((self.measured**2).mean(axis=0)))

    @property
    def relative_error(self) -> FloatArray:
        return readonly(self.rms_error / np.maximum(self.rms_torque, 1e-300))

    @property
    def max_error(self) -> FloatArray:
        return readonly(np.abs(self.predicted - self.measured).max(axis=0))


@dataclass(frozen=True)
class IdentificationResult:
    """What :func:`identify` found.

    Attributes
    ----------
    model : RobotModel
        The model identification started from (kinematics, and the prior for what data cannot see).
    dynamics : Dynamics
        Its Dynamics (evaluates the regressor).
    problem : IdentificationProblem
        W θ = y.
    estimate : LeastSquaresEstimate
        The (weighted) least-squares estimate of the base parameters and Coulomb offsets.
    consistent : ConsistentEstimate or None
        The physically consistent estimate (a full π and a RobotModel), or None if not asked for.
    """

    model: RobotModel
    dynamics: Dynamics
    problem: IdentificationProblem
    estimate: LeastSquaresEstimate
    consistent: ConsistentEstimate | None

    @property
    def base(self) -> BaseParameters:
        return self.problem.base

    @property
    def condition_number(self) -> float:
        """cond of the (weighted) stacked regressor W."""
        return self.estimate.condition_number

    @property
    def identified_model(self) -> RobotModel:
        """The RobotModel of the consistent estimate (raises if it was not computed)."""
        if self.consistent is None:
            raise InvalidParameterError("no consistent estimate: run identify(..., consistent=True)", value=None)
        return self.consistent.model

    def _theta(self, consistent: bool) -> FloatArray:
        if not boolean(consistent, "consistent"):
            return self.estimate.theta
        if self.consistent is None:
            raise InvalidParameterError("no consistent estimate: run identify(..., consistent=True)", value=None)
        return self.consistent.theta

    def predict(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, consistent: bool = False) -> FloatArray:
        """Torques the estimate predicts at samples of q, q̇, q̈.

        Parameters
        ----------
        q, qd, qdd : array_like, shape (S, n)
            [rad, rad/s, rad/s²].
        consistent : bool, optional
            Use the consistent estimate instead of the least-squares one.

        Returns
        -------
        ndarray, shape (S, n)
            [N·m].
        """
        theta = self._theta(consistent)
        arrays = [np.atleast_2d(real_array(a, name)) for a, name in ((q, "q"), (qd, "qd"), (qdd, "qdd"))]
        if any(a.ndim != 2 or a.shape != arrays[0].shape or a.shape[1] != self.problem.n for a in arrays):
            raise ShapeError(
                f"q, qd, qdd must each be (S, {self.problem.n}); got {[a.shape for a in arrays]}",
                value=[a.shape for a in arrays],
            )
        for a, name in zip(arrays, ("q", "qd", "qdd"), strict=True):
            if not np.isfinite(a).all():
                raise NonFiniteError(f"{name} holds NaN or inf", value=a)
        samples_q, samples_qd, samples_qdd = arrays
        w = problem_regressor(self.dynamics, self.base, samples_q, samples_qd, samples_qdd, self.problem.offsets)
        return w @ theta

    def validate(self, data: IdentificationData, consistent: bool = False) -> ValidationResult:
        """Predicted against measured torques on (fresh) data, processed like the identification data.

        Parameters
        ----------
        data : IdentificationData
            The validation experiment.
        consistent : bool, optional
            Use the consistent estimate.

        Returns
        -------
        ValidationResult
        """
        if not isinstance(data, IdentificationData):
            raise InvalidParameterError(
                f"data must be an IdentificationData (see prepare_data), got {type(data).__name__}", value=data
            )
        theta = self._theta(consistent)
        problem = build_problem(self.dynamics, data, self.base, self.problem.offsets)
        predicted = (problem.regressor @ theta).reshape(-1, problem.n)
        return ValidationResult(data.t[list(data.kept)], predicted, problem.torque.reshape(-1, problem.n))

    def report(self, validation: ValidationResult | None = None) -> str:
        """A plain-text report: condition number, estimates ± σ, residuals per joint, validation errors.

        Parameters
        ----------
        validation : ValidationResult, optional
            Validation errors to include.

        Returns
        -------
        str
        """
        from armctl.dynamics.identification.report import format_report

        return format_report(self, validation)

    def plot(self, validation: ValidationResult, **kwargs: Any) -> Figure:
        """The validation plot (see :func:`~armctl.dynamics.identification.report.validation_plot`).

        Parameters
        ----------
        validation : ValidationResult
            From :meth:`validate`.
        **kwargs
            Passed to :func:`~armctl.dynamics.identification.report.validation_plot`.

        Returns
        -------
        matplotlib.figure.Figure
        """
        from armctl.dynamics.identification.report import validation_plot

        return validation_plot(validation, joint_names=self.model.joint_names, **kwargs)


def identify(
    model: RobotModel | Dynamics,
    data: IdentificationData | Sequence[IdentificationData],
    *,
    weighted: bool = True,
    consistent: bool = True,
    offsets: bool = True,
    base: BaseParameters | None = None,
    prior: ArrayLike | None = None,
    prior_weight: float = 1e-6,
    rtol: float = 1e-7,
) -> IdentificationResult:
    """Identify the dynamic parameters of an arm from measured data.

    Parameters
    ----------
    model : RobotModel or Dynamics
        Its kinematics are trusted; its inertial and friction parameters serve only as the prior of the
        consistent estimate.
    data : IdentificationData or sequence of IdentificationData
        One experiment or several.
    weighted : bool, optional
        WLS (per-joint noise levels) instead of OLS.
    consistent : bool, optional
        Also compute the physically consistent full π.
    offsets : bool, optional
        Estimate the Coulomb asymmetry ½(F_c⁺ − F_c⁻) of each joint.
    base : BaseParameters, optional
        Base parameters (default: found numerically).
    prior, prior_weight : optional
        See :func:`consistent_estimate`.
    rtol : float, optional
        The excitation threshold.

    Returns
    -------
    IdentificationResult

    Raises
    ------
    IdentifiabilityError
        The data do not excite some directions (named) above ``rtol``.
    """
    weighted, consistent = boolean(weighted, "weighted"), boolean(consistent, "consistent")
    offsets = boolean(offsets, "offsets")
    excitation_rtol(rtol)
    if consistent:
        check_prior_weight(prior_weight)
    dyn = model if isinstance(model, Dynamics) else Dynamics(model)
    base = base if base is not None else find_base_parameters(dyn)
    problem = build_problem(dyn, data, base, offsets)
    estimate = solve_least_squares(problem, weighted=weighted, rtol=rtol)
    cons = consistent_estimate(problem, dyn.model, estimate, prior, prior_weight) if consistent else None
    return IdentificationResult(dyn.model, dyn, problem, estimate, cons)
