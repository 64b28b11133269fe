"""The simulator's integration step as compiled C code: ``simulate(..., compile=True)``.

For a plant with no friction, contact or disturbance, one step of ``"rk4"`` or ``"euler"`` (see
:mod:`armctl.sim.integrators` for the formulas) is generated with CasADi from the recursive algorithms of
:mod:`armctl.dynamics.recursive` — the model's numbers built in — compiled with the system's C compiler and
cached on disk (:mod:`armctl.dynamics.codegen`: keyed by the model's full fingerprint, so a payload or a
perturbed variant builds its own library; about 2 s for the Panda, then milliseconds to load). A step is then
one call into C, through CasADi's zero-copy buffers: on the Panda an RK4 step costs 5.3 µs, against 24–31 µs
for the one that calls Pinocchio's ABA four times from Python (``python -m armctl.bench.sim_speed`` times the
whole closed loop).

It integrates the model the ``"pinocchio"`` backend expresses (rotors as reflected inertia, no gyroscopic
coupling); its q̈ agrees with Pinocchio's ABA to rounding (tests/sim/test_compiled.py). A mass matrix that is
not positive definite gives a non-finite state, which ``simulate`` reports as a divergence.
"""

from __future__ import annotations

import os
from collections.abc import Callable

import casadi as cs
import numpy as np

from armctl._checks import FloatArray
from armctl.dynamics import recursive
from armctl.dynamics.base import Dynamics
from armctl.dynamics.casadi_buffer import buffer_of, view
from armctl.errors import InvalidParameterError
from armctl.model.robot import RobotModel
from armctl.sim.integrators import rk4, semi_implicit_euler
from armctl.sim.plant import Plant

#: the integrators with a compiled step
SCHEMES = ("rk4", "euler")
#: bumped when the generated code changes, so that stale cached libraries are not loaded
_CODE_VERSION = 2

Step = Callable[[FloatArray, FloatArray, FloatArray, float], tuple[FloatArray, FloatArray, FloatArray]]


def _check_scheme(scheme: str) -> None:
    if scheme not in SCHEMES:
        raise InvalidParameterError(
            f"compile=True has a compiled step for the integrators {SCHEMES}, not "
            f"{scheme!r}: use one of them or compile=False",
            value=scheme,
        )


def step_function(model: RobotModel, scheme: str) -> cs.Function:
    """The CasADi function ``step(q, qd, tau, h) → (q1, qd1, qdd)`` of ``scheme`` ("rk4" or "euler") for
    ``model``: the simulator's own formulas (:func:`armctl.sim.integrators.rk4`,
    :func:`~armctl.sim.integrators.semi_implicit_euler`) applied to symbols, with q̈ = qdd(q, q̇, τ) of
    :func:`armctl.dynamics.recursive.forward_dynamics`."""
    _check_scheme(scheme)
    n = model.n
    q, v, tau = (cs.SX.sym(s, n) for s in ("q", "qd", "tau"))
    h = cs.SX.sym("h")
    fd = recursive.functions(model)["qdd"]
    scheme_step = rk4 if scheme == "rk4" else semi_implicit_euler
    # the scheme's formulas applied to CasADi symbols (its signature says arrays)
    q1, v1, a1 = scheme_step(lambda t, q_, v_, tau_: fd(q_, v_, tau_), 0.0, q, v, tau, h)  # type: ignore[arg-type, return-value]
    return cs.Function(f"step_{scheme}", [q, v, tau, h], [q1, v1, a1])


def check_plant(dyn: Dynamics, scheme: str, plant: Plant) -> None:
    """Raise :class:`~armctl.errors.InvalidParameterError` if ``compile=True`` cannot integrate this plant."""
    _check_scheme(scheme)
    if not plant.simple:
        has = [
            what
            for what, present in (
                ("joint friction", plant.friction is not None),
                ("contact", bool(plant.environments)),
                ("a disturbance", plant.disturbance is not None),
            )
            if present
        ]
        raise InvalidParameterError(
            f"compile=True integrates only a plant without friction, contact or "
            f"disturbance (its step is pure rigid-body dynamics), and this one has "
            f"{' and '.join(has)}: simulate a friction-free model "
            f"(model.reduced(friction=False)) without environment or disturbance, or use "
            f"compile=False",
            value=has,
        )
    if getattr(dyn, "rotor_coupling", False) and any(
        j.motor is not None and j.motor.gyroscopic for j in dyn.model.joints
    ):
        raise InvalidParameterError(
            "compile=True integrates the model the 'pinocchio' backend expresses, "
            "without the rotors' gyroscopic coupling this 'lagrange' plant has: use "
            "rotor_coupling=False, the 'pinocchio' backend, or compile=False",
            value=dyn.backend,
        )


def _library_function(model: RobotModel, scheme: str, cache_dir: str | os.PathLike[str] | None) -> cs.Function:
    """The compiled step function, built only if its library is not cached yet."""
    from armctl.dynamics.codegen import cached

    _check_scheme(scheme)
    name = f"step_{scheme}"
    return cached(
        [name],
        f"sim-step|{model.fingerprint(inertial=True, tool=False)}|v{_CODE_VERSION}",
        lambda: [step_function(model, scheme)],
        cache_dir,
    )[name]


def compiled_step(model: RobotModel, scheme: str, cache_dir: str | os.PathLike[str] | None = None) -> Step:
    """The step of ``scheme`` for ``model`` as a function (q, q̇, τ, h) → (q₁, q̇₁, q̈) running compiled code
    (built on first use, then loaded from the cache).

    Like :func:`armctl.sim.integrators.fast_step`'s, it works in two buffers that take turns: a step writes
    (q₁, q̇₁) into the one it did not read from and returns them as arrays that the next step finds in place
    (no copy in) and the step after next overwrites; q̈ is valid until the next step. Not thread-safe."""
    ext = _library_function(model, scheme, cache_dir)
    n = model.n
    states = [np.zeros((2, n)), np.zeros((2, n))]
    rows = [(s[0], s[1]) for s in states]
    tau_in, h_in, acc = np.zeros(n), np.zeros(1), np.zeros(n)
    evals = []
    for i in (0, 1):  # buffer i reads state i and writes state 1 − i
        buf, run = buffer_of(ext)
        for k, a in enumerate((states[i][0], states[i][1], tau_in, h_in)):
            buf.set_arg(k, view(a))
        for k, a in enumerate((states[1 - i][0], states[1 - i][1], acc)):
            buf.set_res(k, view(a))
        evals.append((buf, run))  # the buffer kept alive with its function
    turn = [0]

    def step(q: FloatArray, v: FloatArray, tau: FloatArray, h: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        i = turn[0]
        q_in, v_in = rows[i]
        if q is not q_in or v is not v_in:  # not the last step's result: copy the state in
            pair = np.array((q, v))  # first: q or v may be a view of these very rows
            states[i][...] = pair
        tau_in[...] = tau
        if h != h_in[0]:
            h_in[0] = h
        evals[i][1]()
        turn[0] = i ^ 1
        q1, v1 = rows[i ^ 1]
        return q1, v1, acc

    return step
