"""Plots of a :class:`~armctl.sim.result.SimResult`. Each helper returns a ``matplotlib.figure.Figure``
(made without pyplot, so no GUI state is touched); matplotlib is imported only when a plot is asked for."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from armctl._checks import whole_number
from armctl.errors import InvalidParameterError, UnknownNameError

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from armctl.sim.result import SimResult

_UNITS = {
    "q": "rad",
    "qd": "rad/s",
    "qdd": "rad/s²",
    "tau": "N·m",
    "tau_applied": "N·m",
    "tau_friction": "N·m",
    "tau_ext": "N·m",
    "q_measured": "rad",
    "qd_measured": "rad/s",
}


def _figure(rows: int, height: float = 2.2) -> tuple[Figure, Any]:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8, height * rows), layout="constrained")
    axes = fig.subplots(rows, 1, sharex=True, squeeze=False)[:, 0]
    return fig, axes


def _mark_divergence(res: SimResult, axes: Any) -> None:
    if res.diverged and res.diverged_at is not None:
        for ax in axes:
            ax.axvline(res.diverged_at, color="red", linestyle="--", linewidth=1)


def plot_joints(
    res: SimResult, quantities: tuple[str, ...] | str = ("q", "qd", "tau_applied"), joints: Any = None
) -> Figure:
    """One panel per quantity (any per-joint array of the result: "q", "qd", "qdd", "tau", "tau_applied",
    "tau_friction", "tau_ext", "q_measured", "qd_measured"; one name or a sequence of them), one line per joint
    (``joints``: 0-based indices 0 … n − 1, default all; negative indices are refused; lines are labelled
    "joint j + 1")."""
    if isinstance(quantities, str):
        quantities = (quantities,)
    quantities = tuple(quantities)
    if not quantities:
        raise InvalidParameterError(
            f"quantities must name at least one of {', '.join(_UNITS)}; got ()", value=quantities
        )
    for name in quantities:
        if not isinstance(name, str) or name not in _UNITS:
            raise UnknownNameError("quantity", name, tuple(_UNITS))
    if joints is None:
        idx = list(range(res.n))
    else:
        given = np.atleast_1d(np.asarray(joints, dtype=object))
        idx = [whole_number(j, f"joints[{i}] (a joint index 0 … {res.n - 1})", 0) for i, j in enumerate(given)]
        if not idx:
            raise InvalidParameterError(
                f"joints must list at least one joint index in 0 … {res.n - 1}, got {joints!r}", value=joints
            )
        for j in idx:
            if j >= res.n:
                raise InvalidParameterError(
                    f"joint index {j} is out of range: the result has {res.n} joints, indices 0 … {res.n - 1}",
                    value=joints,
                )
    fig, axes = _figure(len(quantities))
    for ax, name in zip(axes, quantities, strict=True):
        data = getattr(res, name)
        for j in idx:
            ax.plot(res.t, data[:, j], label=f"joint {j + 1}", linewidth=1)
        ax.set_ylabel(f"{name} [{_UNITS[name]}]")
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc="upper right", fontsize="small", ncol=min(len(idx), 4))
    axes[-1].set_xlabel("t [s]")
    _mark_divergence(res, axes)
    return fig


def plot_energy(res: SimResult) -> Figure:
    """Energy E − E(0) against the work of actuators, friction and external wrenches, and the balance
    residual E − E(0) − W. Raises an InvalidParameterError for a result without samples."""
    if not len(res.t):
        raise InvalidParameterError(
            "the result has no samples (the run stopped before its first one): there is "
            "no energy to plot; check res.divergence",
            value=res,
        )
    fig, axes = _figure(2, 2.8)
    ax = axes[0]
    ax.plot(res.t, res.energy - res.energy[0], label="E − E(0)", linewidth=1.5)
    ax.plot(res.t, res.work_actuator, label="W actuators", linewidth=1)
    ax.plot(res.t, res.work_friction, label="W friction", linewidth=1)
    ax.plot(res.t, res.work_external, label="W external", linewidth=1)
    ax.set_ylabel("[J]")
    ax.legend(loc="best", fontsize="small")
    ax.grid(True, alpha=0.3)
    axes[1].plot(res.t, res.energy_balance(), color="black", linewidth=1)
    axes[1].set_ylabel("E − E(0) − W [J]")
    axes[1].set_xlabel("t [s]")
    axes[1].grid(True, alpha=0.3)
    _mark_divergence(res, axes)
    return fig


def plot_wrench(res: SimResult) -> Figure:
    """The wrench the arm exerts (force and moment, world axes) and the normal force of each contact
    point."""
    fig, axes = _figure(3)
    for i, c in enumerate("xyz"):
        axes[0].plot(res.t, res.wrench[:, i], label=f"f{c}", linewidth=1)
        axes[1].plot(res.t, res.wrench[:, 3 + i], label=f"m{c}", linewidth=1)
    axes[0].set_ylabel("force [N]")
    axes[1].set_ylabel("moment [N·m]")
    for p in range(res.contact_force.shape[1]):
        axes[2].plot(res.t, np.linalg.norm(res.contact_force[:, p], axis=1), label=f"point {p}", linewidth=1)
    axes[2].set_ylabel("|contact force| [N]")
    axes[2].set_xlabel("t [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        if ax.lines:
            ax.legend(loc="upper right", fontsize="small")
    _mark_divergence(res, axes)
    return fig
