"""The ``"pinocchio"`` backend's hot terms in generated C: ``armctl.Dynamics(model, compile=True)`` (or ``"auto"``).

Gravity, forward dynamics, the Slotine–Li passivity torque, the regressor and the passivity regressor are
generated with CasADi from the recursive algorithms of
:mod:`armctl.dynamics.recursive`, with the model's numbers built in (the regressors from the same recursion
with the parameters π as symbols, differentiated: τ is linear in π), compiled with the system's C compiler
and cached on disk by the model's full fingerprint (:mod:`armctl.codegen.library`; a payload or perturbed
variant builds its own library, 2–3 s for the Panda, then milliseconds to load). Each call copies its
inputs into fixed arrays that the C code reads in place (CasADi's zero-copy buffers) and returns a copy of
the result; the terms whose Pinocchio call costs little more than that round trip stay Pinocchio's — inverse
dynamics (RNEA) and the mass matrix (CRBA) — as do the Coriolis matrix, Jacobians, frames and energies
(``python -m armctl.bench.dynamics_speed`` and ``controller_speed`` time both variants).

The model is the one the ``"pinocchio"`` backend expresses (rotors as reflected inertia, no gyroscopic
coupling); every term agrees with Pinocchio's RNEA, ABA and regressor to rounding
(tests/dynamics/test_compiled.py). The Coulomb column's asymmetry ratios are an input of the code, not part of
it: friction variants share a library.

Non-finite inputs: CasADi simplifies its expressions, so an output entry need not depend on every input (the
Panda's τ₁ does not depend on q₁: its axis is along gravity). Every output entry that is not structurally
zero therefore carries Σ 0·xᵢ over all inputs, with the 0 an input of the code that the compiler cannot fold
(0·x = 0 for finite x, NaN for NaN or inf): a NaN or inf in any input reaches the result, as it does through
Pinocchio's numerical algorithms (the kernel's ``nan_propagates``), and checking a result is enough.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

import casadi as cs
import numpy as np

from armctl._checks import FloatArray
from armctl.codegen import Fallback
from armctl.codegen import library as codegen
from armctl.dynamics import recursive
from armctl.dynamics.casadi_buffer import buffer_of, view
from armctl.dynamics.pinocchio_kernel import PinocchioKernel
from armctl.model.robot import PARAMS_PER_JOINT, RobotModel

#: bumped when the generated code changes, so that stale cached libraries are not loaded
_CODE_VERSION = 3
#: the generated functions, in the library's order; each takes its variable inputs, then ``zero`` (a scalar
#: held at 0.0) and, for the regressors, ``rho`` (the Coulomb asymmetry ratios)
NAMES = ("g", "ptau", "qdd", "Y", "Yp")
#: what ``compile="auto"`` runs without a C compiler
FALLBACK = Fallback("the dynamics' generated C code", "Pinocchio", "up to a few times slower")


def _carry(out: cs.SX, inputs: list[cs.SX], zero: cs.SX) -> cs.SX:
    """``out`` (dense) with Σ 0·xᵢ over every entry of ``inputs`` added to each structurally non-zero entry."""
    carrier = cs.sum1(cs.vertcat(*[zero * x for x in inputs]))
    return cs.densify(out + carrier * cs.SX(out.sparsity(), 1.0))


def _regressor(model: RobotModel, tau: Callable[[cs.SX], cs.SX], viscous: cs.SX, coulomb: cs.SX, rho: cs.SX) -> cs.SX:
    """Y (n × 13n) of the rigid part τ(π) (linear in π) with the friction columns: viscous ``viscous_i`` and
    Coulomb κ(c_i) = sgn c_i (1 + ρ_i sgn c_i) at ``coulomb`` (see Dynamics.coulomb_column). The rotor
    column is ∂τ/∂(k_r²I_m): q̈_i on the diagonal, from the recursion like the rest."""
    n = model.n
    pi = cs.SX.sym("pi", PARAMS_PER_JOINT * n)
    y = cs.jacobian(tau(pi), pi)
    s = cs.sign(coulomb)
    kappa = s + rho * s * s
    friction = cs.SX(n, PARAMS_PER_JOINT * n)
    for i in range(n):
        friction[i, PARAMS_PER_JOINT * i + 11] = viscous[i]
        friction[i, PARAMS_PER_JOINT * i + 12] = kappa[i]
    return y + friction


def symbolic_functions(model: RobotModel) -> list[cs.Function]:
    """The CasADi functions of :data:`NAMES` for ``model`` (SX, numbers built in), non-finite carriers
    included (see the module)."""
    n = model.n
    q, qd, qdd, a, w, tau, v, c, qd_r, qdd_r, rho = (
        cs.SX.sym(s, n) for s in ("q", "qd", "qdd", "a", "w", "tau", "v", "c", "qd_r", "qdd_r", "rho")
    )
    zero = cs.SX.sym("zero")
    zeros = cs.SX.zeros(n)
    tf = recursive.joint_transforms(model, q)

    def rnea(vel: cs.SX, acc: cs.SX, params: Any = None, gravity: bool = True) -> cs.SX:
        return recursive.inverse_dynamics(model, q, vel, acc, gravity=gravity, transforms=tf, params=params)

    def passivity(params: Any = None) -> cs.SX:  # R(q, a, q̈_r) − h₀(w): see Dynamics.passivity_regressor
        return rnea(a, qdd_r, params) - rnea(w, zeros, params, gravity=False)

    gravity = rnea(zeros, zeros)
    exprs = {
        "g": ([q], gravity),
        "ptau": ([q, a, w, qdd_r], passivity()),
        "qdd": ([q, qd, tau], recursive.forward_dynamics(model, q, qd, tau)),
        "Y": ([q, qd, qdd, v, c], _regressor(model, lambda p: rnea(qd, qdd, p), v, c, rho)),
        "Yp": ([q, a, w, qdd_r, qd_r, qd], _regressor(model, passivity, qd_r, qd, rho)),
    }
    consts_of = {"Y": [zero, rho], "Yp": [zero, rho]}
    out = []
    for name in NAMES:
        inputs, expr = exprs[name]
        consts = consts_of.get(name, [zero])
        out.append(cs.Function(name, [*inputs, *consts], [_carry(expr, inputs, zero)]))
    return out


def library(model: RobotModel, cache_dir: str | os.PathLike[str] | None = None) -> dict[str, cs.Function]:
    """The compiled functions of ``model`` by name, built if the library is not cached yet."""
    return codegen.cached(
        list(NAMES),
        f"dynamics|{model.fingerprint(inertial=True, tool=False)}|v{_CODE_VERSION}",
        lambda: symbolic_functions(model),
        cache_dir,
        what=f"the dynamics of {model.name!r}",
    )


def _bind(fn: cs.Function, n: int, out: FloatArray, consts: tuple[FloatArray, ...]) -> Callable[..., FloatArray]:
    """``fn`` as a Python function of its variable inputs (each (n,)) writing into ``out`` (returned, not
    copied): each call copies its inputs into arrays bound to one CasADi buffer once and for all, as are
    ``out`` and the constant inputs ``consts``. An input of another length raises ValueError (a copy
    alone would broadcast a length-1 array)."""
    buf, run = buffer_of(fn)
    ins = [np.zeros(n) for _ in range(fn.n_in() - len(consts))]
    for k, arr in enumerate((*ins, *consts)):
        buf.set_arg(k, view(arr))
    buf.set_res(0, view(out.reshape(-1)))  # out is contiguous: a view
    if len(ins) == 1:  # g: the one-input call unrolled
        (b0,) = ins

        def call1(x: FloatArray) -> FloatArray:
            if len(x) != n:
                raise ValueError(f"input has length {len(x)}, not {n}")
            b0[...] = x
            run()
            return out

        call1.bound = (buf, ins, consts)  # type: ignore[attr-defined]  # the buffer reads them: keep them alive
        return call1

    def call(*args: FloatArray) -> FloatArray:
        for x, b in zip(args, ins, strict=True):
            if len(x) != n:
                raise ValueError(f"input has length {len(x)}, not {n}")
            b[...] = x
        run()
        return out

    call.bound = (buf, ins, consts)  # type: ignore[attr-defined]  # kept alive with the function
    return call


class CompiledKernel(PinocchioKernel):
    """The Pinocchio kernel with gravity, forward dynamics, the passivity torque and both regressors on the
    generated code's functions ``functions`` (by name), each bound to buffers of this kernel's own."""

    def __init__(self, model: RobotModel, pin_model: Any, functions: dict[str, cs.Function]) -> None:
        super().__init__(model, pin_model)
        n = self.n
        zero = np.zeros(1)
        rho = np.array(self.friction.ratio)  # (kept alive by the bound calls)
        vec: dict[str, FloatArray] = {k: np.zeros(n) for k in ("g", "ptau", "qdd")}
        y_out = np.zeros((PARAMS_PER_JOINT * n, n))  # both regressors write Y (column-major: Yᵀ here) into it
        calls = {k: _bind(functions[k], n, vec[k], (zero,)) for k in vec}
        for k in ("Y", "Yp"):
            calls[k] = _bind(functions[k], n, y_out, (zero, rho))
        g, qdd, self._y_call, self._yp_call, self._ptau_call = (calls[k] for k in ("g", "qdd", "Y", "Yp", "ptau"))
        self.gravity = lambda q: g(q).copy()
        self.aba = lambda q, qd, tau: qdd(q, qd, tau).copy()

    def regressor(
        self, q: FloatArray, qd: FloatArray, qdd: FloatArray, friction: tuple[FloatArray, FloatArray] | None = None
    ) -> FloatArray:
        v, w = friction if friction is not None else (self.zeros, self.zeros)
        return self._y_call(q, qd, qdd, v, w).T.copy(order="K")

    def passivity_regressor(
        self,
        q: FloatArray,
        qd: FloatArray,
        qd_r: FloatArray,
        qdd_r: FloatArray,
        a: FloatArray,
        w: FloatArray,
        copy: bool = True,
    ) -> FloatArray:
        out = self._yp_call(q, a, w, qdd_r, qd_r, qd).T
        return out.copy(order="K") if copy else out

    def passivity_torque(
        self, q: FloatArray, qd: FloatArray, qd_r: FloatArray, qdd_r: FloatArray, a: FloatArray, w: FloatArray
    ) -> FloatArray:
        return self.add_passivity_friction(self._ptau_call(q, a, w, qdd_r).copy(), qd, qd_r)


def __getattr__(name: str) -> Any:
    """``CompiledDynamics``, the class of ``Dynamics(model, compile=True)`` before it became a
    :class:`~armctl.dynamics.pinocchio_backend.PinocchioDynamics` with ``compiled`` True: that class, with a
    DeprecationWarning (the name goes in the next release)."""
    if name == "CompiledDynamics":
        import warnings

        from armctl.dynamics.pinocchio_backend import PinocchioDynamics

        warnings.warn(
            "armctl.dynamics.compiled.CompiledDynamics is deprecated: compiled dynamics are PinocchioDynamics with "
            "dyn.compiled True (make them with armctl.Dynamics(model, compile=True))",
            DeprecationWarning,
            stacklevel=2,
        )
        return PinocchioDynamics
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
