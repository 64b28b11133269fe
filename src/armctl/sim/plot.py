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
    "error": "rad",
}
#: the quantities drawn over their reference (dashed, in the joint's colour), and the reference's field
_REFERENCE_OF = {"q": "q", "qd": "qd", "qdd": "qdd", "q_measured": "q", "qd_measured": "qd"}
#: the panel titles
_LABELS = {"error": "error q_d − q"}


def _figure(rows: int, height: float = 2.2) -> tuple[Figure, Any]:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(9.5, height * rows), layout="constrained")
    axes = fig.subplots(rows, 1, sharex=True, squeeze=False)[:, 0]
    return fig, axes


def _mark_divergence(res: SimResult, axes: Any) -> None:
    if res.diverged and res.diverged_at is not None:
        for ax in axes:
            ax.axvline(res.diverged_at, color="red", linestyle="--", linewidth=1)


def plot_joints(
    res: SimResult,
    quantities: tuple[str, ...] | str = ("q", "qd", "error", "tau_applied"),
    joints: Any = None,
) -> Figure:
    """One panel per quantity (any per-joint array of the result: "q", "qd", "qdd", "tau", "tau_applied",
    "tau_friction", "tau_ext", "q_measured", "qd_measured", and "error", the tracking error q_d − q; one name
    or a sequence of them), one line per joint (``joints``: 0-based indices 0 … n − 1, default all; negative
    indices are refused), labelled with the plant's joint names. Positions, velocities and accelerations are
    drawn over their reference (dashed, in the joint's colour) when the result holds it. The legend stands to
    the right of the panels, off the curves; a run that diverged is marked by a red dashed line."""
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
    if "error" in quantities and res.reference is None:
        raise InvalidParameterError(
            "the result does not hold its reference (a file saved without one), so it has no error to plot; "
            "leave 'error' out of quantities",
            value=quantities,
        )
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
    names = res.joint_names
    fig, axes = _figure(len(quantities))
    overlaid = False
    for ax, name in zip(axes, quantities, strict=True):
        data = res.error if name == "error" else getattr(res, name)
        ref_name = _REFERENCE_OF.get(name)
        ref = getattr(res.reference, ref_name) if ref_name and res.reference is not None else None
        for c, j in enumerate(idx):
            color = f"C{c % 10}"
            ax.plot(res.t, data[:, j], label=names[j], linewidth=1, color=color)
            if ref is not None:
                ax.plot(res.t, ref[:, j], linewidth=1, linestyle="--", color=color, alpha=0.8)
                overlaid = True
        if name == "error":
            ax.axhline(0.0, color="black", linewidth=0.5)
        ax.set_ylabel(f"{_LABELS.get(name, name)} [{_UNITS[name]}]")
        ax.grid(True, alpha=0.3)
    handles, labels = axes[0].get_legend_handles_labels()
    if overlaid:
        from matplotlib.lines import Line2D

        handles.append(Line2D([], [], color="gray", linestyle="--", linewidth=1))
        labels.append("reference (dashed)")
    fig.legend(handles, labels, loc="outside right upper", fontsize="small")
    title = res.info.get("plant")
    if title:
        fig.suptitle(f"{title}: {res.status}", fontsize="medium")
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
