"""PD + gravity on compiled dynamics runs τ = g(q) + F·[q_d; q̇_d; q; q̇] as one call of generated code
(:mod:`armctl.controllers.pd_generated`): checked against the textbook law with Pinocchio's own g (a second
implementation, written by others); a NaN in any input reaches τ as on the NumPy path."""

from __future__ import annotations

import pickle

import numpy as np
import pinocchio as pin
import pytest

import armctl
from armctl.controllers import PDGravity
from armctl.errors import NonFiniteError
from tests.helpers.arms import model


def _states(n: int, k: int = 4, seed: int = 5) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return list(rng.uniform(-1.5, 1.5, (k, n)))


def _spd(rng: np.random.Generator, n: int, scale: float) -> np.ndarray:
    a = rng.normal(size=(n, n))
    return scale * (a @ a.T / n + np.eye(n))


def test_pd_gravity_runs_as_one_call_of_the_generated_code() -> None:
    """PDGravity on compiled dynamics uses the fused law τ = g(q) + F·[q_d; q̇_d; q; q̇] (one call of the generated
    code): checked against the textbook law with Pinocchio's own g, with full (non-diagonal) gains so that a
    transposed F would show; reassigned gains take effect; two controllers on one object keep their own gains;
    a pickled controller rebinds; the integral and friction terms still add."""
    m = model("puma560")
    dc = armctl.Dynamics(m, compile=True)
    pm = m.to_pinocchio()
    pd = pm.createData()
    rng = np.random.default_rng(11)
    kp, kd, kp2 = _spd(rng, m.n, 100.0), _spd(rng, m.n, 20.0), _spd(rng, m.n, 50.0)
    q, qd, q_ref, qd_ref = _states(m.n)
    ref = armctl.Reference(q_ref, qd_ref)

    def textbook(kp: np.ndarray, kd: np.ndarray, q: np.ndarray = q) -> np.ndarray:
        return kp @ (q_ref - q) + kd @ (qd_ref - qd) + pin.computeGeneralizedGravity(pm, pd, q)

    a, b = PDGravity(dc, kp, kd), PDGravity(dc, kp2, kd)
    for _ in range(2):  # interleaved: each its own F
        np.testing.assert_allclose(a(0.0, q, qd, ref), textbook(kp, kd), rtol=1e-12, atol=1e-10)
        np.testing.assert_allclose(b(0.0, q, qd, ref), textbook(kp2, kd), rtol=1e-12, atol=1e-10)
    assert a._law is not None and PDGravity(armctl.Dynamics(m), kp, kd)._law is None  # fused, and only here
    a.kp = kp2
    np.testing.assert_allclose(a(0.0, q, qd, ref), textbook(kp2, kd), rtol=1e-12, atol=1e-10)
    copy = pickle.loads(pickle.dumps(a))
    np.testing.assert_allclose(copy(0.0, q, qd, ref), a(0.0, q, qd, ref), rtol=1e-12, atol=1e-12)
    assert copy(0.0, q, qd, ref) is not copy(0.0, q, qd, ref)  # a new array each step, not the buffer
    ki = _spd(rng, m.n, 5.0)
    c, p = (PDGravity(d, kp, kd, ki=ki, friction=True) for d in (dc, armctl.Dynamics(m)))
    for t in (0.0, 1e-3, 2e-3):
        np.testing.assert_allclose(c(t, q, qd, ref), p(t, q, qd, ref), rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize(("which", "name"), [(0, "q"), (1, "qd")])
def test_a_nan_in_the_state_is_named_on_the_generated_law(which: int, name: str) -> None:
    """F is a symbol of the generated code: every entry of τ depends on every input, so the result-only check
    still names a NaN in q or q̇ (checked after τ, which the NaN reaches)."""
    m = model("planar_2r")
    ctrl = PDGravity(armctl.Dynamics(m, compile=True), 100.0, 20.0)
    assert ctrl._checks_result
    q, qd, q_ref, qd_ref = (np.array(x) for x in _states(m.n))
    ref = armctl.Reference(q_ref, qd_ref)
    ctrl(0.0, q, qd, ref)
    assert ctrl._law is not None
    state = [q.copy(), qd.copy()]
    state[which][1] = np.nan
    tau = ctrl._law(state[0], state[1], ref.q, ref.qd)
    assert np.isnan(tau).all()  # every entry: the NaN reaches τ through the generated code
    with pytest.raises(NonFiniteError, match=rf"^{name}"):
        ctrl(0.0, state[0], state[1], ref)
