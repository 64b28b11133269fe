"""`QPProblem`: one quadratic program, inspectable before it is solved.

    minimise   ½ xᵀ H x + gᵀ x
    subject to A x = b,   l ≤ C x ≤ u

with x = [q̈ (n); τ (n); f_1 (3); …; f_k (3); s (m, only with slacks)] — the blocks are named in
``variables`` — and every row of A and C named in ``eq_names`` / ``ineq_names`` (e.g. ``dynamics[panda_joint4]``,
``torque_limit[panda_joint4]``). Infinite entries of l, u mean "no bound".
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from armctl._checks import FloatArray

#: a QP as the arrays (H, g, A, b, C, l, u) of the module's formulation
Arrays = tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]


@dataclass(frozen=True)
class QPProblem:
    """The QP of one priority level at one control step (arrays are read-only)."""

    H: FloatArray
    g: FloatArray
    A: FloatArray
    b: FloatArray
    C: FloatArray
    l: FloatArray  # noqa: E741  (the name of the bound in the formulation)
    u: FloatArray
    variables: dict[str, slice]
    eq_names: tuple[str, ...]
    ineq_names: tuple[str, ...]
    level: int = 0
    tasks: tuple[str, ...] = ()
    info: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in ("H", "g", "A", "b", "C", "l", "u"):
            getattr(self, name).flags.writeable = False

    @property
    def nx(self) -> int:
        """Number of decision variables."""
        return int(self.H.shape[0])

    def block(self, x: FloatArray, name: str) -> FloatArray:
        """The part of a solution ``x`` that is the variable block ``name`` ("qdd", "tau", a contact name)."""
        return x[self.variables[name]]

    def objective(self, x: FloatArray) -> float:
        return float(0.5 * x @ self.H @ x + self.g @ x)

    def violations(self, x: FloatArray, tol: float = 1e-6) -> dict[str, float]:
        """Rows that ``x`` violates by more than ``tol`` (absolute), name → violation."""
        out: dict[str, float] = {}
        r = self.A @ x - self.b
        for i in np.flatnonzero(np.abs(r) > tol):
            out[self.eq_names[i]] = float(abs(r[i]))
        cx = self.C @ x
        over = np.maximum(cx - self.u, self.l - cx)
        for i in np.flatnonzero(over > tol):
            out[self.ineq_names[i]] = float(over[i])
        return out

    def to_qpsolvers(self) -> Any:
        """This problem as a ``qpsolvers.Problem`` (P, q, G, h, A, b): each finite bound of l ≤ C x ≤ u becomes
        one row of G x ≤ h."""
        import qpsolvers

        up = np.isfinite(self.u)
        lo = np.isfinite(self.l)
        G = np.vstack([self.C[up], -self.C[lo]])
        h = np.concatenate([self.u[up], -self.l[lo]])
        return qpsolvers.Problem(
            np.array(self.H),
            np.array(self.g),
            G if len(h) else None,
            h if len(h) else None,
            np.array(self.A) if len(self.b) else None,
            np.array(self.b) if len(self.b) else None,
        )
