"""A whole control period in one call on the generated step (:mod:`armctl.sim.generated_engine`,
:meth:`CompiledPlant.period <armctl.sim.compiled_plant.CompiledPlant.period>`, ``step_period.c``), within the one
loop that checks and saturates the controller's torque for every engine.

References: the Python step (the Python engine's hold of τ by :class:`~armctl.sim.saturation.Saturation`, its
integration: NumPy, Pinocchio, LAPACK), written independently of the generated C; ``np.clip`` at the effort limits;
the sample times of a disturbance; exact rest for stiction.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import replace
from typing import Any

import numpy as np
import pytest

import armctl
from armctl.errors import SimulationWarning
from armctl.model.parts import JointLimits
from armctl.sim import Forces, simulate
from armctl.sim.compiled import choose_step
from armctl.sim.engine import TORQUE_NOT_FINITE, state_code
from armctl.sim.friction import make_friction
from armctl.sim.options import regroup
from armctl.sim.period_binding import PeriodBinding
from armctl.sim.plant import Plant
from armctl.sim.saturation import Saturation
from armctl.sim.stepper import advance
from tests.sim.helpers import OpenLoop, Ramp, slider, zero_torque

pytestmark = pytest.mark.one_step  # each test names the step it runs

SCHEMES = ("rk4", "euler", "semi-implicit-euler", "implicit-euler")
#: the effort limits of the saturating planar_3r [N·m]
LIMITS = np.array([6.0, 15.0, 2.0])


def unlimited(n: int) -> dict:
    """A period binding's saturation that holds the torque as it is (n joints)."""
    return {"effort_limit": np.full(n, np.inf), "saturate": False}


def _with_effort(model: armctl.RobotModel, effort: np.ndarray) -> armctl.RobotModel:
    joints = tuple(replace(j, limits=JointLimits(effort=float(e))) for j, e in zip(model.joints, effort, strict=True))
    return replace(model, joints=joints)


def _saturating() -> dict:
    """planar_3r with asymmetric stick-slip friction and a Stribeck hump, effort limits :data:`LIMITS`, pushed by an
    open-loop ramp that crosses them (periods clipped and free, breakaways and stops), 4 sub-steps a period."""
    static = np.array([5.0, 20.0, 3.0])
    model = armctl.models.planar_3r().with_friction(
        viscous=0.2, coulomb=0.6 * static, coulomb_negative=0.5 * static, static=static, stribeck_velocity=0.05
    )
    ramp = OpenLoop(Ramp([3.0, -8.0, 2.5], [20.0, -60.0, -20.0]))
    return {
        "plant": _with_effort(model, LIMITS),
        "controller": ramp,
        "reference": armctl.Reference.hold([0.3, -1.0, 0.5]),
        "dt": 2.5e-4,
    }


def _both(case: dict, **kw: object) -> tuple[armctl.sim.SimResult, armctl.sim.SimResult]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SimulationWarning)  # (the limits' report of the runs)
        python, generated = (simulate(**regroup({**case, **kw}), compile=c) for c in (False, True))
    assert (python.info["compiled"], generated.info["compiled"]) == (False, True)
    return python, generated


