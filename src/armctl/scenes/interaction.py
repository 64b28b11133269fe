"""`InteractionScene`: a scene in which the arm touches a table and the controllers feel it — the plant, a
table (a compliant :class:`~armctl.sim.Plane`), a force/torque sensor at the tool in world axes, and the
interaction controllers (:mod:`armctl.controllers.interaction`) built from presets.

Its result shows the force trace — ``res.sensor[:, 0, :]``, the wrench the arm exerts [N; N·m] (world axes),
the normal force :func:`normal_force` — and the motion (the tool's path, :meth:`InteractionScene.tool_path`).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from armctl.controllers import Admittance, CartesianImpedance, ForceControl, ParallelForcePosition
from armctl.controllers.base import Controller
from armctl.scenes.base import SENSOR, Scene


def normal_force(res: Any, normal: Any = (0.0, 0.0, 1.0)) -> Any:
    """The normal force the arm exerts on the table at each sample [N] (positive pressing): −nᵀ f, f the
    sensor's force (world axes), n the table's outward normal.

    Parameters
    ----------
    res : SimResult
        A run of an interaction scene.
    normal : array_like, shape (3,), optional
        n (default +z).

    Returns
    -------
    ndarray, shape (N,)
    """
    if not res.sensor.size:
        return np.zeros(len(res.t))
    return -(res.sensor[:, SENSOR, :3] @ np.asarray(normal, dtype=float))


class InteractionScene(Scene):
    """A scene of the interaction controllers (see the module), each of which presses f_d = :attr:`force` on the
    table along its believed normal (z) while its target follows the scene's :meth:`path`:

    * ``cartesian_impedance``, ``admittance``: the target δ_c = f_d (k_e + k_z)/(k_e k_z) below the believed
      surface (:func:`impedance_depth`, k_e = :attr:`table_stiffness`), so that the force would be f_d were the
      surface where it is believed;
    * ``force_control``: :class:`~armctl.controllers.ForceControl` along z with PI action, position along x and y;
    * ``parallel_force_position``: the same force and position targets on all three axes.

    A subclass implements :meth:`path` and :meth:`measures` (the force and motion measures that replace the joint
    tracking error of :meth:`~armctl.scenes.base.Scene.metrics`: the reference here is a posture) and lists the
    methods it runs; its parameters are :class:`~armctl.scenes.base.Scene`'s.
    """

    gain_keys: ClassVar[dict[str, tuple[tuple[str, ...], tuple[str, ...]]]] = {
        "cartesian_impedance": (("stiffness",), ("damping", "nullspace_stiffness")),
        "admittance": (("stiffness",), ("damping", "inertia", "kp", "kd")),
        "force_control": (("force_gain", "integral_gain"), ("kp", "kd")),
        "parallel_force_position": (("force_gain", "integral_gain"), ("kp", "kd")),
    }
    #: the desired normal force [N]
    force: float = 10.0
    #: the table's outward normal (world axes)
    normal: Any = (0.0, 0.0, 1.0)
    #: the table's nominal stiffness k_e [N/m], by which the impedances place their targets
    table_stiffness: float = 3e4
    timing_samples = 100
    replay_reads = ("wrench", "tau_applied")

    def path(self, depth: float) -> Any:  # pragma: no cover - abstract
        """The target of a method whose target sits ``depth`` below the believed surface.

        Parameters
        ----------
        depth : float
            [m].

        Returns
        -------
        callable
            t → (pose (4×4), twist (6,), acceleration (6,)).
        """
        raise NotImplementedError

    def measures(self, res: Any, fn: Any) -> dict[str, Any]:  # pragma: no cover - abstract
        """The scene's own measures of a run.

        Parameters
        ----------
        res : SimResult
            A run of this scene.
        fn : ndarray, shape (N,)
            The normal force [N] at each sample (:func:`normal_force`).

        Returns
        -------
        dict of str
        """
        raise NotImplementedError

    def build(self, method: str, gains: dict[str, Any]) -> Controller:
        """The controller of ``method`` (see the class) with checked ``gains``, its target on :meth:`path`.

        Parameters
        ----------
        method : str
            One of :attr:`methods`.
        gains : dict
            Its gains.

        Returns
        -------
        Controller
        """
        dyn = self.dynamics("exact")
        c: Any
        if method in ("cartesian_impedance", "admittance"):
            k, depth = impedance_depth(gains, self.force, self.table_stiffness)
            if method == "cartesian_impedance":
                c = CartesianImpedance(
                    dyn, k, gains.get("damping"), nullspace_stiffness=gains.get("nullspace_stiffness", 5.0)
                )
            else:
                c = Admittance(
                    dyn,
                    k,
                    gains.get("damping"),
                    inertia=gains.get("inertia"),
                    kp=gains.get("kp", 900.0),
                    kd=gains.get("kd"),
                )
            c.set_trajectory(self.path(depth))
            return c
        args, options = pressing_args(dyn, self.force, gains)
        if method == "force_control":
            c = ForceControl(*args, directions=[0.0, 0.0, 1.0], **options)
        else:
            c = ParallelForcePosition(*args, **options)
        c.set_trajectory(self.path(0.0))
        return c

    def tool_path(self, res: Any) -> Any:
        """The tool's position at each sample [m] (N, 3), world axes.

        Parameters
        ----------
        res : SimResult
            A run of this scene.

        Returns
        -------
        ndarray, shape (N, 3)
        """
        dyn = self.dynamics("plant")
        return np.array([dyn.frame_pose(q)[:3, 3] for q in res.q]).reshape(-1, 3)

    def scene_measures(self, res: Any, method: str, gains: dict[str, Any] | None = None) -> dict[str, Any]:
        return self.measures(res, normal_force(res, self.normal))


def pressing_args(dyn: Any, force: float, gains: dict[str, Any]) -> tuple[tuple[Any, ...], dict[str, Any]]:
    """The arguments of a force law (:class:`~armctl.controllers.ForceControl`,
    :class:`~armctl.controllers.ParallelForcePosition`) pressing f_d = ``force`` [N] down (−z, world axes) with
    ``gains``' force and integral gains, and position gains ``kp`` (default 400) and ``kd``: (positional,
    keyword)."""
    options = {"kp": gains.get("kp", 400.0), "kd": gains.get("kd")}
    return (dyn, [0.0, 0.0, -force], gains["force_gain"], gains["integral_gain"]), options


def impedance_depth(gains: dict[str, Any], force: float, table_stiffness: float) -> tuple[Any, float]:
    """The stiffness K of an impedance's ``gains`` and the depth δ_c = f_d (k_e + k_z)/(k_e k_z) [m] below a
    table of stiffness k_e [N/m] at which its target makes the force f_d [N] at rest, k_z [N/m] K's vertical entry
    (K a (3,) diagonal or a 3×3 matrix)."""
    k = np.asarray(gains["stiffness"], dtype=float)
    kz = float(np.diag(k)[2]) if k.ndim == 2 else float(k[2])
    return k, force * (table_stiffness + kz) / (table_stiffness * kz)
