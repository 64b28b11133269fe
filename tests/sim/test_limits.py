"""`LimitReport.of_run` against its definitions (the module's formulas written out sample by sample)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armctl.sim.limits import VELOCITY_TOLERANCE, LimitReport

pytestmark = pytest.mark.one_step  # no simulation


def _by_definition(
    tau: np.ndarray, q: np.ndarray, qd: np.ndarray, effort: np.ndarray, velocity: np.ndarray, lower, upper
) -> dict[str, list[float]]:
    """Each figure of joint j over the N samples, by the module's formulas, one sample at a time."""
    n_s, n = tau.shape
    out: dict[str, list[float]] = {k: [] for k in ("saturated", "torque_peak", "velocity_peak", "velocity_over")}
    out.update({"position_overrun": [], "position_over": []})
    for j in range(n):
        t, v, p = tau[:, j].tolist(), qd[:, j].tolist(), q[:, j].tolist()
        out["saturated"].append(sum(abs(x) > effort[j] for x in t) / n_s)
        out["torque_peak"].append(max(abs(x) for x in t) / effort[j])
        out["velocity_peak"].append(max(abs(x) for x in v) / velocity[j])
        out["velocity_over"].append(sum(abs(x) > (1.0 + VELOCITY_TOLERANCE) * velocity[j] for x in v) / n_s)
        beyond = [max(lower[j] - x, x - upper[j], 0.0) for x in p]
        out["position_overrun"].append(max(beyond))
        out["position_over"].append(sum(b > 0.0 for b in beyond) / n_s)
    return out


limits = st.floats(0.5, 50.0) | st.just(math.inf)


@settings(max_examples=60, deadline=None)
@given(
    samples=st.integers(1, 40),
    n=st.integers(1, 4),
    seed=st.integers(0, 2**32 - 1),
    effort=st.lists(limits, min_size=4, max_size=4),
    velocity=st.lists(limits, min_size=4, max_size=4),
    half_range=st.lists(st.floats(0.1, 3.0) | st.just(math.inf), min_size=4, max_size=4),
)
def test_the_report_is_its_definition(
    samples: int, n: int, seed: int, effort: list, velocity: list, half_range: list
) -> None:
    """Random commands and motions against finite and infinite limits, samples exactly at a limit included: every
    figure equals the module's formula taken sample by sample."""
    rng = np.random.default_rng(seed)
    tau, q, qd = (rng.normal(scale=s, size=(samples, n)) for s in (20.0, 2.0, 5.0))
    f, v = np.array(effort[:n]), np.array(velocity[:n])
    lower, upper = -np.array(half_range[:n]), np.array(half_range[:n]) * 0.8
    tau[0] = np.where(np.isfinite(f), f, tau[0])  # at the limit: not beyond it
    q[-1] = np.where(np.isfinite(upper), upper, q[-1])
    report = LimitReport.of_run(tau, q, qd, f, v, lower, upper, tuple(f"j{i}" for i in range(n)))
    expected = _by_definition(tau, q, qd, f, v, lower, upper)
    for name, values in expected.items():
        np.testing.assert_array_equal(getattr(report, name), np.array(values), err_msg=name)
    assert report.samples == samples


def test_a_run_without_samples_reports_zeros() -> None:
    report = LimitReport.of_run(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros((0, 2)), *([np.ones(2)] * 4), ("a", "b"))
    assert report.samples == 0 and not report.saturated.any() and not report.position_over.any()
