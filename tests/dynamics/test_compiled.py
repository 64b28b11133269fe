"""``Dynamics(model, compile=True)``: the Pinocchio backend with gravity, forward dynamics, the passivity torque
and both regressors in generated C (:mod:`armctl.dynamics.compiled`). Every term is checked against Pinocchio
called directly (its generalized gravity, ABA, RNEA and joint-torque regressor: a second implementation,
written by others), on every built-in arm and a hand-made one with a prismatic joint and tilted axes; the
friction columns against the friction torque; the disk cache; objects that share a library; pickling; the
controllers' torques."""

from __future__ import annotations

import gc
import itertools
import pickle

import numpy as np
import pinocchio as pin
import pytest

import armctl
from armctl.controllers import Adaptive, ComputedTorque, PassivityBased, PDGravity
from armctl.dynamics import compiled
from armctl.errors import BackendError, InvalidParameterError
from tests.dynamics.helpers import skewed_rpr
from tests.helpers.arms import MODEL_NAMES, model

NAMES = (*MODEL_NAMES, "skewed_rpr")


def _model(name: str) -> armctl.RobotModel:
    return skewed_rpr() if name == "skewed_rpr" else model(name)


def _states(n: int, k: int = 4, seed: int = 5) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    out = list(rng.uniform(-1.5, 1.5, (k, n)))
    out[1][0] = 0.0  # a joint at rest: the Coulomb column's sgn 0 = 0
    return out


def _pin_regressor(
    pm: pin.Model, pd: pin.Data, m: armctl.RobotModel, q: np.ndarray, v: np.ndarray, a: np.ndarray
) -> np.ndarray:
    """The rigid-body and rotor columns of Y from Pinocchio's regressor (its ten columns per joint are π's,
    see RobotModel.parameters) and the rotor column q̈_i: Y (n × 13n) without the friction columns."""
    n = m.n
    y = np.zeros((n, 13 * n))
    raw = pin.computeJointTorqueRegressor(pm, pd, q, v, a).reshape(n, 10 * n)  # eigenpy squeezes n = 1
    for j in range(n):
        y[:, 13 * j : 13 * j + 10] = raw[:, 10 * j : 10 * j + 10]
        y[j, 13 * j + 10] = a[j]
    return y


