"""The check of frame tasks' targets in generated code: :func:`target_verdict`.

A trajectory's output is checked at every step (:class:`~armctl.controllers.osc.tasks.target.TargetHolder`):
finite entries and, for a rotation or a pose, R Rᵀ = I to :data:`~armctl.controllers.osc.tasks.target.ROTATION_TOL`,
det R > 0 and a pose's last row [0, 0, 0, 1]. The generated QP data (:mod:`~armctl.controllers.osc.generated`,
and :mod:`~armctl.controllers.osc.generated_contact` with contacts) evaluates these conditions on its inputs, in
its own call, so that the step's Python only checks the arrays' types and shapes; a target the code does not pass
gets the Python check, which names the defect or, on a target within a rounding of the tolerance, takes it. The
code's tolerances are a hair tighter than the Python check's, so that what the code passes the Python check passes
too.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

import casadi as cs

from armctl.controllers.osc.tasks.target import ROTATION_TOL, rotation_det, rotation_gram

#: the tolerance on R Rᵀ − I in the code: the Python check's, less far more than the rounding of its sums
_TOL = ROTATION_TOL - 1e-12


def _finite(x: cs.SX) -> cs.SX:
    """1 if the sum of x's entries is finite (|Σ x| ≤ the largest float: false if an entry is NaN or ±inf, and
    false too where finite entries sum past the range of floats, which the Python check then takes)."""
    return cs.le(cs.fabs(cs.sum1(x)), sys.float_info.max)


def _rotation(e: Sequence[cs.SX]) -> cs.SX:
    """1 if the row-major 3×3 entries ``e`` are a rotation to :data:`_TOL`, with a determinant near +1."""
    ok = cs.SX(1)
    for x in rotation_gram(*e):
        ok = cs.logic_and(ok, cs.le(cs.fabs(x), _TOL))
    det = rotation_det(*e)
    return cs.logic_and(ok, cs.gt(det, 0.5))  # orthonormal to 1e-4: det is ±1 to 1e-3


def target_verdict(kind: str, value: cs.SX, velocity: cs.SX, acceleration: cs.SX) -> cs.SX:
    """1 if a frame task's target (its ``value`` row by row, ``velocity``, ``acceleration``) passes the check of
    :class:`~armctl.controllers.osc.tasks.target.TargetHolder` (see the module), else 0.

    Parameters
    ----------
    kind : str
        ``"pose"`` (value 4×4), ``"orientation"`` (3×3) or ``"position"`` (3).
    value, velocity, acceleration : casadi.SX
        The target's symbols, as the generated code takes them.

    Returns
    -------
    casadi.SX
        The verdict (1 or 0).
    """
    ok = _finite(cs.vertcat(value, velocity, acceleration))
    if kind == "pose":
        last = cs.logic_and(cs.logic_and(cs.eq(value[12], 0.0), cs.eq(value[13], 0.0)), cs.eq(value[14], 0.0))
        ok = cs.logic_and(ok, cs.logic_and(last, cs.eq(value[15], 1.0)))
        ok = cs.logic_and(ok, _rotation([value[k] for k in (0, 1, 2, 4, 5, 6, 8, 9, 10)]))
    elif kind == "orientation":
        ok = cs.logic_and(ok, _rotation([value[k] for k in range(9)]))
    return ok
