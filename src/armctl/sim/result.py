"""`SimResult`: what a closed-loop simulation recorded, sampled at every control instant t_k = k·control_dt.

Arrays have one row per sample (N + 1 rows for N control periods; fewer if the run diverged) and are
read-only. Torques are in N·m (N for prismatic joints), the sign conventions those of

    M q̈ + C q̇ + g = tau_applied − tau_friction − tau_ext,     tau_ext = Σ J_pᵀ h_p + J_toolᵀ h_d

Energies in J. ``save``/``load`` use NumPy's npz format (no pickle).

Contact forces come in two named senses: :attr:`SimResult.contact_force_on_robot` (F_p, what the environment
exerts on the arm: pressing on a floor gives a force along the floor's normal, up; the sense of
:class:`armctl.controllers.osc.Contact` and :class:`~armctl.controllers.osc.ContactForceTask`) and
:attr:`SimResult.contact_force_on_environment` (h_p = −F_p, what the arm exerts, the sense of
:attr:`SimResult.wrench` and of the force sensors, :attr:`SimResult.sensor`). ``contact_force`` is a deprecated
alias of ``contact_force_on_environment``.
"""

from __future__ import annotations

import inspect
import json
import warnings
import zipfile
from collections.abc import Callable
from dataclasses import InitVar, dataclass, field, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from armctl._checks import FloatArray
from armctl.errors import InvalidParameterError
from armctl.sim.limits import LimitReport
from armctl.sim.playback import playback as _playback
from armctl.sim.plot import plot_energy, plot_joints, plot_wrench
from armctl.sim.sampled_reference import SampledReference
from armctl.sim.tables import sim_dataframe, sim_xarray
from armctl.sim.tracking import TRACKING_TOLERANCE, ErrorSummary, joint_summary, task_errors, task_summaries

if TYPE_CHECKING:
    from armctl.model.robot import RobotModel

_ARRAYS = (
    "t",
    "q",
    "qd",
    "qdd",
    "tau",
    "tau_applied",
    "tau_friction",
    "tau_ext",
    "wrench",
    "contact_force_on_environment",
    "sensor",
    "q_measured",
    "qd_measured",
    "stuck",
    "work_actuator",
    "work_friction",
    "work_external",
)
#: entries of a saved result named otherwise than the field (the file format keeps its names)
_FILE_KEYS = {"contact_force_on_environment": "contact_force"}


