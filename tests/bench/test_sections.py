"""The benchmark sections ``integrators``, ``backends`` and ``fidelity``, each run once in quick mode:
finite numbers, the orderings theory predicts, and a written chart."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import armctl
from armctl.bench import backends, fidelity, integrators
from armctl.errors import SimulationWarning


def _finite_numbers(x: Any, path: str = "") -> list[str]:
    """Paths of the numbers in ``x`` that are not finite (booleans and None are not numbers here)."""
    if isinstance(x, dict):
        return [p for k, v in x.items() for p in _finite_numbers(v, f"{path}.{k}")]
    if isinstance(x, list | tuple):
        return [p for i, v in enumerate(x) for p in _finite_numbers(v, f"{path}[{i}]")]
    if isinstance(x, float | int) and not isinstance(x, bool) and not math.isfinite(x):
        return [path]
    return []


def _check_section(module: Any, data: dict[str, Any], tmp_path: Path) -> None:
    json.dumps(data, allow_nan=False)  # JSON-serialisable, no NaN or inf
    assert _finite_numbers(data) == []
    assert module.summary(data).strip()
    png = tmp_path / f"{module.__name__.rsplit('.', 1)[-1]}.png"
    module.plot(data, png)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert png.stat().st_size > 10_000


# ----------------------------------------------------------------------------------------------- integrators
@pytest.fixture(scope="module")
def integ() -> dict[str, Any]:
    return integrators.run(quick=True)


def test_integrators_section(integ: dict[str, Any], tmp_path: Path) -> None:
    _check_section(integrators, integ, tmp_path)
    assert set(integ["integrators"]) == {*integrators.INTEGRATORS, "rk4-compiled"}
    for d in integ["integrators"].values():
        assert all(c["cost"] > 0 and c["error"] > 0 and not c["diverged"] for c in d["cases"])


def test_independent_reference_is_accurate(integ: dict[str, Any]) -> None:
    """DOP853 at rtol 1e-11 agrees with itself at rtol 1e-13, and with the simulator's finest RK4 run (a
    different method) far below the Euler errors."""
    assert integ["reference"]["error_estimate"] < 1e-12
    assert min(c["error"] for c in integ["integrators"]["rk4"]["cases"]) < 1e-10


def test_rk4_is_fourth_order(integ: dict[str, Any]) -> None:
    """Halving the step divides RK4's error by ~16 in its asymptotic range."""
    d = integ["integrators"]["rk4"]
    valid = [p for p in d["orders"] if p is not None]
    assert len(valid) >= 3
    assert all(3.6 < p < 4.4 for p in valid)
    assert 3.8 < d["asymptotic_order"] < 4.2


@pytest.mark.parametrize("name", ["semi-implicit-euler", "implicit-euler"])
def test_euler_schemes_are_first_order(integ: dict[str, Any], name: str) -> None:
    d = integ["integrators"][name]
    valid = [p for p in d["orders"] if p is not None]
    assert len(valid) == len(d["orders"])
    assert all(0.85 < p < 1.15 for p in valid)
    assert 0.95 < d["asymptotic_order"] < 1.05


def test_rk4_beats_euler_at_every_step(integ: dict[str, Any]) -> None:
    rk4 = integ["integrators"]["rk4"]["cases"]
    for name in ("semi-implicit-euler", "implicit-euler"):
        for a, b in zip(rk4, integ["integrators"][name]["cases"], strict=True):
            assert a["step"] == b["step"]
            assert a["error"] < 1e-3 * b["error"]


def test_compiled_rk4_series_is_rk4(integ: dict[str, Any]) -> None:
    """The compiled step is the same scheme on the same model: its errors are RK4's to rounding (far below the
    finest error, 1e-11 rad here), its own cost is measured."""
    rk4, compiled = integ["integrators"]["rk4"], integ["integrators"]["rk4-compiled"]
    for a, b in zip(rk4["cases"], compiled["cases"], strict=True):
        assert a["step"] == b["step"]
        assert abs(a["error"] - b["error"]) < 1e-13 + 1e-6 * a["error"]
        assert b["cost"] > 0 and b["wall_s"] > 0
    assert compiled["asymptotic_order"] == pytest.approx(rk4["asymptotic_order"], abs=0.01)


