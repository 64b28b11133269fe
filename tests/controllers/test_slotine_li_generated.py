"""The Slotine–Li laws on both paths: ``compile="auto"`` (their default: one call of generated C code,
:mod:`armctl.controllers.slotine_li_generated`) and ``compile=False`` (NumPy on Pinocchio's terms). Each is checked
against the textbook law written with Pinocchio's M, C and g and the model's friction (an implementation neither
path uses), on random states with full gains, and the two paths against each other within 1e-9 step after step
with every feature of the adaptive law; without a C compiler ``"auto"`` warns once and gives the same τ."""

from __future__ import annotations

import logging
import pickle
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import pytest

import armctl
from armctl.controllers import Adaptive, PassivityBased
from armctl.controllers import passivity as passivity_module
from armctl.errors import BackendError, InvalidParameterError, NonFiniteError, PerformanceWarning
from tests.helpers.arms import model as builtin

PATHS = ["auto", False]


def _panda_with_rotors_and_friction() -> armctl.RobotModel:
    base = builtin("panda")
    pi = base.parameters().copy()
    pi[10::13] = np.linspace(0.05, 0.3, base.n)  # reflected rotor inertias k_r² I_m
    return base.with_parameters(pi).with_friction(
        viscous=np.linspace(0.5, 1.5, base.n), coulomb=0.8, coulomb_negative=np.linspace(0.4, 1.2, base.n)
    )


def _arm(name: str) -> armctl.RobotModel:
    return _panda_with_rotors_and_friction() if name == "panda+rotors+friction" else builtin(name)


ARMS = ["planar_2r", "puma560", "panda+rotors+friction"]


def _spd(rng: np.random.Generator, n: int, scale: float) -> np.ndarray:
    a = rng.normal(size=(n, n))
    return scale * (a @ a.T / n + np.eye(n))


def _textbook(m: armctl.RobotModel, q: Any, qd: Any, ref: Any, lam: Any, kd: Any) -> tuple[np.ndarray, ...]:
    """(τ, model term, K_D s, s) of M q̈_r + C(q, q̇) q̇_r + g + F_v q̇_r + F_c(q̇) − K_D s with Pinocchio's M (its
    armature the rotors), C and g, and the friction levels F_c⁺ / −F_c⁻ read off the model's joints."""
    pm = m.to_pinocchio()
    data = pm.createData()
    qd_r = ref.qd - lam @ (q - ref.q)
    qdd_r = ref.qdd - lam @ (qd - ref.qd)
    s = qd - qd_r
    mass = pin.crba(pm, data, q)
    mass = np.triu(mass) + np.triu(mass, 1).T
    coriolis = pin.computeCoriolisMatrix(pm, data, q, qd)
    gravity = pin.computeGeneralizedGravity(pm, data, q)
    fr = [j.friction for j in m.joints]
    viscous = np.array([f.viscous for f in fr])
    coulomb = np.array(
        [f.coulomb if v > 0 else (-f.coulomb_neg if v < 0 else 0.0) for f, v in zip(fr, qd, strict=True)]
    )
    model_term = mass @ qdd_r + coriolis @ qd_r + gravity + viscous * qd_r + coulomb
    return model_term - kd @ s, model_term, kd @ s, s


def _state(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray, armctl.Reference]:
    q, qd, q_d, qd_d, qdd_d = rng.uniform(-1.5, 1.5, (5, n))
    return q, qd, armctl.Reference(q_d, qd_d, qdd_d)


