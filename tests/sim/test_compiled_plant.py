"""The generated step of plants with friction, contact and disturbances (:mod:`armctl.sim.compiled_plant`) and the
choice of ``compile``.

Reference: the Python step (NumPy, Pinocchio's ABA, LAPACK), an implementation written independently of the
generated C; stiction against exact rest (bit for bit) and the predicted breakaway torque.
"""

from __future__ import annotations

import logging
import math
import warnings

import numpy as np
import pytest

import armctl
from armctl.errors import BackendError, PerformanceWarning, SimulationWarning
from armctl.sim import ContactPoint, Forces, HuntCrossley, KelvinVoigt, Plane, SmoothFriction, simulate
from armctl.sim import compiled as compiled_module
from armctl.sim.options import regroup
from tests.sim.helpers import OpenLoop, PDGravity, Ramp, slider, zero_torque

pytestmark = pytest.mark.one_step  # each test names the step it runs

SCHEMES = ("rk4", "euler", "semi-implicit-euler", "implicit-euler")


def _stick_slip() -> dict:
    """planar_3r from rest under constant torques: asymmetric Coulomb levels, a Stribeck hump, breakaways and
    stops."""
    static = np.array([5.0, 20.0, 3.0])
    model = armctl.models.planar_3r().with_friction(
        viscous=0.2, coulomb=0.6 * static, coulomb_negative=0.5 * static, static=static, stribeck_velocity=0.05
    )
    ramp = OpenLoop(Ramp([3.0, -8.0, 2.0], [0.0, -40.0, 0.0]))
    return {"plant": model, "controller": ramp, "reference": armctl.Reference.hold([0.3, -1.0, 0.5]), "dt": 5e-4}


def _wall(law: str, friction: str) -> dict:
    """planar_2r pushed by a PD into a wall with tangential friction; two points (the tool, and one on link 2)."""
    model = armctl.models.planar_2r().with_friction(
        viscous=[30.0, 20.0], coulomb=[40.0, 25.0], static=[60.0, 35.0], stribeck_velocity=0.05
    )
    normal = KelvinVoigt(2e5, 2e3) if law == "kv" else HuntCrossley(2e5, 0.5, exponent=1.5)
    wall = Plane(
        normal,
        normal=(-1.0, 0.0, 0.0),
        point=(1.55, 0.0, 0.0),
        friction=0.2,
        points=[ContactPoint(), ContactPoint("joint2", (0.5, 0.0, 0.02))],
    )
    ctrl = PDGravity(armctl.Dynamics(model.reduced(friction=False)), kp=3000.0, kd=300.0)
    return {
        "plant": model,
        "controller": ctrl,
        "reference": armctl.Reference.hold([0.4, -0.2]),
        "q0": [1.0, -0.5],
        "dt": 2e-4,
        "environment": wall,
        "friction": friction,
    }


