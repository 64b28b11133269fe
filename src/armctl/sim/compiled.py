"""The simulator's integration step as generated C code, and the choice between it and the Python step.

:func:`choose_step` is where ``simulate``'s ``compile`` option is decided:

* ``compile="auto"`` (the default): the generated step whenever this plant has one and it can be built (or is
  cached); without a C compiler the Python step, with one :class:`~armctl.errors.PerformanceWarning` (per process
  and cause, :data:`FALLBACK`) that says how to get one;
* ``compile=True``: the generated step, or an error saying why there is none;
* ``compile=False``: the Python step (:mod:`armctl.sim.integrators`, :mod:`armctl.sim.stepper`).

The option is checked by :func:`armctl.codegen.compile_mode`, as everywhere it appears.

A library is built on first use (a second or two; one line is logged with the time it took) and cached on disk
(:mod:`armctl.codegen.library`); it depends on the arm's chain (joint axes and placements) and on the plant's
structure (friction model, contact laws and the links their points ride on, a disturbance, the family of schemes),
not on numbers: payload, perturbed or friction variants of a plant share it (:mod:`armctl.sim.compiled_plant`).

It integrates the model the ``"pinocchio"`` backend expresses (rotors as reflected inertia, no gyroscopic
coupling); runs agree with the Python step's to rounding (tests/sim/test_compiled_plant.py, and every simulator
test on both steps). A mass matrix that is not positive definite gives a non-finite state or a divergence, as in
the Python step.

:func:`compiled_step` is the RK4 or Euler step of a rigid arm generated whole, the arm's numbers built in: a
function (q, q̇, τ, h) → (q₁, q̇₁, q̈) for use outside ``simulate``.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from armctl._checks import FloatArray
from armctl.codegen import Fallback, compile_mode
from armctl.dynamics.base import Dynamics
from armctl.dynamics.casadi_buffer import buffer_of, view
from armctl.errors import InvalidParameterError
from armctl.model.robot import RobotModel
from armctl.sim.integrators import fast_step, make_step, rk4, semi_implicit_euler
from armctl.sim.plant import Plant
from armctl.sim.plant_layout import PlantLayout, layout_of

if TYPE_CHECKING:  # CasADi is imported on first use: ``import armctl`` stays light
    import casadi as cs

#: the integrators of :func:`compiled_step` (for a plant without friction, contact or disturbance, ``simulate``
#: calls their step of the rigid dynamics alone, :attr:`StepChoice.fast`)
SCHEMES = ("rk4", "euler")
#: bumped when the generated code changes, so that stale cached libraries are not loaded
_CODE_VERSION = 2
#: what ``compile="auto"`` runs where the generated step cannot be built
FALLBACK = Fallback("the simulator's generated step", "the Python step", "several times slower")
#: ``compile`` checked (see :func:`armctl.codegen.compile_mode`)
compile_option = compile_mode

Step = Callable[[FloatArray, FloatArray, FloatArray, float], tuple[FloatArray, FloatArray, FloatArray]]


@dataclass(frozen=True)
class StepChoice:
    """What integrates a run: the plant, the step :func:`armctl.sim.stepper.advance` calls, the step of the
    rigid dynamics alone that the loop calls for a plant without friction, contact or disturbance (or None), and
    whether it is generated code (``reason``: why not, if not)."""

    plant: Any
    step: Any
    fast: Step | None
    compiled: bool
    reason: str = ""


def choose_step(
    dyn: Dynamics, scheme: str, plant: Plant, compile: Any = "auto", cache_dir: str | os.PathLike[str] | None = None
) -> StepChoice:
    """The step that integrates ``plant`` with ``scheme`` under ``compile`` (see the module).

    Raises
    ------
    InvalidParameterError
        ``compile`` is not True, False or ``"auto"``; or it is True and the plant has no generated step (the
        rotors' gyroscopic coupling, a friction model or environment of the user's own).
    BackendError
        ``compile=True`` and the library cannot be built (no C compiler, a failing one, an unwritable cache).

    Warns
    -----
    PerformanceWarning
        ``compile="auto"`` and no C compiler, or a build that fails for another reason: the Python step is used
        (one warning per process and cause).
    """
    mode = compile_mode(compile)

    def python(reason: str) -> StepChoice:
        return StepChoice(plant, make_step(scheme, plant), fast_step(scheme, plant), False, reason)

    if mode is False:
        return python("compile=False")
    found = layout_of(plant)
    if isinstance(found, str):
        if mode is True:
            raise InvalidParameterError(f"compile=True: {found}; use compile=False", value=found)
        return python(found)
    try:
        return _generated(dyn, scheme, plant, found, cache_dir)
    except Exception as e:  # "auto" falls back on any failure to build: the run still happens, and says why
        if mode is True:
            raise
        return python(FALLBACK.warn(e, stacklevel=3))


def _generated(
    dyn: Dynamics, scheme: str, plant: Plant, layout: PlantLayout, cache_dir: str | os.PathLike[str] | None
) -> StepChoice:
    """The generated step (built, loaded or found in this process)."""
    from armctl.sim import compiled_plant

    model = dyn.model
    family = compiled_plant.FAMILY[scheme]
    what = ", ".join(
        w
        for w, present in (
            (layout.friction + " friction", layout.has_friction),
            ("contact", bool(layout.points)),
            ("a disturbance", layout.disturbance_joint is not None),
        )
        if present
    )
    fns = compiled_plant.library(
        model,
        layout,
        family,
        cache_dir,
        what=f"the integration step of the plant ({what or 'rigid'}, {scheme}) for {model.name!r}",
    )
    cp = compiled_plant.CompiledPlant(plant, scheme, layout, fns)
    fast = cp.fast if plant.simple and scheme in SCHEMES else None
    return StepChoice(cp, cp.step, fast, True)


def _step_tag(model: RobotModel, scheme: str) -> str:
    return f"sim-step|{model.fingerprint(inertial=True, tool=False)}|v{_CODE_VERSION}"


def _check_scheme(scheme: str) -> None:
    if scheme not in SCHEMES:
        raise InvalidParameterError(
            f"the frictionless compiled step is for the integrators {SCHEMES}, not {scheme!r}", value=scheme
        )


def step_function(model: RobotModel, scheme: str) -> cs.Function:
    """The CasADi function ``step(q, qd, tau, h) → (q1, qd1, qdd)`` of ``scheme`` ("rk4" or "euler") for
    ``model``: the simulator's own formulas (:func:`armctl.sim.integrators.rk4`,
    :func:`~armctl.sim.integrators.semi_implicit_euler`) applied to symbols, with q̈ = qdd(q, q̇, τ) of
    :func:`armctl.dynamics.recursive.forward_dynamics`."""
    import casadi as cs

    from armctl.dynamics import recursive

    _check_scheme(scheme)
    n = model.n
    q, v, tau = (cs.SX.sym(s, n) for s in ("q", "qd", "tau"))
    h = cs.SX.sym("h")
    fd = recursive.functions(model)["qdd"]
    scheme_step = rk4 if scheme == "rk4" else semi_implicit_euler
    # the scheme's formulas applied to CasADi symbols (its signature says arrays)
    q1, v1, a1 = scheme_step(lambda t, q_, v_, tau_: fd(q_, v_, tau_), 0.0, q, v, tau, h)  # type: ignore[arg-type, return-value]
    return cs.Function(f"step_{scheme}", [q, v, tau, h], [q1, v1, a1])


def _library_function(model: RobotModel, scheme: str, cache_dir: str | os.PathLike[str] | None) -> cs.Function:
    """The compiled step function, built only if its library is not cached yet."""
    from armctl.codegen import library as codegen

    _check_scheme(scheme)
    name = f"step_{scheme}"
    make = lambda: [step_function(model, scheme)]  # noqa: E731
    return codegen.cached(
        [name], _step_tag(model, scheme), make, cache_dir, what=f"the {scheme} step of {model.name!r}"
    )[name]


def compiled_step(model: RobotModel, scheme: str, cache_dir: str | os.PathLike[str] | None = None) -> Step:
    """The step of ``scheme`` for ``model`` as a function (q, q̇, τ, h) → (q₁, q̇₁, q̈) running compiled code
    (built on first use, then loaded from the cache).

    Like :func:`armctl.sim.integrators.fast_step`'s, it works in two buffers that take turns: a step writes
    (q₁, q̇₁) into the one it did not read from and returns them as arrays that the next step finds in place
    (no copy in) and the step after next overwrites; q̈ is valid until the next step. Not thread-safe."""
    return _bind_step(_library_function(model, scheme, cache_dir), model.n)


def _bind_step(ext: cs.Function, n: int) -> Step:
    """The compiled step function ``ext`` as a Python function on two alternating buffers (see
    :func:`compiled_step`)."""
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
