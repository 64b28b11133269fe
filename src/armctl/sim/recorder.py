"""`Recorder`: preallocated per-sample arrays of a run, turned into a :class:`SimResult` at the end."""

from __future__ import annotations

import warnings
from functools import partial
from typing import Any, cast

import numpy as np

from armctl._checks import FloatArray
from armctl.dynamics.base import Dynamics
from armctl.errors import SimulationWarning
from armctl.references import Reference
from armctl.sim.contact import Environment, ForceSensor
from armctl.sim.controller_log import ControllerLog
from armctl.sim.limits import LimitReport, check_limits
from armctl.sim.plant import Plant
from armctl.sim.result import SimResult
from armctl.sim.sampled_reference import SampledReference


class Recorder:
    """Rows 0..N for the samples t_k = k·control_dt."""

    def __init__(
        self,
        n: int,
        samples: int,
        control_dt: float,
        environments: tuple[Environment, ...],
        sensors: tuple[ForceSensor, ...],
        measured: bool,
    ) -> None:
        self.samples = samples
        self.control_dt = control_dt
        z = np.zeros
        # τ, the applied τ and q̈ of a sample the run stops at before computing them stay NaN (see ClosedLoop)
        self.q, self.qd, self.qdd = z((samples, n)), z((samples, n)), np.full((samples, n), np.nan)
        self.tau, self.tau_applied = np.full((samples, n), np.nan), np.full((samples, n), np.nan)
        self.tau_friction, self.tau_ext = z((samples, n)), z((samples, n))
        self.stuck = z((samples, n))  # 1.0: the joint is stuck (a boolean mask in the result)
        self.points = [(env, i) for env in environments for i in range(len(env.points))]
        self.wrench = z((samples, 6))
        self.contact_force = z((samples, len(self.points), 3))
        self.contact_position = z((samples, len(self.points), 3))
        #: the Reference given to the controller at each sample (stacked at the end: a list slot is the cheapest
        #: thing to fill every control period)
        self.references: list[Reference | None] = [None] * samples
        self.sensors = sensors
        self.sensor = z((samples, len(sensors), 6))
        self.measured = measured
        self.q_measured = z((samples, n)) if measured else self.q
        self.qd_measured = z((samples, n)) if measured else self.qd
        self.work_friction, self.work_external = z(samples), z(samples)
        self.log = ControllerLog(samples)

    def record_friction(self, k: int, plant: Plant, qd: FloatArray) -> None:
        """The friction torque and the stuck joints at sample k, after the plant's stick solve there
        (:meth:`Plant.begin <armctl.sim.plant.Plant.begin>`)."""
        self.tau_friction[k] = plant.friction_torque(qd)
        if plant.stuck is not None:
            self.stuck[k] = plant.stuck

    def record_external(self, k: int, plant: Plant, t: float, q: FloatArray, qd: FloatArray) -> None:
        """External torques, contact forces, wrench and sensors at sample k (plants with contact or a
        disturbance): τ_ext, the negative of :meth:`Plant.external <armctl.sim.plant.Plant.external>` (without a
        disturbance, −τ_c from the same evaluation as the forces, :meth:`Environment.contact
        <armctl.sim.contact.Environment.contact>`), and the wrench on the environment about the tool frame's origin
        o: f = Σ_p h_p + f_d, m = Σ_p (p − o) × h_p + m_d. (For a plant without a disturbance, the generated
        engine records the same quantities in C: the kernel ``pk_sample``, :meth:`PlantExpressions.sample
        <armctl.sim.generated_plant.PlantExpressions.sample>`, is its second source; a change here is a change there,
        tests/sim/test_contact_record.py fails when they disagree.)"""
        dyn = plant.dyn
        tau_c = np.zeros(len(q))  # Σ J_pᵀ F_p
        f, m = [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
        if self.points:
            tx, ty, tz = dyn.frame_pose(q, None)[:3, 3].tolist()
            forces, positions = [], []
            for env, kin in zip(plant.environments, plant.kinematics, strict=True):
                te, h, p = env.contact(kin, q, qd)
                tau_c += te
                forces.append(h)
                positions.append(p)
            one = len(forces) == 1
            hs = forces[0] if one else np.concatenate(forces)
            ps = positions[0] if one else np.concatenate(positions)
            self.contact_force[k] = hs
            self.contact_position[k] = ps
            for (hx, hy, hz), (px, py, pz) in zip(hs.tolist(), ps.tolist(), strict=True):
                rx, ry, rz = px - tx, py - ty, pz - tz
                f[0] += hx
                f[1] += hy
                f[2] += hz
                m[0] += ry * hz - rz * hy
                m[1] += rz * hx - rx * hz
                m[2] += rx * hy - ry * hx
            if self.sensors:
                self.record_sensors(k, plant, q)
        if plant.disturbance is not None:
            self.tau_ext[k] = -plant.external(t, q, qd)  # (h_d as the plant takes it within its steps)
            hd = plant.disturbance_wrench(t)
            f = [a + b for a, b in zip(f, hd[:3].tolist(), strict=True)]
            m = [a + b for a, b in zip(m, hd[3:].tolist(), strict=True)]
        else:
            self.tau_ext[k] = -tau_c
        self.wrench[k, :3] = f
        self.wrench[k, 3:] = m

    def record_sensors(self, k: int, plant: Plant, q: FloatArray) -> None:
        """The force sensors' readings at sample k (:meth:`ForceSensor.reading
        <armctl.sim.contact.ForceSensor.reading>`) from the contact forces and positions recorded at row k."""
        joints = np.concatenate([kin.joints for kin in plant.kinematics])
        hs, ps = self.contact_force[k], self.contact_position[k]
        for s, sensor in enumerate(self.sensors):
            self.sensor[k, s] = sensor.reading(plant.dyn, q, hs, ps, joints)

    def log_controller(self, k: int, log: dict[str, Any]) -> None:
        """Record the controller's ``last_log`` entries at sample k."""
        self.log.add(k, log)

    def result(
        self,
        rows: int,
        dyn: Dynamics,
        energy: bool,
        info: dict[str, Any],
        divergence: tuple[float, str, FloatArray, FloatArray] | None,
    ) -> SimResult:
        """The SimResult of the first ``rows`` samples."""
        r = slice(0, rows)
        q, qd = self.q[r], self.qd[r]
        # work of a torque held over [t_k, t_k+1) is exactly τ_kᵀ(q_k+1 − q_k)
        dw = np.einsum("ij,ij->i", self.tau_applied[: max(rows - 1, 0)], np.diff(q, axis=0))
        work_act = np.concatenate(([0.0], np.cumsum(dw)))[:rows]
        logs, skipped = self.log.stacked(rows)
        if skipped:
            warnings.warn(
                f"controller log entries not recorded: {', '.join(skipped)}; only numbers and arrays of "
                "one shape per key are stacked into SimResult.logs — log such values as numbers "
                "(e.g. NaN for 'none') or keep them in the controller",
                SimulationWarning,
                stacklevel=3,
            )
        d = divergence
        t = cast(FloatArray, np.arange(rows) * self.control_dt)
        model = dyn.model
        limits = LimitReport.of_run(
            self.tau[r],
            q,
            qd,
            model.effort_limit,
            model.velocity_limit,
            model.lower,
            model.upper,
            model.joint_names,
            clipped=bool(info.get("saturate", True)),
        )
        check_limits(limits, stacklevel=4)
        refs = self.references[:rows]
        # all of them, or the run had no reference recorded, or the reference of its last sample failed
        given = any(x is not None for x in refs)  # (stops at the first: a run records one at every sample)
        return SimResult(
            t=t,
            q=q,
            qd=qd,
            qdd=self.qdd[r],
            tau=self.tau[r],
            tau_applied=self.tau_applied[r],
            tau_friction=self.tau_friction[r],
            tau_ext=self.tau_ext[r],
            wrench=self.wrench[r],
            contact_force_on_environment=self.contact_force[r],
            sensor=self.sensor[r],
            q_measured=self.q_measured[r],
            qd_measured=self.qd_measured[r],
            stuck=self.stuck[r] != 0.0,
            work_actuator=work_act,
            work_friction=self.work_friction[r],
            work_external=self.work_external[r],
            diverged=d is not None,
            diverged_at=None if d is None else d[0],
            divergence="" if d is None else d[1],
            diverged_q=None if d is None else d[2],
            diverged_qd=None if d is None else d[3],
            logs=logs,
            info=info,
            reference=SampledReference.of(t, refs, model.n) if given else None,
            limits=limits,
            contact_position=self.contact_position[r],
            plant=model,
            _energy=None if energy else np.full(rows, np.nan),
            _energy_of=partial(energies, dyn) if energy else None,
            # the whole record is the result's (nothing writes into it after the run); a shorter run's rows are
            # copied, so that the result does not keep the rest
            _copy=rows < self.samples,
        )


def energies(dyn: Dynamics, q: FloatArray, qd: FloatArray) -> FloatArray:
    """E = ½q̇ᵀM(q)q̇ + U(q) at every sample [J]. With Pinocchio, on a workspace of its own (it may run later,
    when the result's energy is first read), and with its O(n) kinetic energy where the model has no
    armature (Pinocchio does not count armature consistently there); ½q̇ᵀMq̇ from CRBA otherwise."""
    pm = getattr(dyn, "pin_model", None)
    if pm is None:
        k = dyn.kernel
        return np.array([k.kinetic(p, v) + k.potential(p) for p, v in zip(q, qd, strict=True)])
    import pinocchio as pin

    pd = pm.createData()
    pot = pin.computePotentialEnergy
    if not np.asarray(pm.armature).any():
        kin = pin.computeKineticEnergy
        return np.array([kin(pm, pd, p, v) + pot(pm, pd, p) for p, v in zip(q, qd, strict=True)])
    crba = pin.crba
    return np.array([0.5 * float(v @ crba(pm, pd, p) @ v) + pot(pm, pd, p) for p, v in zip(q, qd, strict=True)])
