"""What the readers of a run read: :class:`RunRecord`, the part of a :class:`~armctl.sim.SimResult` that its
plots (:mod:`armctl.sim.plot`), its playback page (:mod:`armctl.sim.playback`) and its tables
(:mod:`armctl.sim.tables`) use.

Those readers are typed against this protocol rather than against :class:`~armctl.sim.SimResult` itself, so that
the result, which offers them as methods (``plot``, ``playback``, ``to_dataframe``, ``to_xarray``), sits above
them and they need nothing of it. A :class:`~armctl.sim.SimResult` is a RunRecord; so is any object with these
read-only members.

Arrays have one row per sample (N samples, n joints, P contact points, S force sensors); the units and sign
conventions are those of :class:`~armctl.sim.SimResult`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol

from armctl._checks import FloatArray
from armctl.sim.sampled_reference import SampledReference

if TYPE_CHECKING:
    from armctl.model.robot import RobotModel


class RunRecord(Protocol):
    """The members of a recorded run that its plots, playback and tables read (see the module).

    Attributes
    ----------
    t : ndarray, shape (N,)
        Sample times [s].
    q, qd, qdd : ndarray, shape (N, n)
        Joint positions, velocities, accelerations [rad, rad/s, rad/s² or m, m/s, m/s²].
    tau, tau_applied, tau_friction, tau_ext : ndarray, shape (N, n)
        Commanded, applied (after saturation), friction and external joint torques [N·m or N].
    q_measured, qd_measured : ndarray, shape (N, n)
        The measurements the controller was given.
    wrench : ndarray, shape (N, 6)
        The wrench the arm exerts, [force; moment] in world axes [N, N·m].
    contact_force_on_environment, contact_force_on_robot : ndarray, shape (N, P, 3)
        h_p, the force each contact point exerts, and its opposite F_p = −h_p [N], world axes.
    contact_position : ndarray, shape (N, P, 3), or None
        Where each contact point was [m, world axes].
    sensor : ndarray, shape (N, S, 6)
        Force-sensor readings.
    work_actuator, work_friction, work_external : ndarray, shape (N,)
        Work since t = 0 [J].
    energy : ndarray, shape (N,)
        E = T + U [J].
    error : ndarray, shape (N, n)
        Tracking error reference.q − q (raises where the run holds no reference).
    task_errors : dict of str to ndarray
        Each frame task's position and orientation error, (N, 3) [m or rad].
    reference : SampledReference or None
        The reference at the samples.
    plant : RobotModel or None
        The simulated arm.
    n : int
        Number of joints.
    duration : float
        Simulated time covered [s].
    joint_names : tuple of str
        The joints' names.
    status : str
        ``"ok"``, ``"saturated"``, ``"over limits"``, ``"diverged"`` or ``"failed"``.
    diverged : bool
        The run stopped early.
    diverged_at : float or None
        When [s].
    divergence : str
        Why.
    info : dict
        Settings and counters.
    """

    @property
    def t(self) -> FloatArray: ...
    @property
    def q(self) -> FloatArray: ...
    @property
    def qd(self) -> FloatArray: ...
    @property
    def qdd(self) -> FloatArray: ...
    @property
    def tau(self) -> FloatArray: ...
    @property
    def tau_applied(self) -> FloatArray: ...
    @property
    def tau_friction(self) -> FloatArray: ...
    @property
    def tau_ext(self) -> FloatArray: ...
    @property
    def q_measured(self) -> FloatArray: ...
    @property
    def qd_measured(self) -> FloatArray: ...
    @property
    def wrench(self) -> FloatArray: ...
    @property
    def contact_force_on_environment(self) -> FloatArray: ...
    @property
    def contact_force_on_robot(self) -> FloatArray: ...
    @property
    def contact_position(self) -> FloatArray | None: ...
    @property
    def sensor(self) -> FloatArray: ...
    @property
    def work_actuator(self) -> FloatArray: ...
    @property
    def work_friction(self) -> FloatArray: ...
    @property
    def work_external(self) -> FloatArray: ...
    @property
    def energy(self) -> FloatArray: ...
    @property
    def error(self) -> FloatArray: ...
    @property
    def task_errors(self) -> dict[str, FloatArray]: ...
    @property
    def reference(self) -> SampledReference | None: ...
    @property
    def plant(self) -> RobotModel | None: ...
    @property
    def n(self) -> int: ...
    @property
    def duration(self) -> float: ...
    @property
    def joint_names(self) -> tuple[str, ...]: ...
    @property
    def status(self) -> str: ...
    @property
    def diverged(self) -> bool: ...
    @property
    def diverged_at(self) -> float | None: ...
    @property
    def divergence(self) -> str: ...
    @property
    def info(self) -> dict[str, Any]: ...

    def energy_balance(self) -> FloatArray:
        """E(t) − E(0) − W(t) [J].

        Returns
        -------
        ndarray, shape (N,)
            [J].
        """
        ...
