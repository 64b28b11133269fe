"""The adapter to toppra (TOPP-RA, Pham & Pham 2018), imported only when a problem is solved (toppra pulls in
matplotlib).

A :class:`~armctl.planning.problem.TimeScalingProblem` is handed to ``toppra.algorithm.TOPPRA`` as one
``LinearConstraint`` whose coefficients are already computed (toppra's own ``SecondOrderConstraint`` would call
the dynamics again, three times per gridpoint, through Python lambdas), with the Seidel solver. Only the
parameterization is taken from toppra: the backward pass (controllable sets K_i) and the greedy forward pass
(x_i). The output trajectory is *not* toppra's ``ParametrizeSpline``, which fits a cubic spline through the
gridpoint times and overshoots the limits between them (toppra issues #41, #56, #150); armctl's
:class:`~armctl.planning.timing.GridTiming` keeps s̈ constant over each stage, the very model TOPP-RA solves.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from toppra.algorithm import TOPPRA, ParameterizationReturnCode
from toppra.constraint import DiscretizationType, LinearConstraint, canlinear_colloc_to_interpolate
from toppra.interpolator import AbstractGeometricPath

from armctl._checks import FloatArray
from armctl.planning.path import Path

if TYPE_CHECKING:
    from armctl.planning.problem import TimeScalingProblem


class PathAdapter(AbstractGeometricPath):
    """An armctl :class:`Path` seen as a toppra geometric path on [0, 1]."""

    def __init__(self, path: Path) -> None:
        self._path = path

    def __call__(self, path_positions: Any, order: int = 0) -> FloatArray:
        return self._path(path_positions, order)

    @property
    def dof(self) -> int:
        return self._path.n

    @property
    def path_interval(self) -> FloatArray:
        return np.array([0.0, 1.0])

    def get_duration(self) -> float:  # read by toppra's Seidel wrapper (path "scaling")
        return 1.0

    @property
    def waypoints(self) -> None:
        return None


class RowsConstraint(LinearConstraint):
    """Precomputed rows a u + b x + c ≤ g (F = I) and 0 ≤ x ≤ x_max, valid on one grid only."""

    def __init__(
        self,
        s: FloatArray,
        a: FloatArray,
        b: FloatArray,
        c: FloatArray,
        g: FloatArray,
        x_max: FloatArray,
        interpolation: bool,
    ) -> None:
        super().__init__()
        self._s, self._a, self._b, self._c, self._g = s, a, b, c, g
        self._xbound = np.stack([np.zeros_like(x_max), x_max], axis=1)
        self.dof = a.shape[1]
        self.identical = True
        self.set_discretization_type(
            DiscretizationType.Interpolation if interpolation else DiscretizationType.Collocation
        )
        self._format_string = f"    armctl rows: {a.shape[1]}\n"

    def compute_constraint_params(self, path: Any, gridpoints: FloatArray, *args: Any, **kwargs: Any) -> tuple:
        if gridpoints.shape != self._s.shape or not np.array_equal(gridpoints, self._s):
            raise ValueError("RowsConstraint was built on another grid")
        if self.dof == 0:
            return None, None, None, None, None, None, self._xbound
        eye = np.eye(self.dof)
        if self.discretization_type == DiscretizationType.Interpolation:
            # toppra's helper takes and returns the bounds as (.., xbound, ubound) while the constraint API
            # returns (.., ubound, xbound): passing (None, xbound) gives back (None, xbound) as required
            return canlinear_colloc_to_interpolate(
                self._a, self._b, self._c, eye, self._g, None, self._xbound, gridpoints, identical=True
            )
        return self._a, self._b, self._c, eye, self._g, None, self._xbound


@dataclass(frozen=True)
class ToppraOutput:
    """What toppra returned: ``code`` (its ParameterizationReturnCode name), ``x`` = ṡ² at the gridpoints
    (N+1,) or None, ``K`` the controllable sets (N+1, 2) (NaN rows where the backward pass failed)."""

    code: str
    x: FloatArray | None
    K: FloatArray | None

    @property
    def ok(self) -> bool:
        return self.code == "Ok"


def run_toppra(problem: TimeScalingProblem, rows: tuple[FloatArray, FloatArray, FloatArray]) -> ToppraOutput:
    """TOPP-RA, rest to rest, on ``problem`` with the row coefficients ``rows`` = (a, b, c) (its own, or their
    linearisation, :meth:`~armctl.planning.problem.TimeScalingProblem.linearized`; see :class:`RowsConstraint`)."""
    interpolation = problem.discretization == "interpolation"
    cons = RowsConstraint(problem.s, *rows, problem.g, problem.x_max, interpolation)
    algo = TOPPRA([cons], PathAdapter(problem.path), gridpoints=problem.s, solver_wrapper="seidel")
    _, sd, _, K = algo.compute_parameterization(0.0, 0.0, return_data=True)
    code = algo.problem_data.return_code
    x = None if sd is None else np.asarray(sd, dtype=float) ** 2
    return ToppraOutput(
        code.name if isinstance(code, ParameterizationReturnCode) else str(code),
        x,
        None if K is None else np.asarray(K, dtype=float),
    )