@pytest.mark.parametrize("compile", PATHS)
@pytest.mark.parametrize("name", ARMS)
def test_passivity_based_is_the_textbook_law_on_both_paths(name: str, compile: Any) -> None:
    """τ and the logged model term, damping and s equal the textbook law's on random states, with full
    (non-diagonal) gains so that gains applied entry by entry would show; reassigned gains take effect."""
    m = _arm(name)
    rng = np.random.default_rng(3)
    lam, kd = _spd(rng, m.n, 4.0), _spd(rng, m.n, 20.0)
    ctrl = PassivityBased(armctl.Dynamics(m), lam, kd, compile=compile)
    assert ctrl.uses_generated_code is (compile == "auto")
    for _ in range(4):
        q, qd, ref = _state(rng, m.n)
        tau, model_term, damping, s = _textbook(m, q, qd, ref, lam, kd)
        np.testing.assert_allclose(ctrl(0.0, q, qd, ref), tau, rtol=1e-10, atol=1e-9)
        log = ctrl.last_log
        assert sorted(log) == ["damping", "model", "s"]
        np.testing.assert_allclose(log["model"], model_term, rtol=1e-10, atol=1e-9)
        np.testing.assert_allclose(log["damping"], damping, rtol=1e-12, atol=1e-10)
        np.testing.assert_allclose(log["s"], s, rtol=1e-12, atol=1e-12)
    lam2 = _spd(rng, m.n, 2.0)
    ctrl.lam = lam2
    np.testing.assert_allclose(ctrl(0.0, q, qd, ref), _textbook(m, q, qd, ref, lam2, kd)[0], rtol=1e-10, atol=1e-9)


@pytest.mark.parametrize("name", ARMS)
def test_passivity_based_paths_agree_and_return_new_arrays(name: str) -> None:
    m = _arm(name)
    dyn = armctl.Dynamics(m)
    rng = np.random.default_rng(8)
    gen, plain = PassivityBased(dyn, 3.0, 15.0), PassivityBased(dyn, 3.0, 15.0, compile=False)
    for _ in range(5):
        q, qd, ref = _state(rng, m.n)
        a, b = gen(0.0, q, qd, ref), plain(0.0, q, qd, ref)
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-9)
        for key in plain.last_log:
            np.testing.assert_allclose(gen.last_log[key], plain.last_log[key], rtol=1e-12, atol=1e-9)
    assert gen(0.0, q, qd, ref) is not gen(0.0, q, qd, ref)  # a new array each step, not the buffer
    copy = pickle.loads(pickle.dumps(gen))  # rebinds its generated law
    assert copy.uses_generated_code
    np.testing.assert_allclose(copy(0.0, q, qd, ref), gen(0.0, q, qd, ref), rtol=1e-14, atol=1e-14)


ADAPTIVE_CASES = {
    "plain": {},
    "sigma+dead_zone": {"sigma": 0.3, "dead_zone": 1.0},
    "diagonal": {"gamma": "diagonal"},
    "full": {"gamma": "full"},
    "projection+radius": {"projection": True, "radius": 5.0},
    "composite": {"composite": 2.0, "sigma": 0.1},
    "plant": {"plant": True},
}


def _adaptive(dyn: armctl.Dynamics, case: str, compile: Any) -> Adaptive:
    options = dict(ADAPTIVE_CASES[case])
    p = 13 * dyn.n
    gamma: Any = options.pop("gamma", 0.5)
    if gamma == "diagonal":
        gamma = np.linspace(0.1, 1.0, p)
    elif gamma == "full":
        b = np.random.default_rng(4).uniform(-1.0, 1.0, (p, p))
        gamma = 0.5 * np.eye(p) + 0.01 * (b @ b.T)
    if options.pop("plant", False):
        options["plant"] = armctl.Dynamics(dyn.model)
    theta0 = dyn.parameters() * 0.8
    return Adaptive(dyn, 4.0, 15.0, gamma, theta0=theta0, compile=compile, **options)


