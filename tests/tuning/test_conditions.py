"""The textbook conditions in closed loop: where they hold the simulated arm does what they promise; past the
border the run shows what they warn of (a second equilibrium, a larger tracking error, divergence). And their
numbers against closed forms: the L1 norms of a critically damped loop, the robust inertia estimate, the
sampled-data margin at one inertia (python-control's gain margin)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

import armctl
from armctl.controllers import Controller, PDDesiredGravity, PDGravity
from armctl.errors import InvalidParameterError
from armctl.references import Sinusoid
from armctl.sim import simulate
from armctl.tuning import (
    SampledDataAnalysis,
    computed_torque_condition,
    model_bounds,
    pd_desired_gravity_condition,
    pid_condition,
    robust_inertia_estimate,
    sampled_data_condition,
)
from armctl.tuning.inertia_estimate import impulse_l1_norms
from tests.helpers.arms import dynamics, model


def _bounds(name: str) -> armctl.tuning.ModelBounds:
    return model_bounds(dynamics(name), samples=500)


# ------------------------------------------------------------------------------ PD with desired gravity
# (name, set-point where ∂g/∂q reaches k_g: upright, starts, K_d)
PD_CASES = {
    "pendulum": (np.array([math.pi]), [[math.pi - 2.5], [math.pi - 0.3], [math.pi + 0.01], [math.pi + 3.0]]),
    "planar_2r": (np.array([math.pi / 2, 0.0]), [[math.pi / 2 + 0.05, 0.0], [0.0, 0.0], [math.pi, -2.0]]),
}


def _settle(name: str, kp: float, kd: float, set_point: np.ndarray, start: list[float]) -> armctl.SimResult:
    dyn = dynamics(name)
    return simulate(
        model(name), PDDesiredGravity(dyn, kp, kd), armctl.Reference(set_point), 40.0, q0=start, control_dt=2e-3
    )


@pytest.mark.parametrize("name", ["pendulum", "planar_2r"])
def test_pd_desired_gravity_condition_in_closed_loop(name: str) -> None:
    """K_p 5 % above the certified k_g: every start settles at the set-point. 5 % below the k_g met at the
    upright set-point (where ‖∂g/∂q‖ is largest) the set-point is no longer the only equilibrium: the runs
    settle at rest elsewhere, at a solution of K_p (q_d − q) = g(q) − g(q_d)."""
    b = _bounds(name)
    set_point, starts = PD_CASES[name]
    dyn = dynamics(name)
    j = float(np.linalg.eigvalsh(dyn.mass_matrix(set_point)).max())
    above, below = 1.05 * b.k_g, 0.95 * b.details["k_g"].estimate
    assert pd_desired_gravity_condition(b, above).holds
    verdict = pd_desired_gravity_condition(b, below)
    assert not verdict.holds and verdict.margin == pytest.approx(below - b.k_g) and verdict.certified
    kd = 2 * math.sqrt(0.05 * b.k_g * j) if name == "pendulum" else 250.0
    for start in starts:
        res = _settle(name, above, kd, set_point, start)
        assert np.abs(res.q[-1] - set_point).max() < 1e-3, (start, res.q[-1])
    elsewhere = 0
    for start in starts:
        res = _settle(name, below, kd, set_point, start)
        q_end = res.q[-1]
        assert np.abs(res.qd[-1]).max() < 1e-3  # at rest
        if np.abs(q_end - set_point).max() > 0.1:
            elsewhere += 1
            residual = below * (set_point - q_end) + dyn.gravity_torque(set_point) - dyn.gravity_torque(q_end)
            assert np.abs(residual).max() < 1e-2 * b.k_g  # an equilibrium of the closed loop
    assert elsewhere >= 1


def test_pd_condition_without_gravity_holds_for_every_gain() -> None:
    free = armctl.Dynamics(replace(model("planar_2r"), gravity=np.zeros(3)))
    b = model_bounds(free, samples=200)
    verdict = pd_desired_gravity_condition(b, 1e-3)
    assert b.k_g <= 1e-9 * b.lambda_max and verdict.holds and verdict.factor > 1e3
    with pytest.raises(InvalidParameterError, match="positive definite"):
        pd_desired_gravity_condition(b, [1.0, -1.0])


# ------------------------------------------------------------------------------------------------ PID
def test_pid_tuning_of_kelly_in_closed_loop() -> None:
    """The pendulum under a PID without gravity compensation (PDGravity on a gravity-free controller model),
    tuned by the rule: K_d above the required value; it reaches the set-point from either side. The rule's
    K_d is the formula's, from the bounds."""
    b = _bounds("pendulum")
    kp, ki = 2 * b.k_g, 5.0
    required = ki / (kp - b.k_g) * b.lambda_max**2 / b.lambda_min
    verdict = pid_condition(b, kp, 0.5, ki)
    assert verdict.holds and verdict.details["kd_required"] == pytest.approx(required)
    assert not pid_condition(b, kp, 0.9 * required, ki).holds
    assert not pid_condition(b, 0.9 * b.k_g, 10.0, ki).holds
    controller_model = armctl.Dynamics(replace(model("pendulum"), gravity=np.zeros(3)))
    for start in (math.pi / 2 + 0.3, math.pi / 2 - 0.3):
        res = simulate(
            model("pendulum"),
            PDGravity(controller_model, kp, 0.5, ki=ki),
            armctl.Reference([math.pi / 2]),
            20.0,
            q0=[start],
        )
        assert abs(res.q[-1, 0] - math.pi / 2) < 1e-3