@dataclass(frozen=True, eq=False)
class SimResult:
    """The record of one run of :func:`armctl.simulate`: N samples, one per control period, of an arm of n
    joints. Arrays are read-only.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Sample times [s].
    q, qd, qdd : ndarray, shape (N, n)
        The plant's true state and acceleration [rad, rad/s, rad/s² or m, m/s, m/s²].
    tau : ndarray, shape (N, n)
        The controller's command [N·m or N].
    tau_applied : ndarray, shape (N, n)
        The command after saturation, held over [t_k, t_k+1).
    tau_friction : ndarray, shape (N, n)
        Joint friction torque (for stuck joints the holding torque).
    tau_ext : ndarray, shape (N, n)
        Joint torque of contact and disturbance wrenches.
    wrench : ndarray, shape (N, 6)
        The total wrench h_e the arm exerts on its surroundings (contacts and disturbance), [f; moment about the
        tool-frame origin] in world axes [N, N·m].
    contact_force_on_environment : ndarray, shape (N, P, 3)
        h_p: the force each contact point exerts on its environment [N], world axes (pressing on a floor: down).
        The sense of :attr:`wrench` and :attr:`sensor`; :attr:`contact_force_on_robot` is its opposite.
    sensor : ndarray, shape (N, S, 6)
        Force-sensor readings: the wrench the arm exerts beyond each sensor (see
        :class:`~armctl.sim.ForceSensor`), in the sense of :attr:`contact_force_on_environment`.
    q_measured, qd_measured : ndarray, shape (N, n)
        The measurements taken at each sample, noise included (with a delay of d periods the controller at sample
        k was given row max(k − d, 0)).
    stuck : ndarray, shape (N, n)
        Joints held by stiction.
    work_actuator, work_friction, work_external : ndarray, shape (N,)
        Work done since t = 0 [J] by the applied torque, by friction (≤ 0) and by the external wrenches, so that
        energy − energy[0] ≈ work_actuator + work_friction + work_external (see :meth:`energy_balance`).
    diverged : bool
        The run stopped early.
    diverged_at : float or None
        The time [s] the divergence was detected.
    divergence : str
        Why.
    diverged_q, diverged_qd : ndarray or None
        The offending state.
    logs : dict of str to ndarray
        The controller's ``last_log`` entries stacked over the samples (numbers and arrays only: a key whose
        entries are None, dicts or of varying shape is left out with a
        :class:`~armctl.errors.SimulationWarning` naming it).
    info : dict
        Settings and counters (integrator, steps, sub-steps, stick events, wall time, …); ``unstable_contacts``:
        the contact points the integrator cannot integrate stably at this step (see :mod:`armctl.sim.stability`).
    reference : SampledReference or None
        The reference the controller was given at every sample (``reference.q``, ``.qd``, ``.qdd`` over t), with
        :attr:`error` = reference.q − q.
    limits : LimitReport or None
        How close each joint came to the plant's torque, velocity and position limits, summed up by
        :attr:`status`.
    contact_position : ndarray, shape (N, P, 3)
        Where each contact point was [m, world axes].
    plant : RobotModel or None
        The true arm (its joint names label the plots, its geometry the :meth:`playback`; not saved by
        :meth:`save`).
    """

    t: FloatArray
    q: FloatArray
    qd: FloatArray
    qdd: FloatArray
    tau: FloatArray
    tau_applied: FloatArray
    tau_friction: FloatArray
    tau_ext: FloatArray
    wrench: FloatArray
    contact_force_on_environment: FloatArray
    sensor: FloatArray
    q_measured: FloatArray
    qd_measured: FloatArray
    stuck: FloatArray
    work_actuator: FloatArray
    work_friction: FloatArray
    work_external: FloatArray
    diverged: bool = False
    diverged_at: float | None = None
    divergence: str = ""
    diverged_q: FloatArray | None = None
    diverged_qd: FloatArray | None = None
    logs: dict[str, FloatArray] = field(default_factory=dict)
    info: dict[str, Any] = field(default_factory=dict)
    reference: SampledReference | None = None
    limits: LimitReport | None = None
    contact_position: FloatArray | None = None
    plant: RobotModel | None = field(default=None, repr=False)
    #: the energies, or None with ``_energy_of(q, qd)`` to compute them when first asked for
    _energy: FloatArray | None = field(default=None, repr=False)
    _energy_of: Callable[[FloatArray, FloatArray], FloatArray] | None = field(default=None, repr=False)
    #: False: the arrays given are the result's own, nothing else writes into them (the simulator's record):
    #: made read-only, not copied
    _copy: InitVar[bool] = True

    if TYPE_CHECKING:  # the dataclass's __init__, which also takes the deprecated keyword contact_force (below)

        def __init__(self, *args: Any, **kwargs: Any) -> None: ...

    def __post_init__(self, _copy: bool) -> None:
        for name in (*_ARRAYS, "diverged_q", "diverged_qd", "_energy", "contact_position"):
            a = getattr(self, name)
            if a is not None:
                a = np.array(a, copy=True) if _copy else np.asarray(a)
                a.flags.writeable = False
                object.__setattr__(self, name, a)
        logs = {}
        for k, v in self.logs.items():
            a = np.array(v, copy=True) if _copy else np.asarray(v)
            a.flags.writeable = False
            logs[k] = a
        object.__setattr__(self, "logs", logs)

    # ------------------------------------------------------------------------------ derived
    @property
    def contact_force_on_robot(self) -> FloatArray:
        """F_p = −h_p: the force the environment exerts on each contact point of the arm (N, P, 3) [N], world
        axes. Pressing on a floor with 10 N reads (0, 0, +10): the sense of :class:`armctl.controllers.osc.Contact`
        and :class:`~armctl.controllers.osc.ContactForceTask` (whose target it is to be compared with)."""
        f = -self.contact_force_on_environment
        f.flags.writeable = False
        return f

    @property
    def contact_force(self) -> FloatArray:
        """Deprecated alias of :attr:`contact_force_on_environment` (the same values: the force the arm exerts,
        h_p); it warns with a :class:`DeprecationWarning`. Use :attr:`contact_force_on_environment`, or
        :attr:`contact_force_on_robot` for the force on the arm (−h_p), the sense of the contact tasks."""
        warnings.warn(
            "SimResult.contact_force is deprecated: it is the force the arm exerts on its environment, now named "
            "contact_force_on_environment (same values); for the force on the arm, the sense of osc.Contact and "
            "ContactForceTask, use contact_force_on_robot (= −contact_force_on_environment)",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.contact_force_on_environment

    @property
    def task_errors(self) -> dict[str, FloatArray]:
        """The frame tasks' errors: ``position_error[NAME]`` (N, 3) [m] and ``orientation_error[NAME]`` (N, 3)
        [rad] of each frame task NAME whose target the controller logged (the operational-space controllers do,
        see :mod:`armctl.controllers.osc.task_errors`), e = target − actual in world axes, the actual pose by the
        plant's forward kinematics at :attr:`q` (computed when first asked for; :meth:`save` keeps them in the
        file); NaN on rows the task leaves free (weight 0) and on samples without a target. Empty for a
        controller without frame tasks."""
        cached = self.__dict__.get("_task_error_cache")
        if cached is None:
            cached = task_errors(self.logs, self.plant, self.q)
            for a in cached.values():
                a.flags.writeable = False
            object.__setattr__(self, "_task_error_cache", cached)
        return dict(cached)

    def tracking_errors(self) -> list[ErrorSummary]:
        """The errors the run is judged on, headline first: each task error of :attr:`task_errors` when there are
        some, then the joint error against the joint reference (see :mod:`armctl.sim.tracking`).

        Returns
        -------
        list of ErrorSummary
            Name, kind, RMS and max of each error [m or rad]; empty without a reference or task errors.
        """
        out = task_summaries(self.task_errors)
        if self.reference is not None:
            joint = joint_summary(self.error, self.joint_names, "joint reference" if out else "joints")
            if joint is not None:
                out.append(joint)
        return out

    @property
    def tracked(self) -> bool | None:
        """Whether the run tracked what was asked: it finished (not diverged, not stopped by an exception) and
        the RMS of each task error (or, without task errors, of the joint error) is within
        :data:`armctl.sim.TRACKING_TOLERANCE`. None when there is nothing to judge (no reference and no
        task errors). Separate from :attr:`status`, which is the run's numerical health."""
        summaries = self.tracking_errors()
        headline = [s for s in summaries if s.name != "joint reference"]
        if not headline:
            return None
        if self.diverged or "failure" in self.info:
            return False
        return all(s.within for s in headline)

    @property
    def energy(self) -> FloatArray:
        """E = T + U of the plant at every sample [J] (computed from q, q̇ when first asked for; NaN if the run
        was made with ``energy=False``)."""
        e = self._energy
        if e is None:
            e = self._energy_of(self.q, self.qd) if self._energy_of is not None else np.full(len(self.t), np.nan)
            e.flags.writeable = False
            object.__setattr__(self, "_energy", e)
            object.__setattr__(self, "_energy_of", None)
        return e

    @property
    def n(self) -> int:
        """Number of joints."""
        return int(self.q.shape[1])

    @property
    def duration(self) -> float:
        """Simulated time covered by the samples [s]."""
        return float(self.t[-1] - self.t[0]) if len(self.t) else 0.0

    @property
    def work(self) -> FloatArray:
        """Total work since t = 0 [J]: actuator + friction + external."""
        return self.work_actuator + self.work_friction + self.work_external

    def energy_balance(self) -> FloatArray:
        """E(t) − E(0) − W(t) [J]: zero for the exact solution; its size measures the integration error.

        Returns
        -------
        ndarray, shape (N,)
            [J].
        """
        energy = self.energy
        if not len(energy):  # a run stopped before its first sample
            return np.zeros(0)
        return energy - energy[0] - self.work

    @property
    def error(self) -> FloatArray:
        """Tracking error e = reference.q − q at every sample (N, n) [rad or m]. Raises an InvalidParameterError
        for a result without its reference (one read from a file written before results kept it)."""
        if self.reference is None:
            raise InvalidParameterError(
                "this result does not hold its reference (it was saved without one): compute the error "
                "from the reference itself, e.g. np.array([ref(t).q for t in res.t]) - res.q",
                value=None,
            )
        e = self.reference.q - self.q
        e.flags.writeable = False
        return e

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The plant's joint names (``"joint 0"`` … where the result does not know them)."""
        if self.plant is not None:
            return self.plant.joint_names
        if self.limits is not None and len(self.limits.joint_names) == self.n:
            return self.limits.joint_names
        return tuple(f"joint {j}" for j in range(self.n))

    @property
    def status(self) -> str:
        """``"failed"`` (the run stopped on an exception: the result travelled with it as ``exc.result``,
        ``info["failure"]`` says which), ``"diverged"`` (the run stopped early), ``"saturated"`` (some joint's torque
        sat at its limit on most
        samples, see :data:`armctl.sim.limits.SATURATION_SHARE`), ``"over limits"`` (a joint went beyond its
        velocity limit or outside its position range), or ``"ok"``; the first that applies. Details in
        :attr:`limits`."""
        if "failure" in self.info:
            return "failed"
        if self.diverged:
            return "diverged"
        if self.limits is not None and self.limits.is_saturated:
            return "saturated"
        if self.limits is not None and self.limits.overrun:
            return "over limits"
        return "ok"

    def __repr__(self) -> str:
        head = f"SimResult({self.info.get('plant', '?')}, n = {self.n}, {len(self.t)} samples over {self.duration:g} s"
        head += f", {self.info.get('integrator', '?')}"
        lines = [head + f"): {self.status}"]
        if "failure" in self.info:
            lines.append(f"  stopped at t = {self.duration:g} s by {self.info['failure']}")
        if self.diverged:
            lines.append(f"  diverged at t = {self.diverged_at:g} s ({self.divergence})")
        for summary in self.tracking_errors():  # the task errors first, where there are some
            lines.append(f"  {summary.text()}")
        tracked = self.tracked
        if tracked is not None:
            tasks = bool(self.task_errors)
            lines.append(f"  tracked: {'yes' if tracked else 'no'} (RMS within {_tolerances(tasks)})")
        if len(self.t):
            peak = np.fmax.reduce(np.abs(self.tau_applied), axis=0)  # (NaN: a sample without a torque)
            lines.append(f"  peak |τ applied| {float(peak.max()):.3g} N·m ({self.joint_names[int(peak.argmax())]})")
        if self.limits is not None:
            for text in filter(None, (self.limits.saturation_text(), *self.limits.overrun_texts())):
                lines.append(f"  {text}")
        if self.info.get("unstable_contacts"):
            lines.append("  integrator unstable on a contact (see info['unstable_contacts'])")
        return "\n".join(lines)

    # ------------------------------------------------------------------------------ files
    def save(self, path: str | Path) -> Path:
        """Write the result to an ``.npz`` file.

        Parameters
        ----------
        path : str or path-like
            The file (the suffix ``.npz`` is added if missing).

        Returns
        -------
        pathlib.Path
            The file written.

        Raises
        ------
        InvalidParameterError
            A log holds Python objects (npz stores them only by pickling, which :meth:`load` refuses; the key is
            named), or the path cannot be written.
        """
        path = Path(path)
        if path.suffix != ".npz":
            path = path.with_name(path.name + ".npz")
        arrays: dict[str, Any] = {_FILE_KEYS.get(name, name): getattr(self, name) for name in (*_ARRAYS, "energy")}
        for name in ("diverged_q", "diverged_qd", "contact_position"):
            if getattr(self, name) is not None:
                arrays[name] = getattr(self, name)
        if self.reference is not None:
            for name in ("q", "qd", "qdd"):
                arrays[f"reference_{name}"] = getattr(self.reference, name)
        if self.limits is not None:
            for name in ("effort", "velocity", "lower", "upper"):
                arrays[f"limit_{name}"] = getattr(self.limits, name)
        logs = {**self.task_errors, **self.logs}  # the tasks' errors too (a loaded result has no plant to compute them)
        for k, v in logs.items():
            if v.dtype.kind == "O":
                raise InvalidParameterError(
                    f"log {k!r} holds Python objects (e.g. None or dicts), which a SimResult file cannot store; "
                    "convert it to numbers or drop it (dataclasses.replace(result, logs=...)) before saving",
                    value=k,
                )
            arrays[f"log:{k}"] = v
        meta = {
            "diverged": self.diverged,
            "diverged_at": self.diverged_at,
            "divergence": self.divergence,
            "info": self.info,
            "format": "armctl.SimResult/1",
        }
        if self.limits is not None:
            meta["limits"] = {"joint_names": list(self.limits.joint_names), "clipped": self.limits.clipped}
        arrays["meta"] = np.array(json.dumps(meta, default=_jsonable))
        try:
            np.savez_compressed(path, **arrays)
        except OSError as e:
            raise InvalidParameterError(
                f"cannot write the SimResult to {str(path)!r}: {e.strerror or e}; pass a "
                "path in an existing, writable folder",
                value=str(path),
            ) from e
        return path

    @classmethod
    def load(cls, path: str | Path) -> SimResult:
        """Read a result written by :meth:`save`.

        Parameters
        ----------
        path : str or path-like
            The ``.npz`` file.

        Returns
        -------
        SimResult

        Raises
        ------
        InvalidParameterError
            The file is missing, unreadable or not a complete saved SimResult (named).
        """
        path = Path(path)

        def bad(why: str) -> InvalidParameterError:
            return InvalidParameterError(f"{str(path)!r} {why}; pass a file written by SimResult.save", value=str(path))

        if not path.is_file():
            raise bad("does not exist" if not path.exists() else "is not a file")
        try:
            data = np.load(path, allow_pickle=False)
        except (OSError, ValueError, EOFError, zipfile.BadZipFile) as e:  # unreadable, not NumPy, pickled
            raise bad(f"cannot be read as an npz file ({e})") from e
        if not isinstance(data, np.lib.npyio.NpzFile):
            raise bad("is a single NumPy array (.npy), not a saved SimResult (.npz)")
        with data:
            if "meta" not in data.files:
                raise bad("is not a saved SimResult (no 'meta' entry)")
            missing = [k for k in (*(_FILE_KEYS.get(a, a) for a in _ARRAYS), "energy") if k not in data.files]
            if missing:
                raise bad(f"is incomplete: it lacks the entries {missing}")
            try:
                meta = json.loads(str(data["meta"]))
                kw: dict[str, Any] = {name: data[_FILE_KEYS.get(name, name)] for name in _ARRAYS}
                kw["_energy"] = data["energy"]
                for name in ("diverged_q", "diverged_qd", "contact_position"):
                    kw[name] = data[name] if name in data.files else None
                logs = {k[4:]: data[k] for k in data.files if k.startswith("log:")}
                extra = {k: data[k] for k in data.files if k.startswith(("reference_", "limit_"))}
            except (ValueError, OSError, EOFError, zipfile.BadZipFile) as e:  # bad JSON, object arrays, corrupt
                raise bad(f"has an unreadable entry ({e})") from e
        keys = ("diverged", "diverged_at", "divergence", "info")
        if not isinstance(meta, dict) or any(k not in meta for k in keys):
            raise bad(f"has a 'meta' entry without the keys {list(keys)}")
        if all(f"reference_{k}" in extra for k in ("q", "qd", "qdd")):  # (files of older versions lack them)
            kw["reference"] = SampledReference(kw["t"], *(extra[f"reference_{k}"] for k in ("q", "qd", "qdd")))
        if all(f"limit_{k}" in extra for k in ("effort", "velocity", "lower", "upper")) and "limits" in meta:
            kw["limits"] = LimitReport.of_run(
                kw["tau"],
                kw["q"],
                kw["qd"],
                extra["limit_effort"],
                extra["limit_velocity"],
                extra["limit_lower"],
                extra["limit_upper"],
                joint_names=tuple(meta["limits"]["joint_names"]),
                clipped=bool(meta["limits"]["clipped"]),
            )
        return cls(
            **kw,
            diverged=bool(meta["diverged"]),
            diverged_at=meta["diverged_at"],
            divergence=meta["divergence"],
            logs=logs,
            info=meta["info"],
        )

    # ------------------------------------------------------------------------------ plots
    def plot(self, quantities: tuple[str, ...] | str = ("q", "qd", "error", "tau_applied"), joints: Any = None) -> Any:
        """A matplotlib Figure with one panel per quantity, the reference overlaid and the joints named (see
        :func:`armctl.sim.plot.plot_joints`).

        Parameters
        ----------
        quantities : str or tuple of str, optional
            At least one of: per-joint arrays of the result, ``"q"``, ``"qd"``, ``"qdd"``, ``"tau"``,
            ``"tau_applied"``, ``"tau_friction"``, ``"tau_ext"``, ``"q_measured"``, ``"qd_measured"``, and
            ``"error"`` (q_d − q); contact forces, ``"contact_force"`` (the force on the robot,
            :attr:`contact_force_on_robot`), ``"contact_force_on_robot"``, ``"contact_force_on_environment"``;
            wrenches, ``"wrench"`` (:attr:`wrench`) and ``"sensor"`` (:attr:`sensor`, the measured wrench); and
            the frame tasks' errors, ``"position_error"`` [m] and ``"orientation_error"`` [rad]
            (:attr:`task_errors`).
        joints : int or sequence of int, optional
            The joints to draw in the per-joint panels, 0-based indices 0 … n − 1 (None: all).

        Returns
        -------
        matplotlib.figure.Figure

        Raises
        ------
        InvalidParameterError, UnknownNameError
            No quantity, an unknown one, one the result has nothing of (task errors without frame tasks, a
            sensor reading without sensors), or joint indices out of range.
        """
        return plot_joints(self, quantities, joints)

    def plot_energy(self) -> Any:
        """A matplotlib Figure of the energy balance (see :func:`armctl.sim.plot.plot_energy`).

        Returns
        -------
        matplotlib.figure.Figure
        """
        return plot_energy(self)

    def playback(self, path: str | Path, model: RobotModel | None = None, **options: Any) -> Path:
        """Write the run as a standalone HTML page that plays the arm's motion in 3D.

        Parameters
        ----------
        path : str or path-like
            The page to write.
        model : RobotModel, optional
            The arm to draw (None: :attr:`plant`).
        **options
            Passed to :func:`armctl.sim.playback.playback`: ``fps``, ``meshes``, ``environment``, ``title``.

        Returns
        -------
        pathlib.Path
            The page written.
        """
        return _playback(self, path, model, **options)

    def plot_wrench(self) -> Any:
        """A matplotlib Figure of the contact wrench and forces (see :func:`armctl.sim.plot.plot_wrench`).

        Returns
        -------
        matplotlib.figure.Figure
        """
        return plot_wrench(self)

    # ------------------------------------------------------------------------------ tables
    def to_dataframe(self, layout: str = "long") -> Any:
        """The run as a pandas DataFrame (``pip install "armctl[data]"``; see :mod:`armctl.sim.tables`).

        Parameters
        ----------
        layout : {"long", "wide"}, optional
            ``"long"``: one row per sample and joint, columns ``t`` [s], ``joint`` (the joint's name), ``q``,
            ``qd``, ``qdd``, ``tau``, ``tau_applied`` and, where the result holds its reference, ``q_ref``,
            ``qd_ref``, ``qdd_ref`` and ``error`` (= q_ref − q). ``"wide"``: one row per sample, indexed by
            ``t``, with columns (quantity, joint), so that ``df["q"]`` holds one column per joint.

        Returns
        -------
        pandas.DataFrame
            Angles in rad (m for prismatic joints), torques in N·m (N).

        Raises
        ------
        OptionalDependencyError
            pandas is not installed.
        InvalidParameterError
            An unknown layout.
        """
        return sim_dataframe(self, layout)

    def to_xarray(self) -> Any:
        """The run as an xarray Dataset with coordinates ``time`` [s] and ``joint`` (the joint names)
        (``pip install "armctl[data]"``; see :mod:`armctl.sim.tables`).

        Returns
        -------
        xarray.Dataset
            Variables over (time, joint): ``q``, ``qd``, ``qdd``, ``tau``, ``tau_applied`` and, with the
            reference, ``q_ref``, ``qd_ref``, ``qdd_ref``, ``error``; ``wrench`` over (time, wrench_axis);
            the work terms over time. Each variable's ``units`` and ``long_name`` are in its attrs; the
            run's status and settings in the Dataset's attrs.

        Raises
        ------
        OptionalDependencyError
            xarray is not installed.
        """
        return sim_xarray(self)


def _tolerances(tasks: bool) -> str:
    t = TRACKING_TOLERANCE
    return f"{t['position']:g} m and {t['orientation']:g} rad" if tasks else f"{t['joint']:g} rad or m"


_dataclass_init = SimResult.__init__


def _init(self: SimResult, *args: Any, contact_force: FloatArray | None = None, **kwargs: Any) -> None:
    """The dataclass's __init__, also taking ``contact_force``: the deprecated name of
    ``contact_force_on_environment``."""
    if contact_force is not None:
        if "contact_force_on_environment" in kwargs:
            raise InvalidParameterError(
                "give contact_force_on_environment only (contact_force is its deprecated name), not both",
                value=contact_force,
            )
        kwargs["contact_force_on_environment"] = contact_force
    _dataclass_init(self, *args, **kwargs)


# (inspect reads a function's __signature__, which typeshed does not declare on functions)
_init.__signature__ = inspect.signature(_dataclass_init)  # type: ignore[attr-defined]  # see the line above
setattr(SimResult, "__init__", _init)  # noqa: B010  (mypy: a method is not assigned to)


def _jsonable(x: Any) -> Any:
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    return str(x)


FIELD_NAMES = tuple(f.name for f in fields(SimResult))
