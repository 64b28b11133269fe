"""The report: condition number, estimates ± σ, residual torques per joint, a validation plot."""

from __future__ import annotations

import subprocess
import sys

import numpy as np

import armctl
import armctl.dynamics.identification as ident
from tests.dynamics.identification.helpers import Case, measure


def test_validation_on_fresh_noisy_data_and_report(puma_case: Case) -> None:
    res = puma_case.result
    t, q, tau = measure(armctl.Dynamics(puma_case.truth), puma_case.validation, periods=1, seed=3)
    val = res.validate(ident.prepare_data(t, q, tau, cutoff=5.0))
    assert val.predicted.shape == val.measured.shape == (len(val.t), 6)
    # measured torques here are filtered but noisy: the error is that noise left in band (≪ 2%)
    assert np.all(val.relative_error < 0.02), val.relative_error
    text = res.report(val)
    assert f"{res.condition_number:.4g}" in text
    assert "Residual torques" in text and "Validation" in text and "Physically consistent" in text
    for name in res.estimate.names[:3]:
        assert name[:40] in text
    assert len([ln for ln in text.splitlines() if ln.strip().startswith("joint")]) >= 3 * 6


def test_validation_plot_is_a_figure_with_a_row_per_joint(puma_case: Case) -> None:
    from matplotlib.figure import Figure

    q, qd, qdd = puma_case.validation.evaluate(np.linspace(0, 10, 200))
    tau = puma_case.result.predict(q, qd, qdd, consistent=True)
    val = ident.ValidationResult(np.linspace(0, 10, 200), puma_case.result.predict(q, qd, qdd), tau)
    fig = puma_case.result.plot(val)
    assert isinstance(fig, Figure)
    assert len(fig.axes) == 6
    assert fig.axes[0].get_legend() is not None


def test_importing_identification_does_not_import_matplotlib() -> None:
    code = "import sys, armctl.dynamics.identification; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_estimates_carry_standard_deviations(puma_case: Case) -> None:
    est = puma_case.result.estimate
    assert est.weighted
    assert est.std.shape == est.theta.shape == (len(est.names),)
    assert np.all(est.std > 0) and np.all(np.isfinite(est.std))
    np.testing.assert_allclose(est.std, np.sqrt(np.diag(est.covariance)))
    assert est.noise_std.shape == est.residual_rms.shape == (6,)