# ------------------------------------------------------------------------ computed torque, constant M̂
class ConstantInertiaComputedTorque(Controller):
    """τ = c v + C q̇ + g, v = q̈_d + K_d ė + K_p e: computed torque whose inertia estimate is c I."""

    def __init__(self, dyn: armctl.Dynamics, c: float, kp: float, kd: float) -> None:
        super().__init__(dyn)
        self.c, self.kp, self.kd = c, kp, kd

    def compute(self, t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        v = ref.qdd + self.kd * (ref.qd - qd) + self.kp * (ref.q - q)
        dyn = self.dynamics
        assert dyn is not None
        return self.c * v + dyn.coriolis_matrix(q, qd) @ qd + dyn.gravity_torque(q)


def test_l1_norms_of_a_critically_damped_loop() -> None:
    """ζ = 1, ω: g(t) = t e^(−ωt) ≥ 0, so ‖g‖₁ = 1/ω²; h(t) = ω e^(−ωt)(2 − ωt), ‖h‖₁ = 1 + 2 e⁻²."""
    for w in (1.0, 10.0, 40.0):
        g1, h1 = impulse_l1_norms(w * w, 2 * w)
        assert g1 == pytest.approx(1 / w**2, rel=1e-6)
        assert h1 == pytest.approx(1 + 2 * math.exp(-2), rel=1e-6)
    g1, h1 = impulse_l1_norms(100.0, 4.0)  # underdamped: overshoot, ‖g‖₁ > 1/k_p
    assert g1 > 1 / 100 and h1 > 1.5


# its run goes beyond a velocity limit on the way, as expected
@pytest.mark.filterwarnings("ignore:the run went beyond the plant's limits:armctl.errors.SimulationWarning")
# its run saturates the torque, as expected
@pytest.mark.filterwarnings("ignore:torque at its limit on most samples:armctl.errors.SimulationWarning")
def test_computed_torque_with_a_constant_inertia_in_closed_loop() -> None:
    """Planar 2R, 200 Hz, one period of delay, K_p = 100, K_d = 20, a sinusoid with ‖q̈_d‖ ≤ a:

    * M̂ = c* I, the robust estimate: α γ < 1, and the tracking error after the transient stays within the bound;
    * M̂ = λ_m/5 I: α < 1 still (the textbook premise) but α γ > 1: no guarantee, and the error grows past
      five times the robust estimate's;
    * M̂ = 6 λ_M I: α ≫ 1; the sampled-data condition says the loop is unstable on the arm's light directions, and
      the run diverges (without torque limits)."""
    b = _bounds("planar_2r")
    dyn = dynamics("planar_2r")
    amp, freq = np.array([0.6, 0.8]), np.array([0.3, 0.4])
    ref = Sinusoid([0.5, 1.0], amp, freq)
    a = float(np.linalg.norm(amp * (2 * np.pi * freq) ** 2))
    period = 0.005

    def run(c: float) -> armctl.SimResult:
        return simulate(
            model("planar_2r"),
            ConstantInertiaComputedTorque(dyn, c, 100.0, 20.0),
            ref,
            10.0,
            control_dt=period,
            dt=1e-3,
            delay=1,
            saturate=False,
        )

    def tracking_error(res: armctl.SimResult) -> float:
        late = res.t > 3.0
        qref = np.array([ref(float(t)).q for t in res.t[late]])
        return float(np.linalg.norm(qref - res.q[late], axis=1).max())

    c_star, alpha_star = robust_inertia_estimate(b)
    good = computed_torque_condition(b, c_star, 100.0, 20.0, max_acceleration=a)
    assert good.holds and good.certified and good.details["alpha"] == pytest.approx(alpha_star)
    assert sampled_data_condition(b, 100.0, 20.0, period, 1, inertia_estimate=c_star).holds
    err_good = tracking_error(run(c_star))
    assert err_good <= good.details["error_bound"]

    light = b.lambda_min / 5
    weak = computed_torque_condition(b, light, 100.0, 20.0, max_acceleration=a)
    assert weak.details["alpha_below_one"] and not weak.holds and math.isinf(weak.details["error_bound"])
    assert tracking_error(run(light)) > 5 * err_good

    heavy = 6 * b.lambda_max
    assert not computed_torque_condition(b, heavy, 100.0, 20.0).holds
    assert not sampled_data_condition(b, 100.0, 20.0, period, 1, inertia_estimate=heavy).holds
    assert run(heavy).diverged


def test_robust_estimate_minimises_alpha() -> None:
    b = _bounds("planar_3r")
    c, alpha = robust_inertia_estimate(b)
    assert alpha == pytest.approx((b.lambda_max - b.lambda_min) / (b.lambda_max + b.lambda_min))
    for other in (0.9 * c, 1.1 * c):
        assert computed_torque_condition(b, other, 100.0, 20.0).details["alpha"] > alpha
    # a general M̂: from a sample of the ranges, not certified; without dynamics, a cruder certified bound
    mhat = np.diag([3.0, 1.0, 0.3])
    sampled = computed_torque_condition(b, mhat, 100.0, 20.0, dynamics=dynamics("planar_3r"), samples=300)
    crude = computed_torque_condition(b, mhat, 100.0, 20.0)
    assert not sampled.certified and crude.certified
    assert crude.details["alpha"] >= sampled.details["alpha"]


# ---------------------------------------------------------------------------------------- sampled data
def test_sampled_data_condition_at_one_inertia_is_the_gain_margin() -> None:
    """On the pendulum (λ_m = λ_M = J) with the exact model, the factor is python-control's gain margin of the
    nominal loop; a PD's critical gain is J times that of the per-unit loop."""
    b = _bounds("pendulum")
    j = b.lambda_min
    assert b.lambda_max == pytest.approx(j, rel=1e-9)
    v = sampled_data_condition(b, 100.0, 20.0, 0.01, 1, inertia_estimate=j)
    assert v.factor == pytest.approx(SampledDataAnalysis.of(100.0, 20.0, 0.01, 1).critical_multiplier, rel=1e-6)
    pd = sampled_data_condition(b, 100.0 * j, 20.0 * j, 0.01, 1)
    assert pd.details["critical_kp"] == pytest.approx(100.0 * j * v.factor, rel=1e-6)


# its run goes beyond a velocity limit on the way, as expected
@pytest.mark.filterwarnings("ignore:the run went beyond the plant's limits:armctl.errors.SimulationWarning")
# its run saturates the torque, as expected
@pytest.mark.filterwarnings("ignore:torque at its limit on most samples:armctl.errors.SimulationWarning")
def test_sampled_data_condition_in_closed_loop() -> None:
    """PD + gravity on the planar 2R at 100 Hz with one period of delay, regulating at the stretched elbow
    where the inertia along the arm is λ_m: 5 % below the critical gain over [λ_m, λ_M] the arm settles, 5 %
    above it does not, and 25 % above it diverges."""
    b = _bounds("planar_2r")
    dyn = dynamics("planar_2r")
    v = sampled_data_condition(b, 1.0, 0.2, 0.01, 1)
    critical = v.details["critical_kp"]
    assert v.holds and v.factor == pytest.approx(critical)
    set_point = np.array([0.3, 0.0])

    def run(k: float) -> armctl.SimResult:
        return simulate(
            model("planar_2r"),
            PDGravity(dyn, k, 0.2 * k),
            armctl.Reference(set_point),
            6.0,
            q0=set_point + np.array([0.02, -0.02]),
            control_dt=0.01,
            dt=1e-3,
            delay=1,
            saturate=False,
        )

    assert np.abs(run(0.95 * critical).q[-1] - set_point).max() < 1e-6
    res = run(1.05 * critical)
    assert res.diverged or np.abs(res.q[-1] - set_point).max() > 1e-2
    assert run(1.25 * critical).diverged
    assert not sampled_data_condition(b, 1.05 * critical, 0.2 * 1.05 * critical, 0.01, 1).holds


# ------------------------------------------------------------------------------------------------ the text
def _numbers(text: str) -> list[float]:
    import re

    return [float(x) for x in re.findall(r"(?<![\w(])-?\d+(?:\.\d+)?(?:e[+-]?\d+)?", text)]


def test_a_failing_condition_is_printed_as_the_comparison_that_holds() -> None:
    """Below k_g the condition reads "λ_min(K_p) = a ≤ k_g = b: fails", a true statement about the numbers, and
    above it "a > b"; the two numbers printed are the gain and the bound."""
    b = _bounds("pendulum")
    kp_low, kp_high = 0.5 * b.k_g, 2.0 * b.k_g
    low = pd_desired_gravity_condition(b, kp_low).condition
    high = pd_desired_gravity_condition(b, kp_high).condition
    assert low.startswith("λ_min(K_p) = ") and " ≤ k_g = " in low and ": fails" in low
    assert " > " not in low.split(":")[0]
    assert " > k_g = " in high and "fails" not in high
    a, bound = _numbers(low)[:2]
    assert a == pytest.approx(kp_low, rel=1e-4) and bound == pytest.approx(b.k_g, rel=1e-4) and a <= bound
    pid = pid_condition(b, kp_low, 10.0, 5.0).condition
    assert " ≤ k_g = " in pid and ": fails" in pid
    required = 5.0 / (kp_high - b.k_g) * b.lambda_max**2 / b.lambda_min
    weak = pid_condition(b, kp_high, 0.5 * required, 5.0).condition
    assert " > k_g = " in weak and "λ_min(K_d) = " in weak and " ≤ " in weak and ": fails" in weak


def test_a_failing_inertia_estimate_condition_is_printed_as_it_stands() -> None:
    b = _bounds("planar_2r")
    heavy = 6.0 * b.lambda_max * np.eye(2)
    verdict = computed_torque_condition(b, heavy, 100.0, 20.0)
    assert not verdict.holds and " ≥ 1: fails" in verdict.condition and " < 1" not in verdict.condition.split(":")[0]