@pytest.mark.parametrize("case", sorted(ADAPTIVE_CASES))
@pytest.mark.parametrize("name", ARMS)
def test_adaptive_paths_agree_step_after_step(name: str, case: str) -> None:
    """τ, θ̂ and the logs of the generated path equal the NumPy path's over steps with a jittering dt (a repeated
    time, dt = 0, included), for every feature of the law."""
    m = _arm(name)
    dyn = armctl.Dynamics(m)
    gen, plain = _adaptive(dyn, case, "auto"), _adaptive(dyn, case, False)
    assert gen.uses_generated_code and not plain.uses_generated_code
    rng = np.random.default_rng(21)
    t = 0.0
    for k in range(8):
        q, qd, ref = _state(rng, m.n)
        a, b = gen(t, q, qd, ref), plain(t, q, qd, ref)
        scale = 1.0 + np.abs(b).max()
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-9 * scale)
        np.testing.assert_allclose(gen.theta, plain.theta, rtol=0, atol=1e-9 * (1.0 + np.abs(plain.theta).max()))
        assert sorted(gen.last_log) == sorted(plain.last_log)
        np.testing.assert_allclose(gen.last_log["s"], plain.last_log["s"], rtol=1e-12, atol=1e-12)
        assert gen.last_log["theta"] is gen.theta
        if "V" in plain.last_log:
            np.testing.assert_allclose(gen.last_log["V"], plain.last_log["V"], rtol=1e-9)
        if k != 3:  # step 4 repeats the time: no update
            t += 0.01 * (1.0 + 1e-3 * rng.standard_normal())
    assert not np.allclose(gen.theta, gen.theta0)  # the estimate moved


