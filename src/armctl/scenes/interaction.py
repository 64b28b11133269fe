"""`InteractionScene`: a scene in which the arm touches a table and the controllers feel it — the plant, a
table (a compliant :class:`~armctl.sim.Plane`), a force/torque sensor at the tool in world axes, and the
interaction controllers (:mod:`armctl.controllers.interaction`) built from presets.

Its result shows the force trace — ``res.sensor[:, 0, :]``, the wrench the arm exerts [N; N·m] (world axes),
the normal force :func:`normal_force` — and the motion (the tool's path, :meth:`InteractionScene.tool_path`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np

from armctl.scenes.base import SENSOR, Scene, diverged_errors


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
    """A scene of the interaction controllers (see the module); a subclass sets :attr:`gain_keys` (method →
    (required, optional) gain names), implements :meth:`build` and :meth:`measures`. Its parameters are
    :class:`~armctl.scenes.base.Scene`'s.

    Parameters
    ----------
    name, description, plant, exact, reduced, reference, duration, methods : optional
        As for :class:`~armctl.scenes.base.Scene`.
    control_dt, dt, integrator, q0, sim_options, builders, backend : optional
        As for :class:`~armctl.scenes.base.Scene`.
    """

    gain_keys: ClassVar[dict[str, tuple[tuple[str, ...], tuple[str, ...]]]] = {}
    #: the desired normal force [N]
    force: float = 10.0
    #: the table's outward normal (world axes)
    normal: Any = (0.0, 0.0, 1.0)
    timing_samples = 100
    replay_reads = ("wrench", "tau_applied")

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

    def metrics(
        self,
        res: Any,
        method: str,
        gains: dict[str, Any] | None = None,
        timing_samples: int | None = None,
        timing_rounds: int = 5,
    ) -> dict[str, Any]:
        """The scene's force and motion measures (:meth:`measures`) with :meth:`Scene.metrics`' torque, limit,
        divergence and timing measures (its joint tracking error is replaced: the reference here is a posture).

        Parameters
        ----------
        res : SimResult
            A run of this scene.
        method : str
            The method that ran.
        gains : dict, optional
            Its gains (default: the preset), to rebuild the controller for timing.
        timing_samples : int, optional
            Recorded states replayed to time the controller.
        timing_rounds : int, optional
            Timed passes (0: not timed, NaN).

        Returns
        -------
        dict of str
        """
        out = super().metrics(res, method, gains, timing_samples, timing_rounds)
        out.update(self.measures(res, normal_force(res, self.normal)))
        return diverged_errors(out)


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


def quintic(start: Any, end: Any, t0: float, duration: float) -> Callable[[float], tuple[Any, Any, Any]]:
    """t → (position, velocity, acceleration) of a minimum-jerk move from ``start`` to ``end`` (arrays) between t0
    and t0 + duration [s], held before and after."""
    a, b = np.asarray(start, dtype=float), np.asarray(end, dtype=float)

    def at(t: float) -> tuple[Any, Any, Any]:
        s = min(max((t - t0) / duration, 0.0), 1.0)
        shape = s**3 * (10 - 15 * s + 6 * s * s)
        rate = 30 * s * s * (1 - s) ** 2 / duration
        accel = 60 * s * (1 - s) * (1 - 2 * s) / duration**2
        return a + (b - a) * shape, (b - a) * rate, (b - a) * accel

    return at
