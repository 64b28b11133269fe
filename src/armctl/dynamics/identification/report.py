"""The identification report: a text summary and a validation plot (matplotlib, imported only here, lazily)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from armctl.errors import InvalidParameterError, ShapeError

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from armctl.dynamics.identification.identify import IdentificationResult, ValidationResult


def _joint_table(names: Sequence[str], columns: dict[str, np.ndarray]) -> list[str]:
    head = f"  {'joint':<14}" + "".join(f"{k:>16}" for k in columns)
    rows = [head]
    for i, nm in enumerate(names):
        rows.append(f"  {nm:<14}" + "".join(f"{float(v[i]):>16.4g}" for v in columns.values()))
    return rows


def format_report(result: IdentificationResult, validation: ValidationResult | None = None, max_name: int = 60) -> str:
    """A plain-text report of an identification: the data and their conditioning, each estimated base parameter ±
    its standard deviation (σ and σ/|θ| in %), the residual torque per joint, the physically consistent estimate and,
    if given, the validation errors.

    Parameters
    ----------
    result : IdentificationResult
        What :func:`identify` found.
    validation : ValidationResult, optional
        Validation errors to include.
    max_name : int, optional
        Base parameter names longer than this are cut.

    Returns
    -------
    str
    """
    est, prob = result.estimate, result.problem
    names = result.model.joint_names
    lines = [
        f"Identification of {result.model.name!r} ({prob.n} joints)",
        f"  samples: {prob.samples} ({prob.samples * prob.n} equations), unknowns: {prob.n_unknowns} "
        f"({result.base.n_base} base parameters{f' + {prob.n} Coulomb offsets' if prob.offsets else ''})",
        f"  estimator: {'weighted' if est.weighted else 'ordinary'} least squares; condition number of "
        f"{'Σ^-1/2 W (W weighted by the noise)' if est.weighted else 'W'}: {est.condition_number:.4g}",
        "",
        f"  {'parameter':<{max_name}} {'estimate':>12} {'σ':>11} {'σ/|θ| %':>9}",
    ]
    for nm, th, sd in zip(est.names, est.theta, est.std, strict=True):
        label = nm if len(nm) <= max_name else nm[: max_name - 1] + "…"
        rel = 100.0 * sd / abs(th) if th != 0 else np.inf
        lines.append(f"  {label:<{max_name}} {th:>12.5g} {sd:>11.3g} {rel:>9.3g}")
    lines += ["", "Residual torques [N·m]"]
    lines += _joint_table(names, {"noise σ": est.noise_std, "residual RMS": est.residual_rms})
    if result.consistent is not None:
        c = result.consistent
        lines += [
            "",
            f"Physically consistent estimate: cost ratio {c.cost_ratio:.4g} (1 = as good as least squares),"
            f" {'converged' if c.converged else 'NOT converged'} ({c.message})",
        ]
        masses = c.pi.reshape(prob.n, -1)[:, 0]
        lines += _joint_table(
            names, {"mass [kg]": masses, "residual RMS": c.residual_rms, "Coulomb offset": c.coulomb_offset}
        )
    if validation is not None:
        lines += ["", "Validation"]
        lines += _joint_table(
            names,
            {
                "RMS error": validation.rms_error,
                "RMS torque": validation.rms_torque,
                "relative %": 100.0 * validation.relative_error,
            },
        )
    return "\n".join(lines)


def _joint_names(joint_names: Sequence[str] | None, n: int) -> list[str]:
    """``joint_names`` checked (n strings), or "joint 1" … "joint n" for None."""
    if joint_names is None:
        return [f"joint {i + 1}" for i in range(n)]
    if (
        isinstance(joint_names, str | bytes)
        or not isinstance(joint_names, Sequence)
        or not all(isinstance(x, str) for x in joint_names)
    ):
        raise InvalidParameterError(
            f"joint_names must be a sequence of {n} strings, got {joint_names!r}", value=joint_names
        )
    if len(joint_names) != n:
        raise ShapeError(
            f"joint_names has {len(joint_names)} names for {n} joints: give one per joint", value=joint_names
        )
    return list(joint_names)


def validation_plot(
    validation: ValidationResult,
    joint_names: Sequence[str] | None = None,
    title: str = "Identified model: predicted vs measured torque",
) -> Figure:
    """A figure with one row per joint: measured and predicted torque [N·m] against time [s], and their
    difference (not shown, not saved).

    Parameters
    ----------
    validation : ValidationResult
        The torques.
    joint_names : sequence of str, optional
        One per joint (default "joint 1", …).
    title : str, optional
        The figure's title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    from armctl.dynamics.identification.identify import ValidationResult

    if not isinstance(validation, ValidationResult):
        raise InvalidParameterError(
            f"validation must be a ValidationResult (IdentificationResult.validate), got {type(validation).__name__}",
            value=validation,
        )
    n = validation.measured.shape[1]
    names = _joint_names(joint_names, n)
    fig = Figure(figsize=(9.0, 1.8 * n + 0.8), layout="constrained")
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    rel = validation.relative_error
    for i, ax in enumerate(axes):
        ax.plot(validation.t, validation.measured[:, i], color="0.3", lw=1.2, label="measured")
        ax.plot(validation.t, validation.predicted[:, i], color="C0", lw=1.0, ls="--", label="predicted")
        ax.plot(validation.t, validation.predicted[:, i] - validation.measured[:, i], color="C3", lw=0.8, label="error")
        ax.set_ylabel(f"{names[i]}\nτ [N·m]")
        ax.text(0.99, 0.95, f"RMS error {100 * rel[i]:.2f}%", transform=ax.transAxes, ha="right", va="top", fontsize=8)
    axes[0].legend(loc="upper left", fontsize=8, ncols=3)
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(title)
    return fig
