"""Plots of a run: a :class:`~armctl.sim.SimResult`, read through :class:`~armctl.sim.run_record.RunRecord`.
Each helper returns a ``matplotlib.figure.Figure`` (made without pyplot, so no GUI state is touched); matplotlib
is imported only when a plot is asked for."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from armctl._checks import whole_number
from armctl.errors import InvalidParameterError, UnknownNameError

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from armctl.sim.run_record import RunRecord

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
#: the quantities that are not per joint: contact forces, wrenches and task errors, with their units and labels
_OTHER_UNITS = {
    "contact_force": "N",
    "contact_force_on_robot": "N",
    "contact_force_on_environment": "N",
    "wrench": "N, N·m",
    "sensor": "N, N·m",
    "position_error": "m",
    "orientation_error": "rad",
}
#: every quantity a plot can draw, in the order of the error messages
QUANTITIES = (*_UNITS, *_OTHER_UNITS)
_OTHER_LABELS = {
    "contact_force": "contact force on the robot",
    "contact_force_on_robot": "contact force on the robot",
    "contact_force_on_environment": "contact force on the environment",
    "wrench": "wrench the arm exerts",
    "sensor": "force sensor reading",
    "position_error": "task position error",
    "orientation_error": "task orientation error",
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


def _mark_divergence(res: RunRecord, axes: Any) -> None:
    if res.diverged and res.diverged_at is not None:
        for ax in axes:
            ax.axvline(res.diverged_at, color="red", linestyle="--", linewidth=1)


def plot_joints(
    res: RunRecord,
    quantities: tuple[str, ...] | str = ("q", "qd", "error", "tau_applied"),
    joints: Any = None,
) -> Figure:
    """One panel per quantity (one name or a sequence of them), a run that diverged marked by a red dashed line.

    Per-joint quantities — any per-joint array of the result: "q", "qd", "qdd", "tau", "tau_applied",
    "tau_friction", "tau_ext", "q_measured", "qd_measured", and "error", the tracking error q_d − q — draw one
    line per joint (``joints``: 0-based indices 0 … n − 1, default all; negative indices are refused), labelled
    with the plant's joint names in a legend to the right of the panels. Positions, velocities and
    accelerations are drawn over their reference (dashed, in the joint's colour) when the result holds it.

    The other quantities (see :func:`plot_other`), each with a legend of its own: "contact_force" (the force on
    the robot, ``res.contact_force_on_robot``: +f_n along the surface normal when pressing),
    "contact_force_on_robot" (the same), "contact_force_on_environment" (its opposite), "wrench" (the wrench the
    arm exerts, ``res.wrench``), "sensor" (each force sensor's reading, ``res.sensor``), "position_error" and
    "orientation_error" (each frame task's error, ``res.task_errors``)."""
    if isinstance(quantities, str):
        quantities = (quantities,)
    quantities = tuple(quantities)
    if not quantities:
        raise InvalidParameterError(
            f"quantities must name at least one of {', '.join(QUANTITIES)}; got ()", value=quantities
        )
    for name in quantities:
        if not isinstance(name, str) or name not in QUANTITIES:
            raise UnknownNameError("quantity", name, QUANTITIES)
        _check_other(res, name)
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
    legend_from = None
    for ax, name in zip(axes, quantities, strict=True):
        if name in _OTHER_UNITS:
            plot_other(res, name, ax)
            continue
        legend_from = ax if legend_from is None else legend_from
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
    if legend_from is not None:
        handles, labels = legend_from.get_legend_handles_labels()
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


def _check_other(res: RunRecord, name: str) -> None:
    """Refuse a quantity the result has nothing of (named, with what to do)."""
    if name in ("position_error", "orientation_error"):
        if not any(k.startswith(f"{name}[") for k in res.task_errors):
            raise InvalidParameterError(
                f"the result has no {name.replace('_', ' ')}: its controller logged no frame task errors (the "
                "operational-space controllers log one per frame task, see armctl.controllers.osc.task_errors); "
                f"leave {name!r} out of quantities",
                value=name,
            )
    elif name == "sensor" and not res.sensor.shape[1]:
        raise InvalidParameterError(
            "the result has no force sensor (simulate(..., sensors=[ForceSensor(...)]) adds one); leave 'sensor' "
            "out of quantities",
            value=name,
        )


def _components(ax: Any, t: Any, data: Any, labels: list[str], prefix: str) -> None:
    for i, c in enumerate(labels):
        ax.plot(t, data[:, i], label=f"{prefix}{c}", linewidth=1, color=f"C{i % 10}" if not prefix else None)


def plot_other(res: RunRecord, name: str, ax: Any) -> None:
    """Draw one quantity that is not per joint on the axes ``ax``, with its legend and label.

    Parameters
    ----------
    res : SimResult or RunRecord
        The run.
    name : str
        ``"contact_force"`` / ``"contact_force_on_robot"`` (F_p, one line per point and axis, world axes [N]),
        ``"contact_force_on_environment"`` (h_p = −F_p), ``"wrench"`` (f_x, f_y, f_z [N], m_x, m_y, m_z [N·m],
        world axes), ``"sensor"`` (each sensor's six components in its own axes, or world axes), or
        ``"position_error"`` / ``"orientation_error"`` (each frame task's error target − actual, world axes [m] /
        [rad]; NaN where a row is free, drawn as a gap).
    ax : matplotlib.axes.Axes
        Where to draw.
    """
    t = res.t
    xyz = ["x", "y", "z"]
    if name in ("contact_force", "contact_force_on_robot", "contact_force_on_environment"):
        forces = res.contact_force_on_environment if name.endswith("environment") else res.contact_force_on_robot
        points = forces.shape[1]
        for p in range(points):
            _components(ax, t, forces[:, p], [f"f{c}" for c in xyz], f"point {p}: " if points > 1 else "")
    elif name == "wrench":
        _components(ax, t, res.wrench, ["fx", "fy", "fz", "mx", "my", "mz"], "")
    elif name == "sensor":
        sensors = res.sensor.shape[1]
        for s in range(sensors):
            labels = ["fx", "fy", "fz", "mx", "my", "mz"]
            _components(ax, t, res.sensor[:, s], labels, f"sensor {s}: " if sensors > 1 else "")
    else:
        for key, e in res.task_errors.items():
            if key.startswith(f"{name}["):
                _components(ax, t, e, xyz, f"{key[len(name) + 1 : -1]} ")
    if ax.lines:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    ax.axhline(0.0, color="black", linewidth=0.5)
    ax.set_ylabel(f"{_OTHER_LABELS[name]} [{_OTHER_UNITS[name]}]", fontsize="small")
    ax.grid(True, alpha=0.3)


def plot_energy(res: RunRecord) -> Figure:
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


def plot_wrench(res: RunRecord) -> Figure:
    """The wrench the arm exerts (force and moment, world axes) and the normal force of each contact
    point."""
    fig, axes = _figure(3)
    for i, c in enumerate("xyz"):
        axes[0].plot(res.t, res.wrench[:, i], label=f"f{c}", linewidth=1)
        axes[1].plot(res.t, res.wrench[:, 3 + i], label=f"m{c}", linewidth=1)
    axes[0].set_ylabel("force [N]")
    axes[1].set_ylabel("moment [N·m]")
    for p in range(res.contact_force_on_environment.shape[1]):
        force = res.contact_force_on_environment[:, p]
        axes[2].plot(res.t, np.linalg.norm(force, axis=1), label=f"point {p}", linewidth=1)
    axes[2].set_ylabel("|contact force| [N]")
    axes[2].set_xlabel("t [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        if ax.lines:
            ax.legend(loc="upper right", fontsize="small")
    _mark_divergence(res, axes)
    return fig
