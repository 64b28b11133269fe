"""Drawing the dynamic manipulability ellipsoid of a planar arm, at one configuration or along a path
(matplotlib, imported when called)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import real_array, scalar
from armctl.dynamics.operational_space import dynamic_manipulability, task_rows
from armctl.errors import InvalidParameterError, ShapeError

if TYPE_CHECKING:
    from armctl.dynamics.base import Dynamics


def plot_dynamic_manipulability(
    dynamics: Dynamics,
    configurations: ArrayLike,
    frame: str | None = None,
    rows: str | Sequence[int | str] = "xz",
    torque_scale: ArrayLike | str | None = None,
    scale: float | None = None,
    arm: bool = True,
    ax: Any = None,
) -> Any:
    """Draw the ellipse of frame accelerations that unit-norm torques produce
    (:func:`~armctl.dynamics.operational_space.dynamic_manipulability`) at each configuration, centred at the
    frame's position, in the plane of two position rows (``"xz"`` for the built-in planar arms).

    Parameters
    ----------
    dynamics
        The arm's dynamics.
    configurations
        One q (n,) or a path (m, n) [rad].
    rows
        The two position rows of the plane, e.g. ``"xz"`` or ``("x", "y")``.
    torque_scale
        As :func:`~armctl.dynamics.operational_space.dynamic_manipulability` (None: unit-norm torques).
    scale
        Length drawn per unit of acceleration [m per m/s²]; None: the longest semi-axis over the path is drawn as
        a fifth of the frame's largest distance from the base.
    arm
        Also draw the links (through the joint frames' origins) at each configuration.
    ax
        A matplotlib Axes to draw in (None: a new figure).

    Returns
    -------
    The matplotlib Axes.
    """
    import matplotlib.pyplot as plt
    from matplotlib.patches import Ellipse

    rws = task_rows(rows)
    if len(rws) != 2 or max(rws) > 2:
        raise InvalidParameterError(
            f"rows must name two position rows of the plane (e.g. 'xz'), got {rows!r}", value=rows
        )
    qs = real_array(configurations, "configurations")
    if qs.ndim == 1:
        qs = qs[None, :]
    if qs.ndim != 2 or qs.shape[1] != dynamics.n:
        raise ShapeError(
            f"configurations must have shape ({dynamics.n},) or (m, {dynamics.n}), got {qs.shape}", value=qs
        )
    ellipses = [dynamic_manipulability(dynamics, q, frame, rws, torque_scale) for q in qs]
    centres = np.array([e.center[list(rws)] for e in ellipses])
    if scale is None:
        longest = max(float(e.lengths[0]) for e in ellipses)
        reach = float(np.linalg.norm(centres, axis=1).max()) or 1.0
        scale = 0.2 * reach / longest if longest > 0 else 1.0
    else:
        scale = scalar(scale, "scale", positive=True)
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 5))
    if arm:
        frames = ["world", *dynamics.model.joint_names, dynamics.model.frame(frame).name]
        for q in qs:
            pts = np.array([dynamics.frame_pose(q, f)[:3, 3][list(rws)] for f in frames])
            ax.plot(pts[:, 0], pts[:, 1], "-o", color="0.6", lw=1.5, ms=3, zorder=1)
    for e, c in zip(ellipses, centres, strict=True):
        a, b = (float(v) * scale for v in e.lengths)
        angle = float(np.degrees(np.arctan2(e.axes[1, 0], e.axes[0, 0])))
        ax.add_patch(Ellipse(tuple(c), 2 * a, 2 * b, angle=angle, fill=False, color="#1d3557", lw=1.2, zorder=2))
    ax.plot(centres[:, 0], centres[:, 1], ".", color="#d62828", zorder=3)
    names = ["x", "y", "z"]
    ax.set(
        aspect="equal",
        xlabel=f"{names[rws[0]]} [m]",
        ylabel=f"{names[rws[1]]} [m]",
        title=f"dynamic manipulability of {ellipses[0].frame!r} ({scale:.3g} m per m/s²)",
    )
    ax.autoscale_view()
    return ax
