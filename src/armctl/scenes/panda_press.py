"""``panda_press``: the Panda presses 10 N on a table whose height it knows only to within a centimetre —
Cartesian impedance and admittance, whose force follows from where they believe the surface is, against
parallel force/position control, whose integral action finds the force wherever the surface is."""

from __future__ import annotations

from typing import Any

import numpy as np

from armctl import models
from armctl._checks import scalar
from armctl.dynamics.base import Dynamics
from armctl.scenes.base import holding_scene, quintic
from armctl.scenes.interaction import InteractionScene
from armctl.scenes.panda_contact import Q_HOME

#: the table's stiffness [N/m] and damping [N·s/m]
TABLE_STIFFNESS, TABLE_DAMPING = 3e4, 150.0


class PressScene(InteractionScene):
    """The press scene (built by :func:`panda_press`): the tool starts 2 cm above the table the controllers
    believe in (``z_believed``); the true table is at ``z_table``. Each method moves its target (:meth:`path`) down
    from the start in 1 s (from t = 0.2 s), to its depth below the believed surface, and presses.

    * ``cartesian_impedance``, ``admittance``: the target sits δ_c = f_d (k_e + k_d)/(k_e k_d) below the believed
      surface, so that the force would be f_d were the surface where it is believed (k_e the table's nominal
      stiffness, k_d the vertical stiffness); the force is k_e k_d/(k_e + k_d) (δ_c − Δz) instead, Δz how much
      lower the table is (see :class:`~armctl.scenes.interaction.InteractionScene`).
    * ``parallel_force_position``: the position target is the believed surface, f_d = 10 N down: the integral
      action reaches f_d at rest wherever the table is.

    Its :meth:`measures`: the force at rest (``force_at_rest``, the mean of the last 0.2 s) [N], its error against
    f_d (``force_error``), the RMS force error after 1.5 s (``rms_error``; ``max_error`` its largest), whether
    contact was lost after first touch (``contact_lost``), and the tool's final depth in the table [m]
    (``depth``). Its parameters are :class:`~armctl.scenes.base.Scene`'s.
    """

    table_stiffness = TABLE_STIFFNESS
    z_table: float = 0.0
    z_believed: float = 0.0

    def start_pose(self) -> Any:
        """The tool's pose at the start.

        Returns
        -------
        ndarray, shape (4, 4)
        """
        return Dynamics(self.exact).frame_pose(Q_HOME)

    def path(self, depth: float) -> Any:
        start = self.start_pose()
        move = quintic(start[:3, 3], [start[0, 3], start[1, 3], self.z_believed - depth], 0.2, 1.0)

        def at(t: float) -> tuple[Any, Any, Any]:
            p, v, a = move(t)
            pose = start.copy()
            pose[:3, 3] = p
            return pose, np.concatenate((v, np.zeros(3))), np.concatenate((a, np.zeros(3)))

        return at

    def measures(self, res: Any, fn: Any) -> dict[str, Any]:
        if not len(res.t):
            nan = float("nan")
            return {"force_at_rest": nan, "force_error": nan, "rms_error": nan, "max_error": nan, "error_unit": "N"}
        late = res.t >= res.t[-1] - 0.2
        settled = res.t >= 1.5
        touch = np.flatnonzero(fn > 0)
        err = fn[settled] - self.force if settled.any() else np.array([np.nan])
        z_end = float(self.tool_path(res)[-1, 2])
        return {
            "force_at_rest": float(fn[late].mean()),
            "force_error": float(fn[late].mean() - self.force),
            "rms_error": float(np.sqrt(np.mean(err**2))),
            "max_error": float(np.abs(err).max()),
            "contact_lost": bool(touch.size and (fn[touch[0] + 1 :] <= 0).any()),
            "depth": self.z_table - z_end,
            "error_unit": "N",
        }


def panda_press(offset: float = 0.01) -> PressScene:
    """The Panda pressing 10 N on a table (a Kelvin–Voigt plane of 3·10⁴ N/m) ``offset`` lower than its
    controllers believe, from its ready pose: the methods ``cartesian_impedance``, ``admittance`` and
    ``parallel_force_position`` (see :class:`PressScene`); a force/torque sensor at the tool reads in world axes.

    Parameters
    ----------
    offset : float, optional
        Δz [m]: how much lower the table is than believed (negative: higher).

    Returns
    -------
    PressScene
    """
    from armctl.sim import ForceSensor, KelvinVoigt, Plane

    offset = scalar(offset, "offset")
    model = models.panda()
    z_believed = float(Dynamics(model).frame_pose(Q_HOME)[2, 3]) - 0.02
    z_table = z_believed - offset
    plane = Plane(KelvinVoigt(TABLE_STIFFNESS, TABLE_DAMPING), point=(0.0, 0.0, z_table))
    sc = holding_scene(
        PressScene,
        "panda_press",
        f"Panda pressing 10 N on a table {offset * 100:g} cm lower than believed",
        model,
        Q_HOME,
        duration=3.0,
        dt=5e-4,
        methods=("cartesian_impedance", "admittance", "parallel_force_position"),
        sim_options={"environment": plane, "sensors": ForceSensor(world_axes=True)},
    )
    sc.z_table, sc.z_believed = z_table, z_believed
    return sc