def _pushed_slider() -> dict:
    """A slider with Coulomb friction pushed by a time-varying disturbance: it sticks, breaks away, stops."""
    return {
        "plant": slider(2.0).with_friction(coulomb=5.0, static=6.0),
        "controller": zero_torque,
        "reference": armctl.Reference.hold([0.0]),
        "disturbance": lambda t: np.array([-9.0 * math.sin(6.0 * t) - 2.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
    }


PLANTS = {
    "stick-slip": _stick_slip,
    # (a smooth curve of width 0.1 rad/s: at the default 0.01 its slope is too stiff for Euler at this step)
    "smooth": lambda: {**_stick_slip(), "friction": SmoothFriction(_stick_slip()["plant"], velocity=0.1)},
    # every contact law with every friction law
    "kelvin-voigt wall, stick-slip": lambda: _wall("kv", "stick-slip"),
    "kelvin-voigt wall, smooth": lambda: _wall("kv", "smooth"),
    "hunt-crossley wall, stick-slip": lambda: _wall("hc", "stick-slip"),
    "hunt-crossley wall, smooth": lambda: _wall("hc", "smooth"),
    "pushed slider": _pushed_slider,
    "rigid panda": lambda: {
        "plant": armctl.models.panda(),
        "controller": zero_torque,
        "reference": armctl.Reference.hold([0.0, -0.4, 0.0, -2.0, 0.0, 1.6, 0.8]),
        "saturate": False,
    },
}


@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("name", sorted(PLANTS))
def test_generated_and_python_steps_give_the_same_run(name: str, scheme: str) -> None:
    """Every plant the generated step covers — every friction law, contact law and the disturbance — with every
    scheme: the same joint positions within 1e-9 rad, the same stick states, events and energy bookkeeping as the
    Python step. (The generated step's C driver and CasADi expressions are a second source of the Python step's
    physics: this is the test that fails when one changes without the other.)"""
    case = PLANTS[name]()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SimulationWarning)  # (velocity limits of the free runs)
        python, generated = (
            simulate(**regroup(case), duration=0.4, integrator=scheme, compile=c) for c in (False, True)
        )
    assert (python.info["compiled"], generated.info["compiled"]) == (False, True)
    assert not python.diverged and not generated.diverged
    assert np.abs(generated.q - python.q).max() <= 1e-9
    assert np.abs(generated.qd - python.qd).max() <= 1e-7
    np.testing.assert_array_equal(generated.stuck, python.stuck)
    for key in ("stick_events", "breakaway_events", "implicit_unconverged"):
        assert generated.info[key] == python.info[key], key
    scale = max(np.abs(python.work_actuator).max(), 1e-3)
    for work in ("work_friction", "work_external"):
        assert np.abs(getattr(generated, work) - getattr(python, work)).max() <= 1e-9 * scale, work
    np.testing.assert_allclose(generated.tau_friction, python.tau_friction, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(
        generated.contact_force_on_environment, python.contact_force_on_environment, rtol=1e-7, atol=1e-6
    )
    if name not in ("rigid panda",):
        assert python.info["stick_events"] + python.info["breakaway_events"] > 0 or name.endswith("smooth")


def test_stiction_holds_exactly_on_the_generated_step() -> None:
    """The Panda held by static friction stays where it is bit for bit on the generated step, its holding torque
    the gravity torque; a pendulum under a torque ramp breaks away when the net torque reaches F_s."""
    model = armctl.models.panda()
    q0 = np.array([0.2, -0.6, 0.1, -2.0, 0.3, 1.8, 0.5])
    g0 = armctl.Dynamics(model).gravity_torque(q0)
    sticky = model.with_friction(viscous=0.5, coulomb=np.abs(g0) + 1.0, static=np.abs(g0) + 3.0)
    res = simulate(sticky, zero_torque, armctl.Reference.hold(q0), 3.0, compile=True)
    assert res.info["compiled"]
    assert (res.q == q0).all() and (res.qd == 0.0).all() and (res.qdd == 0.0).all() and res.stuck.all()
    np.testing.assert_allclose(res.tau_friction[-1], -g0, rtol=1e-9, atol=1e-9)

    pendulum = armctl.models.pendulum().with_friction(coulomb=2.0, static=3.5)
    q0p, rate = 0.3, 2.0
    predicted = 2.0 * 9.81 * 0.25 * math.sin(q0p) + 3.5  # g(q0) + F_s
    ramp = simulate(pendulum, OpenLoop(Ramp([0.0], [rate])), armctl.Reference.hold([q0p]), 3.0, compile=True)
    moved = np.flatnonzero(ramp.q[:, 0] != q0p)
    assert ramp.info["compiled"] and moved.size
    assert (ramp.q[: moved[0], 0] == q0p).all()
    assert ramp.tau_applied[moved[0] - 1, 0] == pytest.approx(predicted, rel=0.01)


@pytest.fixture
def fresh_cache(tmp_path, monkeypatch: pytest.MonkeyPatch):  # type: ignore[no-untyped-def]
    """An empty cache, and a process that has loaded no library and warned about nothing yet."""
    monkeypatch.setenv("ARMCTL_CACHE", str(tmp_path))
    compiled_module.FALLBACK.reset()
    return tmp_path


def _friction_run(**kw: object) -> armctl.sim.SimResult:
    model = armctl.models.pendulum().with_friction(viscous=0.1, coulomb=1.0)
    return simulate(model, zero_torque, armctl.Reference.hold([1.0]), 0.2, **kw)


def test_without_a_compiler_the_run_takes_the_python_step_and_warns_once(fresh_cache, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """$CC names a program that is not there and nothing is cached: the run completes on the Python step with
    one warning that says how to get a compiler (not one per run); compile=True raises, naming $CC."""
    monkeypatch.setenv("CC", "/nonexistent/cc")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        runs = [_friction_run(), _friction_run()]
    said = [str(w.message) for w in caught if issubclass(w.category, PerformanceWarning)]
    assert len(said) == 1, said
    assert said[0].startswith("no C compiler was found ($CC = '/nonexistent/cc' is not a program on the PATH)")
    assert "apt install gcc" in said[0] and "compile=False" in said[0]
    assert [r.info["compiled"] for r in runs] == [False, False]
    assert runs[0].q[-1, 0] < 1.0  # it ran: the pendulum fell
    np.testing.assert_array_equal(runs[0].q, runs[1].q)
    assert not list(fresh_cache.rglob("*.so"))
    with pytest.raises(BackendError, match=r"\$CC = '/nonexistent/cc' is not a program"):
        _friction_run(compile=True)


def test_a_build_is_logged_once_with_its_time(fresh_cache, caplog) -> None:  # type: ignore[no-untyped-def]
    """The first run builds the library and logs one line with the time it took; later runs load it silently."""
    with caplog.at_level(logging.INFO, logger="armctl.codegen"):
        first = _friction_run()
        second = _friction_run(integrator="rk4")
    lines = [r.getMessage() for r in caplog.records if r.name == "armctl.codegen"]
    assert len(lines) == 1, lines
    assert "'pendulum'" in lines[0] and " s (cached in " in lines[0] and "\n" not in lines[0]
    assert first.info["compiled"] and second.info["compiled"]
    assert len(list(fresh_cache.rglob("*.so"))) == 1


def test_the_disturbance_is_sampled_at_the_start_middle_and_end_of_each_step() -> None:
    """Both steps evaluate a disturbance at the same instants: multiples of half a step (the start, middle and
    end of each step; the record's samples at the control instants)."""
    seen: dict[bool, set[float]] = {}
    for compile in (False, True):
        times: set[float] = set()

        def push(t: float, times: set[float] = times) -> np.ndarray:
            times.add(t)
            return np.array([-3.0 - t, 0.0, 0.0, 0.0, 0.0, 0.0])

        simulate(
            slider(2.0),
            zero_torque,
            armctl.Reference.hold([0.0]),
            0.01,
            dt=1e-3,
            compile=compile,
            forces=Forces(disturbance=push),
        )
        seen[compile] = times
    assert seen[False] == seen[True]
    halves = np.array(sorted(seen[True])) / 5e-4
    np.testing.assert_allclose(halves, np.round(halves), atol=1e-9)
    assert {round(x) for x in halves} == set(range(21))  # 0, 0.5 ms, …, 10 ms


def test_variants_of_a_plant_share_its_library(fresh_cache) -> None:  # type: ignore[no-untyped-def]
    """A payload, other friction levels or another table are inputs of the generated code, not part of it: the
    variants of a plant run on one library, each with its own dynamics (as the Python step has them)."""
    base = armctl.models.planar_2r().with_friction(viscous=5.0, coulomb=20.0, static=30.0)
    variants = [
        base,
        base.with_payload(8.0, (0.1, 0.0, 0.0), np.diag([0.01, 0.02, 0.02])),
        armctl.models.planar_2r().with_friction(viscous=2.0, coulomb=50.0, static=60.0),
    ]
    finals = []
    for model in variants:
        kw = {"q0": [0.3, -0.2], "qd0": [1.0, -2.0]}
        generated = simulate(model, zero_torque, armctl.Reference.hold([0.3, -0.2]), 0.3, **kw)
        python = simulate(model, zero_torque, armctl.Reference.hold([0.3, -0.2]), 0.3, compile=False, **kw)
        assert generated.info["compiled"]
        assert np.abs(generated.q - python.q).max() <= 1e-9
        finals.append(generated.q[-1])
    assert len(list(fresh_cache.rglob("*.so"))) == 1
    assert np.abs(finals[0] - finals[1]).max() > 1e-3 and np.abs(finals[0] - finals[2]).max() > 1e-3


def test_a_compiler_that_refuses_the_machine_s_flags_builds_portable_code(monkeypatch, tmp_path) -> None:
    """Where the plant's flags for this processor fail to compile, the library is built with the portable flags
    (the library of their key is the one built, and it loads)."""
    from armctl.sim import compiled_plant
    from armctl.sim.plant import Plant
    from armctl.sim.plant_layout import layout_of

    monkeypatch.setattr(compiled_plant, "FLAGS", (*compiled_plant.PORTABLE_FLAGS, "-mno-such-option-anywhere"))
    model = armctl.models.planar_2r()
    layout = layout_of(Plant(armctl.Dynamics(model)))
    assert not isinstance(layout, str)
    functions = compiled_plant.library(model, layout, "explicit", cache_dir=tmp_path)
    assert set(compiled_plant.DRIVER) <= set(functions)
    tag = compiled_plant.library_tag(model, layout, "explicit")[0]
    names = list(compiled_plant.DRIVER)
    portable = compiled_plant.codegen.library_path(names, tag, tmp_path, compiled_plant.PORTABLE_FLAGS)
    refused = compiled_plant.codegen.library_path(names, tag, tmp_path, compiled_plant.FLAGS)
    assert portable.exists() and not refused.exists()
