"""PD + gravity as one call of generated C code: τ = g(q) + F·[q_d; q̇_d; q; q̇].

:class:`~armctl.controllers.PDGravity` on ``armctl.Dynamics(model, compile=True)`` (or ``"auto"`` where it was
built) runs its law through :func:`generated_law`: gravity from the recursion of :mod:`armctl.dynamics.recursive`
(the model the ``"pinocchio"`` backend expresses, numbers built in) and the feedback matrix F = [K_p, K_d, −K_p,
−K_d] (n × 4n) an input of the code, so that gains can change without a new build. The library is compiled once
per model and cached on disk (:mod:`armctl.codegen.library`, beside the dynamics' own).

F is a symbol, so every entry of F·x depends on every entry of x = [q_d; q̇_d; q; q̇]: a NaN or inf in any input
reaches τ (0·NaN is NaN), as on the NumPy path, and checking τ is enough (see :class:`~armctl.controllers.Controller`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import casadi as cs
import numpy as np

from armctl._checks import FloatArray
from armctl.codegen import library as codegen
from armctl.dynamics import recursive
from armctl.dynamics.base import Dynamics
from armctl.dynamics.casadi_buffer import buffer_of, view
from armctl.model.robot import RobotModel

#: bumped when the generated code changes, so that stale cached libraries are not loaded
_CODE_VERSION = 1
_NAME = "pd_gravity"


def law_function(model: RobotModel) -> cs.Function:
    """The CasADi function (x, F) → g(x[2n:3n]) + F·x of ``model``, x = [q_d; q̇_d; q; q̇] (4n,), F (n × 4n)."""
    n = model.n
    x, feedback = cs.SX.sym("x", 4 * n), cs.SX.sym("F", n, 4 * n)
    q = x[2 * n : 3 * n]
    gravity = recursive.inverse_dynamics(model, q, cs.SX.zeros(n), cs.SX.zeros(n))
    return cs.Function(_NAME, [x, feedback], [cs.densify(gravity + cs.mtimes(feedback, x))])


def _function(model: RobotModel, cache_dir: Any) -> cs.Function:
    tag = f"pd-gravity|{model.fingerprint(inertial=True, tool=False)}|v{_CODE_VERSION}"
    found = codegen.cached(
        [_NAME], tag, lambda: [law_function(model)], cache_dir, what=f"PD + gravity of {model.name!r}"
    )
    return found[_NAME]


def generated_law(dynamics: Dynamics, feedback: FloatArray) -> Callable[..., FloatArray] | None:
    """τ = g(q) + F·[q_d; q̇_d; q; q̇] as a function (q, q̇, q_d, q̇_d) → τ (a new array) running generated code,
    on buffers of its own (one per controller and thread), for ``dynamics`` whose terms are generated code
    (``dynamics.compiled`` on the ``"pinocchio"`` backend); None for any other (the NumPy path).

    Its ``feedback`` attribute is its F (``feedback`` copied, n × 4n), to be overwritten in place when the gains
    change. One concatenation copies the four vectors into the stacked input; the caller checks their lengths
    (a wrong total raises ValueError)."""
    if dynamics.backend != "pinocchio" or not getattr(dynamics, "compiled", False):
        return None
    n = dynamics.n
    F = np.array(feedback, dtype=float, order="F")  # CasADi reads a matrix column by column
    if F.shape != (n, 4 * n):
        raise ValueError(f"feedback matrix has shape {F.shape}, not {(n, 4 * n)}")
    flat = F.ravel(order="K")  # F's own memory, column by column (a view)
    buf, run = buffer_of(_function(dynamics.model, dynamics.options.get("cache_dir")))
    x, out = np.zeros(4 * n), np.zeros(n)
    buf.set_arg(0, view(x))
    buf.set_arg(1, view(flat))
    buf.set_res(0, view(out))
    concatenate = np.concatenate

    def law(q: FloatArray, qd: FloatArray, q_d: FloatArray, qd_d: FloatArray) -> FloatArray:
        concatenate((q_d, qd_d, q, qd), out=x)
        run()
        return out.copy()

    # CasADi keeps no reference to what its buffer reads: these do. ``feedback``: F itself, which the
    # controller overwrites in place (F[...] = new gains, the layout kept) when its gains change
    law.bound = (buf, x, flat, out)  # type: ignore[attr-defined]  # kept alive with the law
    law.feedback = F  # type: ignore[attr-defined]  # the F the controller overwrites in place
    return law
