"""Offline identification of an arm's dynamic parameters from measured motion.

    τ = Y(q, q̇, q̈) π = Y_b(q, q̇, q̈) θ          (θ = K π: the base, identifiable, parameters)

1. :func:`optimize_excitation` — a Fourier-series trajectory within the joint limits with a small
   condition number of the stacked base regressor;
2. :func:`prepare_data` — a log of q and τ filtered (zero phase), differentiated and decimated;
3. :func:`identify` — W θ = y stacked (:func:`build_problem`), ordinary or weighted least squares with
   standard deviations (:func:`solve_least_squares`), and a physically consistent full π and RobotModel
   (:func:`consistent_estimate`);
4. :meth:`IdentificationResult.report` and :meth:`IdentificationResult.plot` — the report.

Too little excitation raises :class:`~armctl.errors.IdentifiabilityError` with the unidentifiable directions.
"""

from armctl.dynamics.identification.base_parameters import BaseParameters, find_base_parameters
from armctl.dynamics.identification.consistency import ConsistentEstimate, consistent_estimate
from armctl.dynamics.identification.data import IdentificationData, prepare_data, settling_samples
from armctl.dynamics.identification.excitation import FourierExcitation
from armctl.dynamics.identification.excitation_design import ExcitationDesign, optimize_excitation
from armctl.dynamics.identification.identify import IdentificationResult, ValidationResult, identify
from armctl.dynamics.identification.least_squares import LeastSquaresEstimate, solve_least_squares
from armctl.dynamics.identification.problem import IdentificationProblem, build_problem
from armctl.dynamics.identification.report import format_report, validation_plot
from armctl.model.from_parameters import model_from_parameters

__all__ = [
    "BaseParameters",
    "ConsistentEstimate",
    "ExcitationDesign",
    "FourierExcitation",
    "IdentificationData",
    "IdentificationProblem",
    "IdentificationResult",
    "LeastSquaresEstimate",
    "ValidationResult",
    "build_problem",
    "consistent_estimate",
    "find_base_parameters",
    "format_report",
    "identify",
    "model_from_parameters",
    "optimize_excitation",
    "prepare_data",
    "settling_samples",
    "solve_least_squares",
    "validation_plot",
]
