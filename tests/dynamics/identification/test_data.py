"""Data handling: zero-phase filtering, differentiation, parallel filtering, decimation, and bad logs."""

from __future__ import annotations

import numpy as np
import pytest

from armctl.dynamics.identification import IdentificationData, build_problem, prepare_data, solve_least_squares
from armctl.errors import IdentificationWarning, InvalidParameterError, NonFiniteError, ShapeError
from tests.helpers.arms import dynamics


def test_derivatives_of_a_noisy_sine_match_the_closed_form() -> None:
    """q = A sin(ωt) sampled at 1 kHz with 1e-4 rad noise: q̇ = Aω cos, q̈ = −Aω² sin (no phase lag)."""
    fs, w, amp = 1000.0, 2 * np.pi * 0.5, 0.8
    t = np.arange(0.0, 12.0, 1 / fs)
    rng = np.random.default_rng(0)
    q = (amp * np.sin(w * t))[:, None] + 1e-4 * rng.standard_normal((t.size, 1))
    data = prepare_data(t, q, np.zeros_like(q), cutoff=5.0, decimate=1)
    tk = t[list(data.kept)]
    k = np.asarray(data.kept)
    np.testing.assert_allclose(data.qd[k, 0], amp * w * np.cos(w * tk), atol=5e-3 * amp * w)
    np.testing.assert_allclose(data.qdd[k, 0], -amp * w**2 * np.sin(w * tk), atol=3e-2 * amp * w**2)


def test_parallel_filtering_keeps_coulomb_jumps_consistent() -> None:
    """Noise-free data of an arm with large Coulomb friction: filtering both τ and the regressor gives back
    the exact base parameters, whereas the sign jumps would bias a fit on filtered τ alone."""
    dyn = dynamics("puma560")
    fs = 200.0
    t = np.arange(0.0, 8.0, 1 / fs)
    rng = np.random.default_rng(1)
    a, b = 0.5 * rng.standard_normal((2, 6, 3))
    w = 2 * np.pi / 8.0 * np.arange(1, 4)
    q = (np.sin(np.outer(t, w)) / w) @ a.T - (np.cos(np.outer(t, w)) / w) @ b.T
    qd = np.cos(np.outer(t, w)) @ a.T + np.sin(np.outer(t, w)) @ b.T
    qdd = (-np.sin(np.outer(t, w)) * w) @ a.T + (np.cos(np.outer(t, w)) * w) @ b.T
    tau = np.array([dyn.inverse_dynamics(*x) for x in zip(q, qd, qdd, strict=True)])
    raw = IdentificationData(t, q, qd, qdd, tau)
    filtered = prepare_data(t, q, tau, cutoff=10.0)
    exact = IdentificationData(t, q, qd, qdd, tau, sos=filtered.sos, decimate=filtered.decimate, trim=filtered.trim)
    for data in (raw, exact):
        problem = build_problem(dyn, data)
        est = solve_least_squares(problem, weighted=False)
        truth = problem.base.project(dyn.model.parameters())
        np.testing.assert_allclose(est.theta[: truth.size], truth, atol=1e-6 * np.abs(truth).max())
        assert est.residual_rms.max() < 1e-6
    # τ filtered, regressor not: the smoothed Coulomb jumps leave a residual of the order of F_c
    only_tau = IdentificationData(t, q, qd, qdd, _filtered(exact, tau))
    est = solve_least_squares(build_problem(dyn, only_tau), weighted=False)
    assert est.residual_rms[0] > 1.0, est.residual_rms  # joint 1: F_c ≈ 26 N·m; 2.4 N·m here


def _filtered(data: IdentificationData, x: np.ndarray) -> np.ndarray:
    import scipy.signal

    return scipy.signal.sosfiltfilt(np.array(data.sos), x, axis=0)


def test_decimation_and_trimming() -> None:
    t = np.arange(0.0, 4.0, 1e-3)
    q = np.sin(t)[:, None] * np.ones((1, 2))
    with pytest.warns(IdentificationWarning, match=r"^trim=100 leaves the filter's start-up transient"):
        data = prepare_data(t, q, q, cutoff=10.0, decimate=20, trim=100)
    assert list(data.kept) == list(range(100, 4000 - 100, 20))
    assert data.reduce(q).shape == (len(data.kept), 2)
    with pytest.raises(InvalidParameterError, match="aliasing"):
        prepare_data(t, q, q, cutoff=10.0, decimate=60)


@pytest.mark.parametrize(("t_len", "q_len", "tau_len"), [(100, 99, 100), (100, 100, 98), (101, 100, 100)])
def test_mismatched_sample_counts_raise(t_len: int, q_len: int, tau_len: int) -> None:
    t = np.arange(t_len) * 1e-3
    with pytest.raises(ShapeError, match=rf"q \({q_len}, 2\), tau \({tau_len}, 2\)"):
        prepare_data(t, np.zeros((q_len, 2)), np.zeros((tau_len, 2)), cutoff=10.0)
    with pytest.raises(ShapeError, match=rf"\({q_len}, 2\)|{t_len} samples"):
        IdentificationData(t, np.zeros((q_len, 2)), np.zeros((q_len, 2)), np.zeros((q_len, 2)), np.zeros((tau_len, 2)))


def test_other_bad_logs_raise() -> None:
    t = np.arange(1000) * 1e-3
    z = np.zeros((1000, 2))
    with pytest.raises(ShapeError):
        prepare_data(t, z, np.zeros((1000, 3)), cutoff=10.0)  # joints differ
    t_bad = t.copy()
    t_bad[500:] += 0.01
    with pytest.raises(InvalidParameterError, match="uniformly"):
        prepare_data(t_bad, z, z, cutoff=10.0)
    with pytest.raises(InvalidParameterError, match="Nyquist"):
        prepare_data(t, z, z, cutoff=600.0)
    z_nan = z.copy()
    z_nan[3, 1] = np.nan
    with pytest.raises(NonFiniteError, match=r"^q holds NaN or inf"):
        prepare_data(t, z_nan, z, cutoff=10.0)
    with pytest.raises(ShapeError, match="joints"):
        build_problem(dynamics("planar_3r"), IdentificationData(t, z, z, z, z))


@pytest.mark.parametrize(
    ("kwargs", "shown"),
    [
        ({"order": 0}, "order"),
        ({"order": 2.7}, "2.7"),
        ({"decimate": 1.5}, "1.5"),
        ({"decimate": 0}, "decimate"),
        ({"trim": -1}, "trim"),
        ({"order": True}, "True"),
    ],
)
def test_filter_settings_must_be_whole_numbers(kwargs: dict[str, object], shown: str) -> None:
    # they were truncated silently (order=2.7 ran a 2nd-order filter) or accepted (order=0)
    t = np.arange(0.0, 2.0, 0.002)
    q = np.sin(t)[:, None]
    with pytest.raises(InvalidParameterError, match=shown):
        prepare_data(t, q, q, cutoff=5.0, **kwargs)  # type: ignore[arg-type]


def test_whole_floats_are_whole_numbers() -> None:
    t = np.arange(0.0, 2.0, 0.002)
    q = np.sin(t)[:, None]
    a, b = prepare_data(t, q, q, cutoff=5.0, order=4.0), prepare_data(t, q, q, cutoff=5.0, order=4)
    assert np.array_equal(a.qdd, b.qdd)