def test_adaptive_holds_theta_in_the_dead_zone_and_follows_gain_changes() -> None:
    dyn = armctl.Dynamics(builtin("puma560"))
    rng = np.random.default_rng(2)
    gen, plain = (Adaptive(dyn, 4.0, 15.0, 0.5, dead_zone=1e6, compile=c) for c in PATHS)
    q, qd, ref = _state(rng, dyn.n)
    for t in (0.0, 0.01, 0.02):
        np.testing.assert_allclose(gen(t, q, qd, ref), plain(t, q, qd, ref), rtol=1e-12, atol=1e-9)
    assert np.array_equal(gen.theta, gen.theta0)  # held: ‖s‖ < δ
    for c in (gen, plain):
        c.dead_zone = 0.0
        c.kd = 30.0
        c.gamma = 0.2
    for t in (0.03, 0.04):
        np.testing.assert_allclose(gen(t, q, qd, ref), plain(t, q, qd, ref), rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(gen.theta, plain.theta, rtol=1e-12, atol=1e-12)
    assert not np.array_equal(gen.theta, gen.theta0)


def test_one_library_per_arm_structure(
    tmp_path: Path, caplog: pytest.LogCaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A payload or friction variant of an arm loads the library its structure built (one build, logged once)."""
    m = builtin("planar_2r")
    variants = [m, m.with_payload(0.5), m.with_friction(viscous=0.2, coulomb=0.1)]
    monkeypatch.setenv("ARMCTL_CACHE", str(tmp_path))  # an empty cache: the first one builds
    with caplog.at_level(logging.WARNING, logger="armctl.codegen"):
        ctrls = [PassivityBased(armctl.Dynamics(v), 2.0, 5.0) for v in variants]
    builds = [r for r in caplog.records if "Slotine" in r.getMessage()]
    assert len(builds) == 1 and all(c.uses_generated_code for c in ctrls)
    q, qd, ref = _state(np.random.default_rng(0), 2)
    for v, c in zip(variants, ctrls, strict=True):  # each with its own parameters
        np.testing.assert_allclose(c(0.0, q, qd, ref), _textbook(v, q, qd, ref, 2.0 * np.eye(2), 5.0 * np.eye(2))[0])


def test_a_nan_in_the_state_is_named_on_the_generated_law() -> None:
    """Λ and K_D are symbols of the generated code: a NaN in q or q̇ reaches every entry of τ, so the result-only
    check still names it."""
    ctrl = PassivityBased(armctl.Dynamics(builtin("panda")), 3.0, 10.0)
    assert ctrl.uses_generated_code and ctrl._checks_result
    q, qd, ref = _state(np.random.default_rng(1), 7)
    for which, name in ((0, "q"), (1, "qd")):
        state = [q.copy(), qd.copy()]
        state[which][0] = np.nan
        with pytest.raises(NonFiniteError, match=rf"^{name}"):
            ctrl(0.0, state[0], state[1], ref)


def test_compile_takes_the_three_values_of_the_policy() -> None:
    dyn = armctl.Dynamics(builtin("planar_2r"))
    for value in ("yes", 1, None):
        with pytest.raises(InvalidParameterError, match=r"compile must be True .*False .*'auto'.*got "):
            PassivityBased(dyn, 1.0, 1.0, compile=value)
        with pytest.raises(InvalidParameterError, match=r"compile must be True .*False .*'auto'.*got "):
            Adaptive(dyn, 1.0, 1.0, 1.0, compile=value)
    lagrange = armctl.Dynamics(builtin("planar_2r"), backend="lagrange", rotor_coupling=False)
    assert not PassivityBased(lagrange, 1.0, 1.0).uses_generated_code  # "auto": the backend's own terms
    assert PassivityBased(lagrange, 1.0, 1.0, compile=True).uses_generated_code


@pytest.fixture
def no_compiler(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """No C compiler and an empty cache; the laws' fallback warning forgotten (a fresh process)."""
    monkeypatch.setenv("CC", "no-such-compiler-armctl")
    monkeypatch.setenv("ARMCTL_CACHE", str(tmp_path))
    passivity_module.FALLBACK.reset()
    yield tmp_path
    passivity_module.FALLBACK.reset()


def test_without_a_compiler_auto_warns_once_and_gives_the_same_torque(no_compiler: Path) -> None:
    dyn = armctl.Dynamics(builtin("planar_3r"))
    q, qd, ref = _state(np.random.default_rng(5), 3)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        made = [PassivityBased(dyn, 2.0, 8.0), Adaptive(dyn, 2.0, 8.0, 0.1), PassivityBased(dyn, 2.0, 8.0)]
    said = [w for w in caught if issubclass(w.category, PerformanceWarning)]
    assert len(said) == 1 and said[0].filename == __file__, [str(w.message) for w in said]
    assert str(said[0].message).startswith("no C compiler was found") and "Slotine" in str(said[0].message)
    assert not any(c.uses_generated_code for c in made)
    assert not list(no_compiler.rglob("*.so"))
    np.testing.assert_array_equal(
        made[0](0.0, q, qd, ref), PassivityBased(dyn, 2.0, 8.0, compile=False)(0.0, q, qd, ref)
    )
    np.testing.assert_array_equal(
        made[1](0.0, q, qd, ref), Adaptive(dyn, 2.0, 8.0, 0.1, compile=False)(0.0, q, qd, ref)
    )
    with pytest.raises(BackendError, match=r"\$CC = 'no-such-compiler-armctl' is not a program"):
        PassivityBased(dyn, 2.0, 8.0, compile=True)


def test_each_thread_runs_the_law_on_buffers_of_its_own() -> None:
    """A controller called from another thread binds the generated law to that thread's kernel: the same τ there
    as here, and here again after."""
    from concurrent.futures import ThreadPoolExecutor

    dyn = armctl.Dynamics(builtin("puma560"))
    gen, plain = PassivityBased(dyn, 3.0, 15.0), PassivityBased(dyn, 3.0, 15.0, compile=False)
    q, qd, ref = _state(np.random.default_rng(6), dyn.n)
    expected = plain(0.0, q, qd, ref)
    here = gen(0.0, q, qd, ref)
    with ThreadPoolExecutor(1) as pool:
        there = pool.submit(gen, 0.0, q, qd, ref).result()
    for tau in (here, there, gen(0.0, q, qd, ref)):
        np.testing.assert_allclose(tau, expected, rtol=1e-12, atol=1e-9)