@pytest.mark.parametrize("name", NAMES)
def test_compiled_terms_agree_with_pinocchio_called_directly(name: str) -> None:
    m = _model(name)
    dc = armctl.Dynamics(m, compile=True)
    pm = m.to_pinocchio()
    pd = pm.createData()
    n = m.n
    pi = m.parameters()
    for seed in range(3):
        q, qd, qd_r, qdd = _states(n, seed=seed)
        tau_f = dc.friction_torque(qd)
        # gravity and forward dynamics (ABA with the friction torque subtracted, as the API defines it)
        np.testing.assert_allclose(
            dc.gravity_torque(q), pin.computeGeneralizedGravity(pm, pd, q), rtol=1e-10, atol=1e-10
        )
        np.testing.assert_allclose(
            dc.forward_dynamics(q, qd, qdd), pin.aba(pm, pd, q, qd, qdd - tau_f), rtol=1e-8, atol=1e-8
        )
        # the regressor: Pinocchio's columns, and Y π = τ (RNEA plus friction)
        y = dc.regressor(q, qd, qdd)
        rigid = [c for c in range(13 * n) if c % 13 < 11]
        np.testing.assert_allclose(y[:, rigid], _pin_regressor(pm, pd, m, q, qd, qdd)[:, rigid], rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(y @ pi, pin.rnea(pm, pd, q, qd, qdd) + tau_f, rtol=1e-10, atol=1e-9)
        # the passivity regressor and torque: M q̈_r + C(q, q̇) q̇_r + g from Pinocchio's M and Coriolis matrix
        coriolis = pin.computeCoriolisMatrix(pm, pd, q, qd)
        expected = (
            pin.crba(pm, pd, q) @ qdd
            + coriolis @ qd_r
            + pin.computeGeneralizedGravity(pm, pd, q)
            + dc.friction_torque(qd)
            - m.parameters()[11::13] * (qd - qd_r)
        )  # viscous at q̇_r
        yp = dc.passivity_regressor(q, qd, qd_r, qdd)
        np.testing.assert_allclose(yp @ pi, expected, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(dc.passivity_torque(q, qd, qd_r, qdd), expected, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("name", ["pendulum", "puma560", "panda", "skewed_rpr"])
def test_every_regressor_entry_matches_the_plain_backend(name: str) -> None:
    # entry by entry, friction columns included (the Puma's Coulomb friction is asymmetric, and the RPR arm's
    # is made so: the column's ratio is an input of the compiled code)
    m = _model(name)
    if name == "skewed_rpr":
        m = m.with_friction(viscous=[0.1, 0.2, 0.3], coulomb=[1.0, 2.0, 0.5], coulomb_negative=[0.5, 2.0, 1.5])
    dc, dp = armctl.Dynamics(m, compile=True), armctl.Dynamics(m)
    for seed in range(3):
        q, qd, qd_r, qdd = _states(m.n, seed=seed)
        np.testing.assert_allclose(dc.regressor(q, qd, qdd), dp.regressor(q, qd, qdd), rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(
            dc.passivity_regressor(q, qd, qd_r, qdd), dp.passivity_regressor(q, qd, qd_r, qdd), rtol=1e-10, atol=1e-10
        )
        for friction in (None, (qd_r, qd)):  # the primitive's other friction columns
            np.testing.assert_allclose(
                dc.kernel.regressor(q, qd, qdd, friction),
                dp.kernel.regressor(q, qd, qdd, friction),
                rtol=1e-10,
                atol=1e-10,
            )


def test_friction_variants_share_a_library_and_keep_their_own_coulomb_ratio(tmp_path, monkeypatch) -> None:
    base = armctl.models.planar_2r()
    armctl.Dynamics(base, compile=True, cache_dir=tmp_path)
    monkeypatch.setattr(compiled, "symbolic_functions", lambda m: pytest.fail("rebuilt a cached library"))
    asym = base.with_friction(viscous=0.3, coulomb=2.0, coulomb_negative=0.5)  # F_c⁺ = 2, F_c⁻ = 0.5
    dc = armctl.Dynamics(asym, compile=True, cache_dir=tmp_path)  # loaded, not built
    assert len(list(tmp_path.rglob("*.so"))) == 1
    q, qd, qdd = np.array([0.2, -0.4]), np.array([0.5, -0.7]), np.array([0.1, 0.3])
    y = dc.regressor(q, qd, qdd)
    np.testing.assert_allclose(
        y @ asym.parameters(), armctl.Dynamics(asym).inverse_dynamics(q, qd, qdd), rtol=1e-12, atol=1e-12
    )
    np.testing.assert_allclose(y[:, [12, 25]].diagonal(), [2.0 / 1.25, -0.5 / 1.25])  # F_c^± / F̄_c


def test_a_variant_with_another_tool_frame_shares_the_library(tmp_path, monkeypatch) -> None:
    # the generated code holds joint-space terms only: a tool frame elsewhere changes none of them
    from dataclasses import replace

    base = armctl.models.planar_2r()
    armctl.Dynamics(base, compile=True, cache_dir=tmp_path)
    monkeypatch.setattr(compiled, "symbolic_functions", lambda m: pytest.fail("rebuilt a cached library"))
    other = replace(base, tool_frame=base.joint_names[0])
    assert other.fingerprint() != base.fingerprint()
    dc = armctl.Dynamics(other, compile=True, cache_dir=tmp_path)
    assert len(list(tmp_path.rglob("*.so"))) == 1
    q = np.array([0.3, 0.4])
    np.testing.assert_allclose(dc.frame_pose(q), armctl.Dynamics(other).frame_pose(q), atol=1e-12)  # its own tool
    assert not np.allclose(dc.frame_pose(q), armctl.Dynamics(base).frame_pose(q))
    np.testing.assert_allclose(dc.gravity_torque(q), armctl.Dynamics(other).gravity_torque(q), rtol=1e-12)


def test_a_payload_builds_its_own_library(tmp_path) -> None:
    arm = armctl.models.planar_2r()
    heavy = arm.with_payload(2.0, (0.05, 0.0, 0.0))
    a, b = (
        armctl.Dynamics(arm, compile=True, cache_dir=tmp_path),
        armctl.Dynamics(heavy, compile=True, cache_dir=tmp_path),
    )
    assert len(list(tmp_path.rglob("*.so"))) == 2
    q = np.array([0.3, 0.4])
    np.testing.assert_allclose(b.gravity_torque(q), armctl.Dynamics(heavy).gravity_torque(q), rtol=1e-12)
    assert not np.allclose(a.gravity_torque(q), b.gravity_torque(q))


def test_objects_sharing_a_library_do_not_share_buffers() -> None:
    # each object binds its own arrays (inputs, outputs and the constants the code reads, kept alive: an early
    # version let its constant zero be freed, and the next allocation gave every term an offset)
    m = model("panda")
    a = armctl.Dynamics(m, compile=True)
    b = armctl.Dynamics(m, compile=True)
    gc.collect()
    _ = [np.full(50, 7.0) for _ in range(100)]  # reuse freed memory, if any was
    plain = armctl.Dynamics(m)
    q1, q2 = _states(7)[:2]
    for dyn, q in ((a, q1), (b, q2), (a, q2), (b, q1)):
        np.testing.assert_allclose(dyn.gravity_torque(q), plain.gravity_torque(q), rtol=1e-12, atol=1e-12)


def test_a_bad_cache_dir_is_named(tmp_path) -> None:
    m = model("planar_2r")
    with pytest.raises(InvalidParameterError, match="cache_dir must be a path"):
        armctl.Dynamics(m, compile=True, cache_dir=123)
    for backend in ("pinocchio", "lagrange"):  # nothing is compiled: the folder would be ignored
        with pytest.raises(InvalidParameterError, match=r"pass compile=True or 'auto' too"):
            armctl.Dynamics(m, backend=backend, cache_dir=tmp_path)
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    with pytest.raises(BackendError, match="cannot create the cache folder"):
        armctl.Dynamics(m, compile=True, cache_dir=blocked / "cache")


def test_options_repr_and_pickle() -> None:
    m = model("planar_2r")
    dc = armctl.Dynamics(m, compile=True)
    assert dc.backend == "pinocchio" and dc.options["compile"] is True
    assert "compile=True" in repr(dc)
    again = pickle.loads(pickle.dumps(dc))
    q = np.array([0.1, 0.2])
    assert again.options["compile"] and np.array_equal(again.gravity_torque(q), dc.gravity_torque(q))
    plain = armctl.Dynamics(m, compile=False)
    assert not plain.compiled and "compile" not in plain.options and "compile" not in repr(plain)
    with pytest.raises(InvalidParameterError, match=r"compile must be True .*'auto'"):
        armctl.Dynamics(m, compile="yes")


def test_controllers_give_the_same_torques_on_compiled_dynamics() -> None:
    m = model("puma560")
    dc, dp = armctl.Dynamics(m, compile=True), armctl.Dynamics(m)
    q, qd, qd_r, qdd = _states(m.n)
    ref = armctl.Reference(q + 0.05, qd_r, qdd)
    laws = (
        lambda d: PDGravity(d, 100.0, 20.0, friction=True),
        lambda d: ComputedTorque(d, 100.0, 20.0),
        lambda d: PassivityBased(d, 5.0, 20.0),
        lambda d: Adaptive(d, 5.0, 20.0, 0.01, composite=0.5),
    )
    for law in laws:
        c, p = law(dc), law(dp)
        for t in itertools.islice(itertools.count(0.0, 1e-3), 5):  # the adaptive law integrates between calls
            np.testing.assert_allclose(c(t, q, qd, ref), p(t, q, qd, ref), rtol=1e-10, atol=1e-10)


def test_simulation_on_a_compiled_plant_matches_the_plain_one() -> None:
    m = model("planar_2r")
    ctrl = PDGravity(armctl.Dynamics(m), 400.0, 40.0)
    ref = armctl.Reference(np.array([0.5, -0.3]))
    runs = [armctl.simulate(armctl.Dynamics(m, compile=c), ctrl, ref, 0.5, q0=np.zeros(2)) for c in (False, True)]
    np.testing.assert_allclose(runs[1].q, runs[0].q, rtol=0, atol=1e-10)
    assert abs(runs[0].q[-1, 0]) > 0.1  # it moved