def test_observed_orders_of_a_power_law() -> None:
    steps = [0.1 / 2**k for k in range(5)]
    errors = [3.0 * h**4 for h in steps]
    orders = integrators.observed_orders(steps, errors, floor=1e-8)
    assert orders[:3] == pytest.approx([4.0, 4.0, 4.0])
    assert orders[3] is None  # the finer error (4.6e-9) is below the floor


# -------------------------------------------------------------------------------------------------- backends
@pytest.fixture(scope="module")
def back() -> dict[str, Any]:
    return backends.run(quick=True)


def test_backends_section(back: dict[str, Any], tmp_path: Path) -> None:
    _check_section(backends, back, tmp_path)
    assert {"puma560", "panda"} <= set(back["arms"])
    for arm in back["arms"].values():
        assert all(c["cost_s"] > 0 and c["error"] >= 0 for c in arm["candidates"].values())


def test_compiled_reference_is_exact(back: dict[str, Any]) -> None:
    for arm in back["arms"].values():
        cands = arm["candidates"]
        if "lagrange_compiled" in cands:  # the reference's own expressions, compiled to C
            assert cands["lagrange_compiled"]["error"] < 1e-12


def _coupling_torque(lag: armctl.Dynamics, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """τ_Δ = ΔM q̈ + Σ_jk (∂ΔM_ij/∂q_k − ½ ∂ΔM_jk/∂q_i) q̇_j q̇_k from the rotor-coupling part ΔM(q) of the mass
    matrix alone (central differences): the Lagrange equations of T_Δ = ½ q̇ᵀ ΔM q̇, which has no potential."""
    eps = 1e-6
    n = len(q)
    dm = np.empty((n, n, n))  # dm[k] = ∂ΔM/∂q_k
    for k in range(n):
        e = np.zeros(n)
        e[k] = eps
        dm[k] = (lag.rotor_coupling_matrix(q + e) - lag.rotor_coupling_matrix(q - e)) / (2 * eps)
    mdot_qd = np.einsum("kij,k,j->i", dm, qd, qd)
    grad = np.einsum("ijk,j,k->i", dm, qd, qd)
    return lag.rotor_coupling_matrix(q) @ qdd + mdot_qd - 0.5 * grad


def test_pinocchio_error_is_exactly_the_rotor_coupling(back: dict[str, Any]) -> None:
    """Pinocchio's armature model misses only the rotors' gyroscopic coupling: its error equals that of the
    Lagrange backend without coupling, and the size of the coupling torque τ_Δ computed here on its own from
    the coupling part ΔM of the mass matrix (on the benchmark's states); clearly nonzero on arms with motors,
    zero on the Panda."""
    for name, arm in back["arms"].items():
        c = arm["candidates"]
        assert c["pinocchio"]["error"] == pytest.approx(c["lagrange_vm_nc"]["error"], rel=1e-6, abs=1e-12)
        model = backends.arm_model(name)
        if arm["has_motors"]:
            lag = armctl.Dynamics(model, backend="lagrange")
            rows = zip(*backends.random_states(model, arm["states"]), strict=True)
            tau = np.array([_coupling_torque(lag, *row) for row in rows])
            share = math.sqrt((tau**2).sum(axis=1).mean()) / arm["tau_rms"]
            assert c["pinocchio"]["error"] == pytest.approx(share, rel=1e-5)
            assert c["pinocchio"]["error"] > 1e-4, name
        else:
            assert c["pinocchio"]["error"] < 1e-12, name
    assert not back["arms"]["panda"]["has_motors"]


def test_simplified_models_cost_accuracy(back: dict[str, Any]) -> None:
    """Dropping the rotors or the friction is a far larger error than the missing coupling."""
    for arm in back["arms"].values():
        c = arm["candidates"]
        for key in ("pinocchio_no_rotors", "pinocchio_no_friction", "pinocchio_rigid"):
            if key in c:
                assert c[key]["error"] > 10 * max(c["pinocchio"]["error"], 1e-6)
        if "pinocchio_rigid" in c:
            assert c["pinocchio_rigid"]["error"] >= c["pinocchio_no_friction"]["error"]


def test_relative_rms() -> None:
    ref = np.array([[3.0, 4.0], [0.0, 0.0]])
    assert backends.relative_rms(ref, ref) == 0.0
    assert backends.relative_rms(1.1 * ref, ref) == pytest.approx(0.1)


# -------------------------------------------------------------------------------------------------- fidelity
@pytest.fixture(scope="module")
def fid() -> dict[str, Any]:
    return fidelity.run(quick=True)


def test_fidelity_section(fid: dict[str, Any], tmp_path: Path) -> None:
    _check_section(fidelity, fid, tmp_path)
    assert {"planar_2r", "panda_topp"} <= set(fid["scenes"])


def test_every_term_has_a_share(fid: dict[str, Any]) -> None:
    for s in fid["scenes"].values():
        assert set(s["shares"]) == set(fidelity.TERMS)
        assert s["shares"]["contact"] == 0.0  # no scene here touches anything


def test_term_shares_by_hand() -> None:
    """RMS √(mean_s ‖τ(s)‖²) of each term and its share of the sum, on terms whose RMS is known: a constant
    (3, 4) has RMS 5; rows (1, 0) and (−1, 0) have RMS 1; zeros have 0."""
    terms = {"a": np.array([[3.0, 4.0], [3.0, 4.0]]), "b": np.array([[1.0, 0.0], [-1.0, 0.0]]), "c": np.zeros((2, 2))}
    out = fidelity.term_shares(terms)
    assert out["rms"] == pytest.approx({"a": 5.0, "b": 1.0, "c": 0.0})
    assert out["shares"] == pytest.approx({"a": 5.0 / 6.0, "b": 1.0 / 6.0, "c": 0.0})
    assert out["sum_of_term_rms"] == pytest.approx(6.0)
    assert out["required_rms"] == pytest.approx(np.sqrt((32.0 + 20.0) / 2))  # rows (4, 4) and (2, 4)
    assert out["rms_per_joint"]["a"] == pytest.approx([3.0, 4.0])
    assert out["rms_per_joint"]["b"] == pytest.approx([1.0, 0.0])


def test_shares_follow_the_models(fid: dict[str, Any]) -> None:
    """No motors on the Panda: no rotor term; no friction on the 2R arm; friction where the plant has it;
    the 2R arm's rotors (k_r = 100) are a large share."""
    sc = fid["scenes"]
    assert sc["panda_topp"]["shares"]["rotor"] == 0.0
    assert sc["planar_2r"]["shares"]["friction"] == 0.0
    assert sc["pendulum"]["shares"]["friction"] > 0.01
    assert sc["panda_topp"]["shares"]["friction"] > 0.005
    assert sc["planar_2r"]["shares"]["rotor"] > 0.1


def test_terms_add_up_to_the_exact_inverse_dynamics() -> None:
    """inertia + Coriolis + gravity + rotor + friction = the exact (Lagrange, rotor-coupled) τ of the plant."""
    model = armctl.models.planar_2r().with_friction(viscous=0.5, coulomb=2.0)
    ref = armctl.references.Sinusoid([0.3, -0.4], [0.4, 0.5], [0.5, 0.7])
    times = np.linspace(0.0, 2.0, 7)
    terms = fidelity.model_terms(model, model, ref, times)
    exact = armctl.Dynamics(model, backend="lagrange", rotor_coupling=True)
    for i, t in enumerate(times):
        r = ref(float(t))
        total = sum(terms[k][i] for k in fidelity.TERMS)
        np.testing.assert_allclose(total, exact.inverse_dynamics(r.q, r.qd, r.qdd), rtol=1e-9, atol=1e-9)


def test_gravity_dominates_a_rest_like_reference() -> None:
    model = armctl.models.planar_2r()
    slow = armctl.references.Sinusoid([0.3, -0.4], [0.4, 0.5], [0.01, 0.01])
    shares = fidelity.term_shares(fidelity.model_terms(model, model, slow, np.linspace(0.0, 20.0, 50)))["shares"]
    assert shares["gravity"] > 0.99
    assert max(shares, key=shares.__getitem__) == "gravity"


def test_choice_is_the_cheapest_within_the_factor(fid: dict[str, Any]) -> None:
    for s in fid["scenes"].values():
        cl = s["closed_loop"]
        cands, choice = cl["candidates"], cl["candidates"][cl["choice"]]
        assert cl["threshold"] == pytest.approx(fid["factor"] * cands[cl["baseline"]]["rms_error"])
        assert not choice["diverged"] and choice["rms_error"] <= cl["threshold"]
        for c in cands.values():
            if not c["diverged"] and c["rms_error"] <= cl["threshold"]:
                assert choice["compute_s"] <= (1 + cl["tie"]) * c["compute_s"]


def test_dropping_the_rotors_breaks_tracking_on_the_2r_arm(fid: dict[str, Any]) -> None:
    """Reflected rotor inertia k_r² I_m = 100 kg·m² is most of the 2R arm's inertia: without it computed
    torque misses its error dynamics by far, so the chosen model keeps the rotors."""
    cl = fid["scenes"]["planar_2r"]["closed_loop"]
    no_rotor = [c for c in cl["candidates"].values() if not c["kept"]["rotors"]]
    assert no_rotor and all(c["rms_error"] > 10 * cl["threshold"] for c in no_rotor)
    assert cl["choice_kept"]["rotors"]


def test_choose_tie_prefers_fewer_terms() -> None:
    def cand(err: float, cost: float, rotors: bool, friction: bool) -> dict[str, Any]:
        return {
            "rms_error": err,
            "compute_s": cost,
            "diverged": False,
            "kept": {"rotors": rotors, "friction": friction},
        }

    cands = {
        "full": cand(1.0, 10.0, True, True),
        "lean": cand(1.5, 10.5, False, True),
        "bad": cand(3.0, 1.0, False, False),
    }
    assert fidelity.choose(cands, "full", factor=2.0, tie=0.1) == "lean"
    assert fidelity.choose(cands, "full", factor=2.0, tie=0.0) == "full"
    assert fidelity.choose(cands, "full", factor=4.0, tie=0.1) == "bad"


def test_the_adaptive_stability_map_adapts_with_the_scene_preset_gain() -> None:
    """Not Γ → 0 (which made the map the passivity-based one): the pendulum scene's preset Γ."""
    from armctl.bench import stability
    from armctl.tuning.presets import load_preset

    ctrl = stability.make_controller("adaptive", 1.0, 2.0)
    gamma = np.asarray(load_preset("pendulum", "adaptive")["gains"]["gamma"])
    np.testing.assert_array_equal(ctrl.gamma, np.diag(gamma))
    assert not ctrl.projection


def test_time_controllers_checks_rounds_and_skips_empty_windows() -> None:
    import math

    from armctl.bench.suite import time_controllers
    from armctl.errors import InvalidParameterError

    empty = {"t": [], "q": np.zeros((0, 1)), "qd": np.zeros((0, 1)), "ref": []}
    rows = [{"scene": "pendulum", "method": "pd_gravity", "compute_s": 1.0, "window": empty}]
    with pytest.raises(InvalidParameterError, match="rounds must be a whole number >= 1, got 0"):
        time_controllers([dict(rows[0], window=empty)], 0)
    time_controllers(rows, 2)
    assert math.isnan(rows[0]["compute_s"]) and rows[0]["compute_timing"] == "no recorded steps to replay"
    assert "window" not in rows[0]


def test_pareto_front_compares_noisy_times_by_their_quartiles() -> None:
    from armctl.bench.suite import pareto_front

    # (time, error): a is fast and coarse, b slow and exact, c slower than a only by noise and more accurate
    points = [(10.0, 3e-3), (40.0, 1e-4), (12.0, 2e-3), (11.0, 5e-3), (float("nan"), 1e-9)]
    assert pareto_front(points) == [0, 1, 2]  # the strict order: d is beaten by a; NaN never on the front
    spans = [(8.0, 14.0), (35.0, 45.0), (9.0, 16.0), (9.5, 13.0), (0.0, 0.0)]
    # with quartiles a and c tie in time, and c is the more accurate: a drops off; d ties with both, beaten
    assert pareto_front(points, spans) == [1, 2]
    # the same medians with quartiles that no longer overlap: a is clearly faster and back on the front
    apart = [(9.9, 10.1), (39.0, 41.0), (11.9, 12.1), (10.9, 11.1), (0.0, 0.0)]
    assert pareto_front(points, apart) == [0, 1, 2]
    # a point without quartiles (NaN) is compared by its median: it does not tie with everyone on time
    assert pareto_front(
        [(1.0, 1.0), (10.0, 0.5), (100.0, 0.1)], [(0.9, 1.1), (9.0, 11.0), (float("nan"), float("nan"))]
    ) == [0, 1, 2]


def test_a_diverged_run_has_no_tracking_error_to_rank() -> None:
    from armctl.scenes import scene

    sc = scene("pendulum")
    # gains far beyond the sampled-data border (k·T² ≫ 4), without torque limits to bound the growth
    with pytest.warns(SimulationWarning, match="over its velocity limit"):  # on its way to diverging
        res = sc.run("computed_torque", gains={"kp": 1e7, "kd": 1e4}, saturate=False)
    assert res.diverged
    m = sc.metrics(res, "computed_torque", gains={"kp": 1e7, "kd": 1e4}, timing_rounds=0)
    # before this was NaN, the error up to the divergence (~7e-3 rad at 0.2 s) ranked it above stable methods
    assert math.isnan(m["rms_error"]) and math.isnan(m["max_error"])
    assert 0.0 < m["rms_error_until_divergence"] <= m["max_error_until_divergence"]
    want = np.array([sc.reference(t).q for t in res.t])
    assert m["rms_error_until_divergence"] == pytest.approx(float(np.sqrt(((res.q - want) ** 2).mean())))


def test_a_failing_method_is_a_row_of_the_bench(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    from armctl.bench import suite
    from armctl.errors import SolverError
    from armctl.scenes.base import Scene

    def failing_run(self: Scene, method: str, gains: Any = None, **overrides: Any) -> Any:
        raise SolverError("the QP is infeasible at t = 0.3 s")

    monkeypatch.setattr(Scene, "run", failing_run)
    row = suite.run_scene_method("pendulum", "pd_gravity")
    assert row["failed"] == "SolverError: the QP is infeasible at t = 0.3 s"
    assert math.isnan(row["rms_error"]) and math.isnan(row["compute_s"]) and not row["diverged"]
    ok = {
        "scene": "pendulum",
        "method": "computed_torque",
        "rms_error": 1e-4,
        "max_error": 2e-4,
        "torque_rms": 1.0,
        "compute_s": 1e-5,
        "compute_s_iqr": [9e-6, 1.1e-5],
        "diverged": False,
        "diverged_at": None,
    }
    late = dict(ok, method="passivity", rms_error=float("nan"), max_error=float("nan"), diverged=True, diverged_at=0.21)
    suite.time_controllers([row], 1)  # nothing to replay: skipped, not an error
    rows = [dict(row), ok, late]
    suite.plot_pareto(rows, tmp_path / "chart.png")
    assert (tmp_path / "chart.png").stat().st_size > 1000
    lines = suite.summary({"scenes": rows, "total_seconds": 1.0}).splitlines()
    assert any("pd_gravity" in ln and "FAILED (SolverError: the QP is infeasible" in ln for ln in lines)
    assert any("passivity" in ln and "diverged at 0.21 s" in ln for ln in lines)
    assert any("computed_torque" in ln and ln.endswith("ok") for ln in lines)


def test_fidelity_makes_no_choice_against_a_diverged_full_model() -> None:
    def cand(err: float, cost: float, diverged: bool = False) -> dict[str, Any]:
        return {"rms_error": err, "compute_s": cost, "diverged": diverged, "kept": {"rotors": True, "friction": True}}

    # the full model diverged (NaN error): 2 × its error was a threshold of NaN before, or of the error
    # until the divergence, under which a cheaper model was "sufficient"
    cands = {"full": cand(float("nan"), 10.0, diverged=True), "lean": cand(1e-3, 5.0)}
    assert fidelity.choose(cands, "full") is None


def test_a_scene_that_cannot_be_built_is_a_failed_row(monkeypatch: pytest.MonkeyPatch) -> None:
    import armctl.scenes
    from armctl.bench import suite
    from armctl.errors import InfeasibleError

    def unbuildable(name: str) -> Any:
        raise InfeasibleError("torque limit of joint 2 exceeded at s = 0.4")

    monkeypatch.setattr(suite, "SCENE_NAMES", ("panda_topp",))
    monkeypatch.setattr(armctl.scenes, "scene", unbuildable)
    rows = suite.scene_matrix("serial", rounds=1)
    assert [(r["scene"], r["method"], r["failed"]) for r in rows] == [
        ("panda_topp", "(scene)", "InfeasibleError: torque limit of joint 2 exceeded at s = 0.4")
    ]
    assert "window" not in rows[0]
