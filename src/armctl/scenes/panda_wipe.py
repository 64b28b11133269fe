"""``panda_wipe``: the Panda wipes a table — 10 N of normal force while it slides 15 cm along it against surface
friction. The table slopes down by 2° along the path, which the controllers do not know: force control holds
the force, Cartesian impedance's force follows the height it did not expect, and parallel force/position control
reads the surface friction as a force error and lags along the path."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from armctl import models
from armctl._checks import scalar
from armctl.dynamics.base import Dynamics
from armctl.scenes.base import holding_scene, quintic
from armctl.scenes.interaction import InteractionScene
from armctl.scenes.panda_contact import Q_HOME

#: the table's stiffness [N/m], damping [N·s/m] and friction coefficient
TABLE_STIFFNESS, TABLE_DAMPING, TABLE_FRICTION = 3e4, 150.0, 0.3
#: the slide: its length along x [m], start [s] and duration [s]
SLIDE, SLIDE_START, SLIDE_TIME = 0.15, 1.5, 2.0


class WipeScene(InteractionScene):
    """The wipe scene (built by :func:`panda_wipe`): the tool starts 1 cm above the table where the controllers
    believe it is (flat, at ``z_believed``), goes down to it in 0.8 s, presses, then slides ``SLIDE`` along x
    (a minimum-jerk move of ``SLIDE_TIME`` from ``SLIDE_START``).

    * ``force_control``: :class:`~armctl.controllers.ForceControl` along the believed normal (z), with PI action;
      position along x and y.
    * ``parallel_force_position``: the same force and position targets on all three axes.
    * ``cartesian_impedance``: the target δ_c below the believed surface (as in ``panda_press``).

    Its :meth:`measures`, over the slide: the normal force's RMS error [N] (``rms_error``; ``max_error`` its
    largest), its range (``force_min``, ``force_max``), the tool's RMS path error along the table [m]
    (``path_rms_error``, in x and y against the target path), and whether contact was lost (``contact_lost``).
    Its parameters are :class:`~armctl.scenes.base.Scene`'s.
    """

    table_stiffness = TABLE_STIFFNESS
    z_believed: float = 0.0

    def path(self, depth: float) -> Any:
        start = Dynamics(self.exact).frame_pose(Q_HOME)
        x0, y0, z0 = start[:3, 3]
        down = quintic([z0], [self.z_believed - depth], 0.2, 0.8)
        along = quintic([x0], [x0 + SLIDE], SLIDE_START, SLIDE_TIME)

        def at(t: float) -> tuple[Any, Any, Any]:
            (z, vz, az), (x, vx, ax) = down(t), along(t)
            pose = start.copy()
            pose[:3, 3] = [x[0], y0, z[0]]
            return pose, np.array([vx[0], 0, vz[0], 0, 0, 0]), np.array([ax[0], 0, az[0], 0, 0, 0])

        return at

    def measures(self, res: Any, fn: Any) -> dict[str, Any]:
        sliding = (res.t >= SLIDE_START) & (res.t <= SLIDE_START + SLIDE_TIME)
        if not sliding.any():
            nan = float("nan")
            return {"rms_error": nan, "max_error": nan, "path_rms_error": nan, "error_unit": "N"}
        err = fn[sliding] - self.force
        path = self.path(0.0)
        want = np.array([path(float(t))[0][:2, 3] for t in res.t[sliding]])
        xy = self.tool_path(res)[sliding, :2]
        return {
            "rms_error": float(np.sqrt(np.mean(err**2))),
            "max_error": float(np.abs(err).max()),
            "force_min": float(fn[sliding].min()),
            "force_max": float(fn[sliding].max()),
            "path_rms_error": float(np.sqrt(np.mean(np.sum((xy - want) ** 2, axis=1)))),
            "contact_lost": bool((fn[sliding] <= 0).any()),
            "error_unit": "N",
        }


def panda_wipe(slope: float = 2.0) -> WipeScene:
    """The Panda pressing 10 N on a table with surface friction μ = 0.3 (a Kelvin–Voigt plane of 3·10⁴ N/m) and
    sliding 15 cm along x; the table slopes down by ``slope`` degrees along x, unknown to the controllers. The
    methods ``force_control``, ``parallel_force_position`` and ``cartesian_impedance`` (:class:`WipeScene`),
    integrated at 0.2 ms (the table's friction is stiff below its slip velocity); a force/torque sensor at the
    tool reads in world axes.

    Parameters
    ----------
    slope : float, optional
        θ [deg]: the table descends by tan θ per metre along +x.

    Returns
    -------
    WipeScene
    """
    from armctl.sim import ForceSensor, KelvinVoigt, Plane

    theta = math.radians(scalar(slope, "slope"))
    model = models.panda()
    tool = Dynamics(model).frame_pose(Q_HOME)[:3, 3]
    z_believed = float(tool[2]) - 0.01
    normal = (math.sin(theta), 0.0, math.cos(theta))
    plane = Plane(
        KelvinVoigt(TABLE_STIFFNESS, TABLE_DAMPING),
        normal=normal,
        point=(tool[0], tool[1], z_believed),
        friction=TABLE_FRICTION,
    )
    sc = holding_scene(
        WipeScene,
        "panda_wipe",
        f"Panda wiping a table at 10 N over 15 cm against friction μ = 0.3; the table slopes {slope:g}° unknown",
        model,
        Q_HOME,
        duration=4.0,
        dt=2e-4,
        methods=("force_control", "parallel_force_position", "cartesian_impedance"),
        sim_options={"environment": plane, "sensors": ForceSensor(world_axes=True)},
    )
    sc.z_believed = z_believed
    sc.normal = normal
    return sc