@pytest.mark.parametrize("scheme", SCHEMES)
def test_the_period_saturates_and_records_as_the_loop_does(scheme: str) -> None:
    """Open-loop torques crossing the effort limits, 4 sub-steps a period: the generated period clips exactly the
    rows the Python loop clips, holds np.clip of the torque, and the runs agree (joint positions within 1e-9 rad,
    the same stuck joints, events, friction torques and work)."""
    python, generated = _both(_saturating(), duration=0.4, integrator=scheme)
    np.testing.assert_array_equal(generated.tau, python.tau)  # open loop: the same commands
    beyond = (np.abs(python.tau) > LIMITS).any(axis=1)
    assert beyond.any() and not beyond.all()
    for res in (python, generated):
        np.testing.assert_array_equal(res.tau_applied, np.clip(res.tau, -LIMITS, LIMITS))
    assert not python.diverged and not generated.diverged
    assert np.abs(generated.q - python.q).max() <= 1e-9
    assert np.abs(generated.qd - python.qd).max() <= 1e-7
    np.testing.assert_array_equal(generated.stuck, python.stuck)
    assert python.stuck.any()
    for key in ("stick_events", "breakaway_events", "implicit_unconverged"):
        assert generated.info[key] == python.info[key], key
    assert python.info["stick_events"] + python.info["breakaway_events"] > 0
    np.testing.assert_allclose(generated.tau_friction, python.tau_friction, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(generated.qdd, python.qdd, rtol=1e-7, atol=1e-7)
    scale = np.abs(python.work_actuator).max()
    assert np.abs(generated.work_friction - python.work_friction).max() <= 1e-9 * scale


class _NaNAfter:
    """The ramp of :func:`_saturating`, NaN on joint 2 from t_bad on."""

    def __init__(self, t_bad: float) -> None:
        self.t_bad = t_bad
        self.ramp = Ramp([3.0, -8.0, 2.5], [20.0, -60.0, -20.0])

    def __call__(self, t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        tau = self.ramp(t)
        if t >= self.t_bad - 1e-12:
            tau[1] = math.nan
        return tau


@pytest.mark.parametrize("t_bad", [0.05, 0.1])  # a period within the run, the last sample
def test_a_torque_that_is_not_finite_stops_the_run_where_the_loop_stops_it(t_bad: float) -> None:
    """τ_k with a NaN: on both steps the run stops as diverged at sample k, with the same message and the samples
    before it (the last sample too)."""
    case = {**_saturating(), "controller": _NaNAfter(t_bad)}
    python, generated = _both(case, duration=0.1)
    k = round(t_bad / 1e-3)
    for res in (python, generated):
        assert res.diverged and res.diverged_at == pytest.approx(t_bad)
        assert "non-finite torque" in res.divergence and "nan" in res.divergence
        assert len(res.t) == k
    assert generated.divergence == python.divergence
    assert np.abs(generated.q - python.q).max() <= 1e-9
    assert np.abs(generated.diverged_q - python.diverged_q).max() <= 1e-9  # the state at sample k


@pytest.mark.parametrize(
    ("bound", "value", "start"),
    [("max_velocity", 2.0, (2.8, 0.0)), ("max_position", 0.5, (0.4, 1.5))],
)
def test_the_state_a_period_leaves_is_checked_as_the_loop_checks_it(
    bound: str, value: float, start: tuple[float, float]
) -> None:
    """A pendulum with stick-slip friction, 3 sub-steps a period, falling from near the top (a velocity bound) or
    thrown up (a position bound): the run stops at the first sample beyond the bound, the same on both steps (the
    generated period checks the state it leaves)."""
    case = {
        "plant": armctl.models.pendulum().with_friction(viscous=0.05, coulomb=0.1, static=0.2),
        "controller": zero_torque,
        "reference": armctl.Reference.hold([start[0]]),
        "q0": [start[0]],
        "qd0": [start[1]],
        "dt": 1e-3 / 3,
    }
    python, generated = _both(case, duration=2.0, **{bound: value})
    for res in (python, generated):
        assert res.diverged and res.divergence.endswith(f"beyond {bound} = {value:g}")
    assert generated.diverged_at == python.diverged_at and 0 < len(generated.t) < 2000
    assert np.abs(generated.q - python.q).max() <= 1e-9
    velocity = bound == "max_velocity"
    assert np.abs(generated.diverged_qd if velocity else generated.diverged_q).max() > value
    assert np.abs(generated.qd if velocity else generated.q).max() <= value


def test_the_disturbance_is_sampled_at_the_same_instants_with_several_sub_steps() -> None:
    """A slider with stick-slip friction pushed by a time-varying disturbance, 4 sub-steps a period: the generated
    period takes the disturbance at the instants the Python step takes it (the start, middle and end of every
    sub-step), and the runs agree, stick–slip events included."""
    seen: dict[bool, set[float]] = {}
    runs = {}
    for compile in (False, True):
        times: set[float] = set()

        def push(t: float, times: set[float] = times) -> np.ndarray:
            times.add(t)
            return np.array([-9.0 * math.sin(6.0 * t) - 2.0, 0.0, 0.0, 0.0, 0.0, 0.0])

        runs[compile] = simulate(
            slider(2.0).with_friction(coulomb=5.0, static=6.0),
            zero_torque,
            armctl.Reference.hold([0.0]),
            1.2,
            dt=2.5e-4,
            compile=compile,
            forces=Forces(disturbance=push),
        )
        seen[compile] = times
    assert seen[False] == seen[True]
    halves = np.array(sorted(seen[True])) / 1.25e-4  # every half sub-step of 1200 periods, and nothing else
    np.testing.assert_allclose(halves, np.round(halves), atol=1e-9)
    assert {round(x) for x in halves} == set(range(2 * 4 * 1200 + 1))
    python, generated = runs[False], runs[True]
    assert generated.info["compiled"] and python.info["stick_events"] > 0 and python.info["breakaway_events"] > 0
    for key in ("stick_events", "breakaway_events"):
        assert generated.info[key] == python.info[key], key
    assert np.abs(generated.q - python.q).max() <= 1e-9
    np.testing.assert_array_equal(generated.stuck, python.stuck)
    np.testing.assert_allclose(generated.wrench, python.wrench, rtol=1e-12, atol=1e-12)
    assert np.abs(generated.work_external - python.work_external).max() <= 1e-9


def _plant(dyn: armctl.Dynamics, compile: bool) -> Any:
    return _choice(dyn, compile).plant


def _choice(dyn: armctl.Dynamics, compile: bool) -> Any:
    return choose_step(dyn, "rk4", Plant(dyn, make_friction("stick-slip", dyn.model)), compile)


def test_one_period_writes_its_rows_of_the_record_and_nothing_else() -> None:
    """One period of the Panda from a state with joints 2 and 4 at rest (one held by static friction, one breaking
    away) and the others sliding, 3 sub-steps: row k of q̈, the friction torque and the stuck mask, row k + 1 of q,
    q̇ and the work, as the Python plant's begin and sub-steps give them; the other rows untouched."""
    static = np.full(7, 0.4)
    static[1] = 60.0  # joint 2 holds
    model = armctl.models.panda().with_friction(viscous=0.2, coulomb=0.3, static=static)
    dyn = armctl.Dynamics(model)
    q = np.array([0.1, 0.0, -0.2, -1.8, 0.3, 1.5, 0.2])
    v = np.array([0.4, 0.0, -0.3, 0.0, 0.5, -0.2, 0.1])
    tau = dyn.gravity_torque(q)
    tau[3] += 8.0  # joint 4 breaks away
    rows, k, m, h = 6, 2, 3, 1e-3 / 3
    names = ("tau", "q", "qd", "qdd", "tau_friction", "stuck", "tau_applied")
    record = {name: np.full((rows, 7), -7.0) for name in names}
    record.update({name: np.full(rows, -7.0) for name in ("work_friction", "work_external")})
    record["q"][k], record["qd"][k], record["tau"][k] = q, v, tau
    record["stuck"][k] = 0.0
    record["work_friction"][k] = record["work_external"][k] = 1.5
    before = {name: a.copy() for name, a in record.items()}
    generated = _plant(dyn, True)
    generated.bind_record(
        PeriodBinding(
            **record, **unlimited(7), substeps=m, dt=h, accel_at_start=False, max_velocity=1e3, max_position=math.inf
        )
    )
    generated.period(k, 0.002)

    choice = _choice(dyn, False)
    python = choice.plant
    python.begin(0.002, q, v, tau)
    stuck, friction = python.stuck.copy(), python.friction_torque(v).copy()
    assert stuck.tolist() == [False, True, False, False, False, False, False]
    q1, v1, work = q, v, 1.5
    for i in range(m):
        q1, v1, a, dwf, _ = advance(python, choice.step, 0.002 + i * h, q1, v1, tau, h, begun=i == 0)
        work += dwf
        if i == 0:
            qdd = a
    np.testing.assert_allclose(record["q"][k + 1], q1, rtol=0, atol=1e-12)
    np.testing.assert_allclose(record["qd"][k + 1], v1, rtol=0, atol=1e-10)
    np.testing.assert_allclose(record["qdd"][k], qdd, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(record["tau_friction"][k], friction, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(record["stuck"][k], stuck.astype(float))
    np.testing.assert_array_equal(record["tau_applied"][k], tau)  # held as it is (no saturation)
    assert record["work_friction"][k + 1] == pytest.approx(work, rel=1e-9) and work < 1.5
    assert record["work_external"][k + 1] == 1.5
    for name, a in record.items():
        written = {"q": [k + 1], "qd": [k + 1], "work_friction": [k + 1], "work_external": [k + 1]}.get(name, [])
        written = written + ([k] if name in ("qdd", "tau_friction", "stuck", "tau_applied") else [])
        others = [i for i in range(rows) if i not in written]
        np.testing.assert_array_equal(a[others], before[name][others], err_msg=name)


def test_a_row_outside_the_record_is_an_index_error() -> None:
    """A period from the last row would write beyond the record: it writes nothing and raises an IndexError naming
    the row; the last sample (no step after it) is inside."""
    model = armctl.models.planar_2r().with_friction(viscous=0.1, coulomb=0.2, static=0.3)
    dyn = armctl.Dynamics(model)
    rows = 3
    names = ("tau", "q", "qd", "qdd", "tau_friction", "stuck", "tau_applied")
    record = {name: np.zeros((rows, 2)) for name in names}
    record.update({name: np.zeros(rows) for name in ("work_friction", "work_external")})
    record["q"][:] = [0.2, -0.1]
    record["tau"][:] = [0.5, -0.3]
    plant = _plant(dyn, True)
    plant.bind_record(
        PeriodBinding(
            **record, **unlimited(2), substeps=1, dt=1e-3, accel_at_start=False, max_velocity=1e3, max_position=math.inf
        )
    )
    untouched = {name: a.copy() for name, a in record.items()}
    with pytest.raises(IndexError, match="sample 2 is outside the record"):
        plant.period(rows - 1, 2e-3)
    for name, a in record.items():
        np.testing.assert_array_equal(a, untouched[name], err_msg=name)
    plant.last_sample(rows - 1, 2e-3)
    assert np.isfinite(record["qdd"][rows - 1]).all() and (record["qdd"][rows - 1] != 0.0).any()


def _state_reason(q: np.ndarray, qd: np.ndarray, max_velocity: float, max_position: float) -> int:
    """The loop's rule for the state of a sample, written out: 1 not finite (the sums of q and q̇ overflow or are
    NaN), 2 a |q̇_i| beyond max_velocity, 3 a |q_i| beyond max_position, 0 none."""
    if not math.isfinite(sum(q.tolist()) + sum(qd.tolist())):
        return 1
    if np.abs(qd).max() > max_velocity:
        return 2
    return 3 if np.abs(q).max() > max_position else 0


@pytest.mark.parametrize(
    ("v0", "tau", "reason"),
    [
        ([0.1, -0.2], [0.0, 0.0], 0),
        ([1e300, 0.01], [0.0, 0.0], 1),  # centrifugal terms of 1e600: the state is not finite
        ([2.995, 0.01], [5000.0, 0.0], 2),
        ([0.01, 2.0], [0.0, 0.0], 3),
    ],
)
def test_the_period_checks_the_state_it_leaves_by_the_loops_rule(v0: list, tau: list, reason: int) -> None:
    """planar_2r from a state and a torque that take it beyond the bounds (max_velocity 3 rad/s, max_position
    1 rad) or not: the code the generated period gives the row it wrote is the rule's, and the Python rule's
    (:func:`armctl.sim.engine.state_code`, which the other engines use)."""
    dyn = armctl.Dynamics(armctl.models.planar_2r().with_friction(viscous=0.1, coulomb=0.2, static=0.3))
    rows = 2
    names = ("tau", "q", "qd", "qdd", "tau_friction", "stuck", "tau_applied")
    record = {name: np.zeros((rows, 2)) for name in names}
    record.update({name: np.zeros(rows) for name in ("work_friction", "work_external")})
    record["tau"][0], record["q"][0], record["qd"][0] = tau, [0.2, 0.999], v0
    plant = _plant(dyn, True)
    binding = PeriodBinding(
        **record, **unlimited(2), substeps=2, dt=5e-4, accel_at_start=False, max_velocity=3.0, max_position=1.0
    )
    plant.bind_record(binding)
    with np.errstate(all="ignore"):
        code = plant.period(0, 0.0)
        q1, v1 = record["q"][1], record["qd"][1]
        assert code == _state_reason(q1, v1, 3.0, 1.0) == state_code(q1, v1, 3.0, 1.0) == reason


@pytest.mark.parametrize("substeps", [1, 4])
def test_stiction_holds_exactly_on_the_period(substeps: int) -> None:
    """The Panda held by static friction against gravity, 1 and 4 sub-steps a period: it stays where it is bit for
    bit, q̇ = q̈ = 0 exactly, every joint stuck, the holding torque the gravity torque."""
    q0 = np.array([0.2, -0.6, 0.1, -2.0, 0.3, 1.8, 0.5])
    g0 = armctl.Dynamics(armctl.models.panda()).gravity_torque(q0)
    sticky = armctl.models.panda().with_friction(viscous=0.5, coulomb=np.abs(g0) + 1.0, static=np.abs(g0) + 3.0)
    res = simulate(sticky, zero_torque, armctl.Reference.hold(q0), 0.5, dt=1e-3 / substeps, compile=True)
    assert res.info["compiled"]
    assert (res.q == q0).all() and (res.qd == 0.0).all() and (res.qdd == 0.0).all() and res.stuck.all()
    np.testing.assert_allclose(res.tau_friction, np.broadcast_to(-g0, res.tau_friction.shape), rtol=1e-9, atol=1e-9)


#: torques of planar_2r against the limits (4, inf) [N·m]: within, at, beyond, a sum that overflows, infinite, NaN
HELD_CASES = [
    [1.5, -300.0],
    [4.0, 1e9],
    [-4.0, -0.0],
    [7.5, 2.0],
    [-1e300, 5.0],
    [1e308, 1e308],
    [math.inf, 0.0],
    [0.0, -math.inf],
    [math.nan, 1.0],
]


@pytest.mark.parametrize("saturate", [True, False])
@pytest.mark.parametrize("tau", HELD_CASES)
def test_the_period_holds_the_torque_by_the_saturation_rule(tau: list, saturate: bool) -> None:
    """The generated period holds τ_k as :class:`~armctl.sim.saturation.Saturation` does (its C transcription):
    the same applied row bit for bit, np.clip at the limits where ``saturate`` (τ itself otherwise), and for a τ_k
    that is not finite the code TORQUE_NOT_FINITE with nothing written (the state, q̈ and the applied row as they
    were)."""
    dyn = armctl.Dynamics(armctl.models.planar_2r().with_friction(viscous=0.1, coulomb=0.2, static=0.3))
    limit = np.array([4.0, math.inf])
    rows = 2
    names = ("tau", "q", "qd", "qdd", "tau_friction", "stuck", "tau_applied")
    record = {name: np.full((rows, 2), -7.0) for name in names}
    record.update({name: np.zeros(rows) for name in ("work_friction", "work_external")})
    record["q"][0], record["qd"][0], record["tau"][0] = [0.2, -0.3], [0.1, 0.0], tau
    plant = _plant(dyn, True)
    plant.bind_record(
        PeriodBinding(
            **record,
            effort_limit=limit,
            saturate=saturate,
            substeps=1,
            dt=1e-3,
            accel_at_start=False,
            max_velocity=math.inf,
            max_position=math.inf,
        )
    )
    before = {name: a.copy() for name, a in record.items()}
    python_applied = np.full((rows, 2), -7.0)
    with np.errstate(all="ignore"):
        held = Saturation(python_applied, limit, saturate).hold(0, np.array(tau))
        code = plant.period(0, 0.0)
    finite = bool(np.isfinite(tau).all())
    assert (held is not None) == finite
    if not finite:
        assert code == TORQUE_NOT_FINITE
        for name, a in record.items():
            np.testing.assert_array_equal(a, before[name], err_msg=name)
        return
    assert code == state_code(record["q"][1], record["qd"][1], math.inf, math.inf)  # (a huge τ held: not finite)
    expected = np.clip(tau, -limit, limit) if saturate else np.array(tau)
    np.testing.assert_array_equal(python_applied[0], expected)
    np.testing.assert_array_equal(record["tau_applied"][0], expected)
    assert np.signbit(record["tau_applied"][0]).tolist() == np.signbit(python_applied[0]).tolist()
