"""`Plant`: the truth that ``simulate`` integrates — rigid-body dynamics, joint friction, contact environments
and an external-wrench disturbance:

    M(q) q̈ + C(q, q̇) q̇ + g(q) = τ − τ_f(q̇) − Σ_p J_p(q)ᵀ h_p − J_tool(q)ᵀ h_d(t)

τ: the applied (held, saturated) torque; τ_f: the friction model's torque, or for stuck joints the holding
torque of the stick–slip constraint; h_p: contact forces on the environment; h_d(t): the disturbance wrench at
the tool frame, with the sign of ``Dynamics``' ``wrench`` (what the arm exerts on the environment: a push of F
on the arm is h_d = −F). Within an integration step [t, t + h], h_d is evaluated at its start, middle and end and
follows the parabola through these three values (:meth:`Plant.sample_disturbance`): exactly the disturbance at
RK4's stages, and the same numbers for the Python and the generated step.

The plant also gives the powers the integrators accumulate into work: p_f = −q̇ᵀτ_f (≤ 0) and
p_e = −q̇ᵀ(Σ J_pᵀh_p + J_toolᵀh_d).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from armctl._checks import BoolArray, FloatArray, real_array
from armctl.dynamics.base import Dynamics
from armctl.errors import NonFiniteError, ShapeError
from armctl.sim.contact import Environment
from armctl.sim.friction import FrictionModel, StickSlip
from armctl.sim.stick_slip import constrained_accel, solve_sticking

Disturbance = Callable[[float], Any]


class Plant:
    """The simulated arm. ``friction``: a friction model (None or all-zero: none); ``environments``: contact
    environments; ``disturbance``: t [s] → h_d (6,) or None.

    Stick–slip state (set by :meth:`begin` at the start of every step, fixed during it): ``stuck`` (boolean
    mask or None), ``direction`` (sliding direction ±1 of every joint that can stick, 0 at rest) and ``hold``
    (holding friction torques of the stuck joints).
    """

    def __init__(
        self,
        dyn: Dynamics,
        friction: FrictionModel | None = None,
        environments: Sequence[Environment] = (),
        disturbance: Disturbance | None = None,
    ) -> None:
        self.dyn = dyn
        self.n = n = dyn.n
        self.friction = None if friction is None or friction.is_zero else friction
        f = self.friction
        self.sticky: StickSlip | None = f if isinstance(f, StickSlip) and f.any_capable else None
        self.environments = tuple(environments)
        self.kinematics = [env.kinematics(dyn) for env in self.environments]
        self.disturbance = disturbance
        self.has_external = bool(self.environments) or disturbance is not None
        #: no friction, no contact, no disturbance: q̈ is Pinocchio's ABA of τ and work needs no quadrature
        self.simple = self.friction is None and not self.has_external
        self._zeros = np.zeros(n)
        self._capable = self.sticky.capable.astype(float) if self.sticky is not None else self._zeros
        self.kernel = k = dyn.kernel
        self.forward = k.aba
        self.mass = k.mass
        self.rnea = k.rnea
        self.zeros = k.zeros
        self.direction = np.zeros(n)
        self._stickslip = isinstance(f, StickSlip)
        self._fv = f.viscous if f is not None else self._zeros
        self._set_direction(self.direction)
        self.stuck: BoolArray | None = None
        self.all_stuck = False
        self.hold = np.zeros(n)
        self.stats = {"stick_events": 0, "breakaway_events": 0, "implicit_unconverged": 0}
        self._window: tuple[float, float, FloatArray] | None = None  # the step's disturbance samples

    # ---------------------------------------------------------------------------------- disturbance
    def sample_disturbance(self, t: float, h: float) -> None:
        """Evaluate h_d at t, t + h/2 and t + h: until :meth:`end_step`, the disturbance at a time t + θh of the
        step is the parabola through them, h_d(θ) = (1 − θ)(1 − 2θ) h₀ + 4θ(1 − θ) h_½ + θ(2θ − 1) h₁."""
        d = self.disturbance_wrench
        self._window = (t, h, np.array((d(t), d(t + 0.5 * h), d(t + h))))

    def end_step(self) -> None:
        """Back to evaluating h_d at the time asked (outside a step: at the samples, for the record)."""
        self._window = None

    def disturbance_at(self, t: float) -> FloatArray:
        """h_d at t: within a step, on the parabola through its samples (see :meth:`sample_disturbance`).
        (C copy: ``step_core.c``'s ``armctl_interp``; tests/sim/test_compiled_plant.py fails when they disagree.)"""
        w = self._window
        if w is None:
            return self.disturbance_wrench(t)
        t0, h0, samples = w
        theta = (t - t0) / h0
        for node in (0.0, 0.5, 1.0):  # the stages of a whole step: their sample exactly
            if abs(theta - node) < 1e-9:
                theta = node
        l0, l1, l2 = (1.0 - theta) * (1.0 - 2.0 * theta), 4.0 * theta * (1.0 - theta), theta * (2.0 * theta - 1.0)
        return l0 * samples[0] + l1 * samples[1] + l2 * samples[2]

    # ---------------------------------------------------------------------------------- forces
    def disturbance_wrench(self, t: float) -> FloatArray:
        """h_d(t) (6,), checked."""
        h = self.disturbance(t)  # type: ignore[misc]  # called only when there is one
        if h.__class__ is not np.ndarray or h.dtype != np.float64:  # text, dicts, complex: named errors
            h = real_array(h, f"disturbance(t) at t = {t:g} s")
        if h.shape != (6,):
            raise ShapeError(
                f"disturbance(t) must return a (6,) wrench [f; moment], got shape {h.shape} at t = {t}", value=h
            )
        if not math.isfinite(sum(h.tolist())) and not np.isfinite(h).all():  # (a sum of finite entries can overflow)
            raise NonFiniteError(f"disturbance(t) returned a non-finite wrench {h} at t = {t}", value=h)
        return h

    def external(self, t: float, q: FloatArray, qd: FloatArray) -> FloatArray:
        """The external joint torque *added* to τ: Σ J_pᵀF_p − J_toolᵀh_d (F_p: contact force on the arm)."""
        tau = np.zeros(self.n)
        for env, kin in zip(self.environments, self.kinematics, strict=True):
            tau += env.joint_torque(kin, q, qd)[0]
        if self.disturbance is not None:
            tau -= self.kernel.jacobian(q, None).T @ self.disturbance_at(t)
        return tau

    def external_stiffness(self, t: float, q: FloatArray, qd: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(τ_e, K, D): :meth:`external` with its derivatives in q and q̇ (the disturbance taken as given)."""
        n = self.n
        tau, kj, dj = np.zeros(n), np.zeros((n, n)), np.zeros((n, n))
        for env, kin in zip(self.environments, self.kinematics, strict=True):
            te, ke, de = env.joint_torque(kin, q, qd, stiffness=True)
            tau += te
            kj += ke
            dj += de
        if self.disturbance is not None:
            tau -= self.kernel.jacobian(q, None).T @ self.disturbance_at(t)
        return tau, kj, dj

    def friction_torque(self, qd: FloatArray) -> FloatArray:
        """τ_f now: the model's torque for sliding joints, the holding torque for stuck ones."""
        if self.friction is None:
            return np.zeros(self.n)
        return self.kinetic_friction(qd) + self.hold

    def _set_direction(self, direction: FloatArray) -> None:
        key = direction.tolist()
        if key == getattr(self, "_direction_key", None):
            return
        self._direction_key = key
        self.direction = direction
        if self._stickslip:
            f: StickSlip = self.friction  # type: ignore[assignment]  # _stickslip: it is a StickSlip
            self._level = f.level(direction)
            self._hump = f.hump(direction) if f.has_stribeck else None

    def kinetic_friction(self, qd: FloatArray) -> FloatArray:
        """The friction model's torque at q̇ for the current sliding directions (0 for stuck joints)."""
        if self._stickslip:
            tau = self._fv * qd + self._level
            if self._hump is not None:
                tau += self._hump * np.exp(-((qd / self.friction.stribeck_velocity) ** 2))  # type: ignore[union-attr]  # _stickslip
            return tau
        return self.friction.torque(qd, self.direction)  # type: ignore[union-attr]  # called with friction only

    def friction_slope(self, qd: FloatArray) -> FloatArray:
        """∂τ_f/∂q̇ (diagonal) for the current sliding directions."""
        return self.friction.slope(qd, self.direction)  # type: ignore[union-attr]  # called with friction only

    # ------------------------------------------------------------------------------ stick–slip
    def begin(self, t: float, q: FloatArray, qd: FloatArray, tau: FloatArray, held: BoolArray | None = None) -> None:
        """Decide which joints stick for the step starting at (t, q, q̇) under τ (see
        :mod:`armctl.sim.stick_slip`); ``held``: joints kept stuck whatever their holding torque.
        (C copy: ``step_events.c``'s ``armctl_begin``; tests/sim/test_compiled_plant.py fails when they disagree.)"""
        sticky = self.sticky
        if sticky is None:
            return
        self._set_direction(np.sign(qd) * self._capable)
        if 0.0 not in qd.tolist():
            self._free_all()
            return
        cand = sticky.capable & (qd == 0.0)
        if not cand.any():
            self._free_all()
            return
        net = tau - self.kinetic_friction(qd)
        if self.has_external:
            net = net + self.external(t, q, qd)
        rhs = net - self.rnea(q, qd, self.zeros)
        stuck, direction, lam = solve_sticking(sticky, self.mass(q), rhs, cand, self.direction, held)
        self.stats["breakaway_events"] += int((cand & ~stuck).sum())
        self._set_direction(direction)
        self.hold = lam
        self.stuck = stuck if stuck.any() else None
        self.all_stuck = bool(stuck.all())

    def _free_all(self) -> None:
        self.stuck = None
        self.all_stuck = False
        if self.hold.any():
            self.hold = np.zeros(self.n)

    def crossings(self, qd1: FloatArray) -> FloatArray | None:
        """Joints that slid during the step and whose velocity reached zero or reversed (None if none)."""
        if self.sticky is None:
            return None
        d = self.direction * qd1
        if min(d.tolist()) > 0.0 or not self.direction.any():
            return None
        mask = (self.direction != 0.0) & (d <= 0.0)
        return mask if mask.any() else None

    # ------------------------------------------------------------------------------ accelerations
    def accel(self, t: float, q: FloatArray, qd: FloatArray, tau: FloatArray) -> FloatArray:
        """q̈ for the current stick state."""
        net = tau
        if self.friction is not None:
            net = net - self.kinetic_friction(qd)
        if self.has_external:
            net = net + self.external(t, q, qd)
        return self._solve(q, qd, net)

    def accel_work(self, t: float, q: FloatArray, qd: FloatArray, tau: FloatArray) -> tuple[FloatArray, float, float]:
        """(q̈, p_f, p_e): :meth:`accel` and the friction and external powers [W]."""
        a, f, e = self.accel_forces(t, q, qd, tau)
        return a, -float(qd @ f) if f is not None else 0.0, float(qd @ e) if e is not None else 0.0

    def accel_forces(
        self, t: float, q: FloatArray, qd: FloatArray, tau: FloatArray
    ) -> tuple[FloatArray, FloatArray | None, FloatArray | None]:
        """(q̈, τ_f, τ_e): :meth:`accel` with the friction torque (against the motion) and the external torque
        (added to τ) it used, each None if the plant has none. (Generated: ``pk_rhs`` of
        :func:`armctl.sim.generated_plant.kernels`, called by ``step_core.c``'s ``armctl_rhs``.)"""
        net = tau
        f = e = None
        if self.friction is not None:
            f = self.kinetic_friction(qd)
            net = net - f
        if self.has_external:
            e = self.external(t, q, qd)
            net = net + e
        return self._solve(q, qd, net), f, e

    def _solve(self, q: FloatArray, qd: FloatArray, net: FloatArray) -> FloatArray:
        if self.stuck is None:
            return self.forward(q, qd, net)
        if self.all_stuck:
            return np.zeros(self.n)
        return constrained_accel(self.mass(q), net - self.rnea(q, qd, self.zeros), self.stuck)

    def kinetic(self, q: FloatArray, qd: FloatArray) -> float:
        return 0.5 * float(qd @ self.mass(q) @ qd)
