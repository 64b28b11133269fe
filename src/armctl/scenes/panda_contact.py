"""``panda_contact``: the Panda approaches a table, presses on it with 10 N and slides 10 cm along it against
surface friction — operational-space control as a QP with a sliding contact and normal-force regulation,
against Khatib's closed-form controller, which can only press through its pose stiffness. The joints have
viscous and Coulomb friction (the contact scene checked with joint friction), which both
controllers' model knows."""

from __future__ import annotations

from typing import Any, ClassVar, cast

import numpy as np
from numpy.typing import ArrayLike

from armctl import models
from armctl._checks import boolean, scalar
from armctl.controllers.base import Controller
from armctl.controllers.osc import (
    ClosedFormOSC,
    Contact,
    ContactForceTask,
    FramePoseTask,
    OperationalSpaceQP,
    PostureTask,
)
from armctl.dynamics.base import Dynamics
from armctl.references import Reference
from armctl.scenes.base import Scene, holding_scene, quintic

Q_HOME = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])  # the Panda's "ready" posture


class PressAndSlide(Controller):
    """Scene logic around an operational-space controller: approach the table at 2 cm/s; on touching it
    (tool below the table plane) the QP switches its sliding contact on, frees the pose task's normal row
    and ramps the normal force to ``force`` [N] in 0.2 s; then slide ``slide`` [m] along x (quintic profile
    of ``slide_time`` s from ``slide_start`` s). ``closed_form=True`` uses :class:`ClosedFormOSC` instead,
    which keeps pushing its pose target 1 cm below the table: the force is whatever its stiffness gives.

    Parameters
    ----------
    dyn : Dynamics
        The controller's model.
    z_table : float
        The table's height [m].
    mu : float
        The friction coefficient of the sliding contact.
    force : float, optional
        The normal force to reach [N], finite, ≥ 0.
    slide : float, optional
        How far to slide along x [m].
    slide_start : float, optional
        When the slide starts [s], finite, ≥ 0.
    slide_time : float, optional
        How long it takes [s], finite, > 0.
    closed_form : bool, optional
        Use :class:`ClosedFormOSC` instead of the QP.
    kp, kd : array_like, optional
        The pose task's gains (see :class:`FramePoseTask`; ``kd=None``: its default).
    """

    dynamics: Dynamics  # given to __init__, never None

    def __init__(
        self,
        dyn: Dynamics,
        z_table: float,
        mu: float,
        force: float = 10.0,
        slide: float = 0.1,
        slide_start: float = 0.75,
        slide_time: float = 1.0,
        closed_form: bool = False,
        kp: ArrayLike = 400.0,
        kd: ArrayLike | None = None,
    ) -> None:
        super().__init__(dyn)
        self.p0, self.z_table = dyn.frame_pose(Q_HOME), scalar(z_table, "z_table")
        mu = scalar(mu, "mu", nonnegative=True)
        self.force_target = scalar(force, "force", nonnegative=True)
        self.slide = scalar(slide, "slide")
        self.slide_start = scalar(slide_start, "slide_start", nonnegative=True)
        self.slide_time = scalar(slide_time, "slide_time", positive=True)
        self._slide = quintic(0.0, self.slide, self.slide_start, self.slide_time)  # along x
        self.pose = FramePoseTask(kp=kp, kd=kd)
        self.pose.set_trajectory(self.target)
        self.closed_form = boolean(closed_form, "closed_form")
        self.touched: float | None = None
        if self.closed_form:
            self.ctrl: Controller = ClosedFormOSC(dyn, self.pose, PostureTask(dyn.n, kp=25.0))
        else:
            self.contact = Contact(mode="sliding", mu=mu, kd=100.0, active=False)
            self.force_task = ContactForceTask(self.contact, 0.0, weight=1.0)
            self._force = 0.0  # the force task's target [N]
            self.ctrl = OperationalSpaceQP(
                dyn, [self.pose, self.force_task, PostureTask(dyn.n, kp=25.0, priority=1)], contacts=[self.contact]
            )

    def target(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Tool pose, twist and acceleration targets.

        Parameters
        ----------
        t : float
            The time [s].

        Returns
        -------
        tuple of ndarray
            (pose (4, 4), twist (6,), acceleration (6,)).
        """
        pose, twist, acc = self.p0.copy(), np.zeros(6), np.zeros(6)
        z_end = self.z_table - 0.01
        pose[2, 3] = max(self.p0[2, 3] - 0.02 * t, z_end)
        twist[2] = -0.02 if pose[2, 3] > z_end else 0.0
        x, vx, ax = self._slide(t)
        pose[0, 3] += x
        twist[0], acc[0] = vx, ax
        return pose, twist, acc

    def reset(self) -> None:
        super().reset()
        self.ctrl.reset()
        self.touched = None
        self.pose.weight = 1.0
        if not self.closed_form:
            self.contact.active = False
            self.force_task.set_target(0.0)
            self._force = 0.0

    def compute(self, t: float, q: np.ndarray, qd: np.ndarray, ref: Reference) -> np.ndarray:
        if self.touched is None and self.dynamics.frame_pose(q)[2, 3] <= self.z_table:
            self.touched = t
            if not self.closed_form:
                self.contact.active = True
                self.pose.weight = [1, 1, 0, 1, 1, 1]  # the contact takes over the normal direction
        if self.touched is not None and not self.closed_form:
            force = self.force_target * min(1.0, (t - self.touched) / 0.2)
            if force != self._force:  # the ramp, then its end held (set once)
                self.force_task.set_target(force)
                self._force = force
        tau = self.ctrl.compute(t, q, qd, ref)
        self.last_log = dict(self.ctrl.last_log)
        return tau


def panda_contact_model() -> Any:
    return models.panda().with_friction(
        viscous=[0.5, 0.5, 0.5, 0.5, 0.2, 0.2, 0.2], coulomb=[0.8, 0.8, 0.8, 0.8, 0.3, 0.3, 0.3]
    )


class ContactScene(Scene):
    """A scene whose methods (``osc_qp``, ``osc_closed_form``) are :class:`PressAndSlide` controllers, their gains
    the pose task's ``kp`` and ``kd`` (the preset, ``controllers/panda_contact.<method>.toml``, unless given; a
    missing key: the task's default). Its :meth:`metrics`' error is the tool's position error [m] (RMS, max) in
    the table plane against the controller's target, with the normal force error after settling [N]
    (``force_rms_error``) and contact loss (``contact_lost``) reported. Its parameters are :class:`Scene`'s.
    """

    z_table: float = 0.0
    mu: float = 0.3
    timing_samples = 100  # a QP step costs ten times a joint-space law's

    gain_keys: ClassVar[dict[str, tuple[tuple[str, ...], tuple[str, ...]]]] = {
        "osc_qp": ((), ("kp", "kd")),
        "osc_closed_form": ((), ("kp", "kd")),
    }

    def build(self, method: str, gains: dict[str, Any]) -> Controller:
        return PressAndSlide(
            self.dynamics("exact"),
            self.z_table,
            self.mu,
            closed_form=method == "osc_closed_form",
            kp=gains.get("kp", 400.0),
            kd=gains.get("kd"),
        )

    def scene_measures(self, res: Any, method: str, gains: dict[str, Any] | None = None) -> dict[str, Any]:
        if not len(res.t):  # a run without samples: nothing to measure
            return {"force_rms_error": float("nan"), "contact_lost": False, "error_unit": "m"}
        dyn = self.dynamics("exact")
        probe = cast(PressAndSlide, self.controller(method, gains))
        x = np.array([dyn.frame_pose(q)[:3, 3] for q in res.q])
        want = np.array([probe.target(float(t))[0][:3, 3] for t in res.t])
        err = np.linalg.norm((x - want)[:, :2], axis=1)  # in the table plane: the normal is force-controlled
        fn = res.contact_force_on_robot[:, 0, 2] if res.contact_force_on_environment.size else np.zeros(len(res.t))
        touch = np.flatnonzero(fn > 0)
        settled = (res.t >= res.t[touch[0]] + 0.4) if touch.size else np.zeros(len(res.t), bool)
        return {
            "rms_error": float(np.sqrt((err**2).mean())),
            "max_error": float(err.max()),
            "force_rms_error": float(np.sqrt(((fn[settled] - 10.0) ** 2).mean())) if settled.any() else float("nan"),
            "contact_lost": bool(touch.size and (fn[touch[0] + 1 :] <= 0).any()),
            "error_unit": "m",
        }


def panda_contact() -> Scene:
    """The Panda with joint friction pressing 10 N on a table (a Kelvin–Voigt plane, surface friction μ = 0.3)
    just below its ready pose, and sliding 10 cm along it: the methods ``osc_qp`` and ``osc_closed_form``
    (:class:`PressAndSlide`), integrated at 0.2 ms.

    Returns
    -------
    ContactScene
    """
    from armctl.sim import KelvinVoigt, Plane

    model = panda_contact_model()
    z_table = float(Dynamics(model).frame_pose(Q_HOME)[2, 3]) - 0.005
    plane = Plane(KelvinVoigt(2e4, 50.0), normal=(0, 0, 1), point=(0, 0, z_table), friction=0.3)
    sc = holding_scene(
        ContactScene,
        "panda_contact",
        "Panda with joint friction pressing 10 N on a table (surface friction μ = 0.3) and sliding 10 cm",
        model,
        Q_HOME,
        duration=1.95,
        # 0.2 ms steps: below its 1 mm/s slip velocity the table's friction is a viscous law of slope
        # μ f_n / v_slip, which RK4 integrates only below 0.4 ms here (at the closed form's 21 N;
        # armctl.sim.after_run): at 1 ms the tangential force chatters
        dt=2e-4,
        methods=("osc_qp", "osc_closed_form"),
        sim_options={"environment": plane},
    )
    sc.z_table = z_table
    return sc
