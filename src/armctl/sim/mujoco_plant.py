"""`MujocoPlant`: a MuJoCo scene as the plant of ``armctl.simulate(..., engine="mujoco")``, and what the engine reads
back from MuJoCo at a sample (friction, external torques, contact forces).

The plant is MuJoCo's: its arm is the serial chain of the scene (:func:`armctl.model.mjcf.read_chain`), its
contacts, joint limits, tendons and equality constraints are the scene's. Built from an armctl model
(:meth:`MujocoPlant.from_model`), the scene is :meth:`~armctl.RobotModel.to_mjcf` without contacts and without
limit stops, the plant armctl's own simulator integrates.

MuJoCo's equations of motion for the arm's joints,

    M q̈ + c = qfrc_applied + qfrc_passive + qfrc_constraint,

are split into SimResult's terms ``M q̈ + C q̇ + g = tau_applied − tau_friction − tau_ext``:

    tau_friction = −(qfrc_damper + the frictionloss rows of J_efcᵀ f_efc)     (damping F_v and frictionloss F_c)
    tau_ext      = −(every other passive and constraint force on the arm's joints)  (contacts, limits, springs, …)
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from armctl._checks import FloatArray
from armctl._mujoco import require_mujoco
from armctl.errors import InvalidParameterError, ModelLoadError
from armctl.model.mjcf import compile_mjcf
from armctl.model.mjcf_chain import MjcfChain, read_chain
from armctl.model.robot import RobotModel
from armctl.sim.recorder import Recorder

if TYPE_CHECKING:
    from armctl.dynamics.base import Dynamics


class MujocoPlant:
    """A MuJoCo scene holding an arm, and the armctl model of that arm: the model gives the plant's effort limits
    (saturation), tool frame (wrench, disturbances) and energies; MuJoCo integrates the scene.

    Parameters
    ----------
    scene : str or path-like
        An MJCF file path or text whose arm is the serial chain below the body ``base``, in a scene of its own
        (floors, tables, objects, mesh contacts).
    model : RobotModel, optional
        The armctl model of that arm (None: :meth:`~armctl.RobotModel.from_mjcf` of the scene, with
        ``tool_frame``); its joints must be the chain's, by name and in order.
    base : str, optional
        The body the arm starts from (None: the one subtree of the world with joints).
    tool_frame : str, optional
        The tool frame of the model read from the scene.

    Raises
    ------
    ModelLoadError
        The scene does not compile, or its chain and ``model`` differ.
    """

    def __init__(
        self,
        scene: str | os.PathLike[str],
        model: RobotModel | None = None,
        *,
        base: str | None = None,
        tool_frame: str | None = None,
    ) -> None:
        if not isinstance(scene, str | os.PathLike):
            raise InvalidParameterError(
                f"scene must be an MJCF file path or text, got {type(scene).__name__}", value=scene
            )
        self.scene = os.fspath(scene)
        self.base = base
        self.limits = True  # the scene's joint limits act
        _, chain = self.compile()
        if model is None:
            model = RobotModel.from_mjcf(self.scene, tool_frame=tool_frame, base=base)
        elif not isinstance(model, RobotModel):
            raise InvalidParameterError(f"model must be an armctl.RobotModel, got {type(model).__name__}", value=model)
        elif tool_frame is not None:
            raise InvalidParameterError("give tool_frame with the model (RobotModel.tool_frame), not here", value=model)
        self.model = model
        self._check(chain)

    @classmethod
    def from_model(cls, model: RobotModel) -> MujocoPlant:
        """The plant armctl's own simulator integrates for a model, in MuJoCo: ``model.to_mjcf`` with simple shapes,
        no contacts and no joint-limit stops.

        Parameters
        ----------
        model : RobotModel
            The arm.

        Returns
        -------
        MujocoPlant
        """
        self = cls.__new__(cls)
        self.scene, self.base, self.limits, self.model = model.to_mjcf(meshes=False, contacts=False), None, False, model
        self._check(self.compile()[1])
        return self

    def compile(self) -> tuple[Any, MjcfChain]:
        """A fresh ``mjModel`` of the scene (each run sets its own step and integrator) and its arm.

        Returns
        -------
        tuple of (mujoco.MjModel, MjcfChain)
        """
        m, _ = compile_mjcf(self.scene, "simulate(..., engine='mujoco')")
        if not self.limits:  # the plant of armctl's own simulator: no limit stops, no contacts
            m.jnt_limited[:] = 0
            m.opt.disableflags |= int(require_mujoco("MuJoCo").mjtDisableBit.mjDSBL_CONTACT)
        return m, read_chain(m, self.base, "the MuJoCo scene")

    def _check(self, chain: MjcfChain) -> None:
        names = tuple(j.name for j in chain.joints)
        if names != self.model.joint_names:
            raise ModelLoadError(
                f"the arm of the MuJoCo scene has the joints {names}; the model {self.model.name!r} has "
                f"{self.model.joint_names}: they must be the same, in the same order",
                value=names,
            )

    def __repr__(self) -> str:
        what = "from its model" if not self.limits else "from a scene"
        return f"MujocoPlant({self.model.name!r}, {what}, {self.model.n} joints)"


@dataclass
class Readout:
    """Indices of the arm in MuJoCo's arrays, and the reads of one sample (see the module for the split)."""

    mj: Any
    m: Any
    qadr: Any  # qpos address of each arm joint
    vadr: Any  # dof address of each arm joint
    body_joint: Any  # (nbody,) armctl joint (1-based) whose link a body belongs to; 0: not a moving arm body

    @classmethod
    def of(cls, mj: Any, m: Any, chain: MjcfChain) -> Readout:
        body_joint = np.zeros(m.nbody, dtype=int)
        for b, i in chain.body_joint.items():
            body_joint[b] = i
        ids = list(chain.joint_ids)
        return cls(mj, m, np.array(m.jnt_qposadr[ids]), np.array(m.jnt_dofadr[ids]), body_joint)

    def __post_init__(self) -> None:
        self._friction_dof = int(self.mj.mjtConstraint.mjCNSTR_FRICTION_DOF)
        self._fl = np.zeros(self.m.nv)
        #: below this the frictionloss force is inside its bound (1 − 10⁻⁹ of it)
        self._bound = (1.0 - 1e-9) * np.array(self.m.dof_frictionloss[self.vadr])

    def _frictionloss(self, d: Any) -> None:
        """The frictionloss force of every dof into ``_fl`` (MuJoCo puts the friction rows after the equality rows,
        one row a dof)."""
        fl = self._fl
        fl[:] = 0.0
        nf = d.nf
        if nf:
            rows = slice(d.ne, d.ne + nf)
            sel = d.efc_type[rows] == self._friction_dof
            fl[d.efc_id[rows][sel]] = d.efc_force[rows][sel]

    def torques(self, d: Any) -> tuple[FloatArray, FloatArray]:
        """(tau_friction, tau_ext) of the arm's joints at the state of the last ``mj_forward``."""
        self._frictionloss(d)
        v = self.vadr
        damper, fl = d.qfrc_damper[v], self._fl[v]
        other = d.qfrc_passive[v] - damper + d.qfrc_constraint[v] - fl
        return -(damper + fl), -other

    def stuck(self) -> Any:
        """Arm joints with frictionloss whose friction force was inside its bound at the last :meth:`torques`:
        MuJoCo's soft version of sticking (the joint may still creep)."""
        return np.abs(self._fl[self.vadr]) < self._bound

    def contacts(self, d: Any) -> tuple[FloatArray, FloatArray, FloatArray, Any]:
        """Every contact between a moving link of the arm and the rest of the scene: (h (C, 3) the force the arm
        exerts [N], its moment about the contact point (C, 3) [N·m] (torsional and rolling friction), position
        (C, 3) [m], 1-based joint whose link touches (C,)). Contacts of the arm with itself are left out."""
        mj, m = self.mj, self.m
        con = d.contact
        count = d.ncon
        if count == 0:
            z = np.zeros((0, 3))
            return z, z, z, np.zeros(0, dtype=int)
        geoms = np.array(con.geom[:count]).reshape(count, 2)
        bodies = m.geom_bodyid[geoms]
        links = self.body_joint[bodies]
        keep = (np.array(con.efc_address[:count]) >= 0) & ((links[:, 0] > 0) != (links[:, 1] > 0))
        f6 = np.zeros(6)
        hs, ms, ps, js = [], [], [], []
        frames = np.array(con.frame[:count]).reshape(count, 3, 3)
        positions = np.array(con.pos[:count]).reshape(count, 3)
        for c in np.flatnonzero(keep):
            mj.mj_contactForce(m, d, int(c), f6)
            # in the contact frame (normal from geom 0 to geom 1): what geom 0 exerts on geom 1
            sign = 1.0 if links[c, 0] > 0 else -1.0
            hs.append(sign * frames[c].T @ f6[:3])
            ms.append(sign * frames[c].T @ f6[3:])
            ps.append(positions[c])
            js.append(max(links[c]))
        if not hs:
            z = np.zeros((0, 3))
            return z, z, z, np.zeros(0, dtype=int)
        return np.array(hs), np.array(ms), np.array(ps), np.array(js)

    def record(self, rec: Recorder, d: Any, dyn: Dynamics, k: int, q: Any, tf: Any, te: Any, hd: Any) -> None:
        """Friction, external torques, contacts, wrench and sensors at sample k into ``rec`` (after the sample's
        forward dynamics; tf, te: :meth:`torques`; hd: the disturbance wrench or None)."""
        rec.tau_friction[k] = tf
        rec.stuck[k] = self.stuck()
        hs, moments, ps, links = self.contacts(d)
        f, mom = np.zeros(3), np.zeros(3)
        if len(hs):
            tool = dyn.frame_pose(q, None)[:3, 3]
            np.add.at(rec.contact_force[k], links - 1, hs)
            f += hs.sum(axis=0)
            r = ps - tool
            mom += moments.sum(axis=0)  # r × h of every contact at once, its components written out
            mom += (r[:, [1, 2, 0]] * hs[:, [2, 0, 1]] - r[:, [2, 0, 1]] * hs[:, [1, 2, 0]]).sum(axis=0)
        for i, sensor in enumerate(rec.sensors):
            rec.sensor[k, i] = sensor.reading(dyn, q, hs, ps, links)
        if hd is not None:
            f += hd[:3]
            mom += hd[3:]
            te = te + dyn.jacobian(q).T @ hd
        rec.tau_ext[k] = te
        rec.wrench[k, :3], rec.wrench[k, 3:] = f, mom


def integrator_code(mj: Any, name: str) -> int:
    """MuJoCo's code of an integrator name (:data:`MUJOCO_INTEGRATORS`)."""
    return int(getattr(mj.mjtIntegrator, MUJOCO_INTEGRATORS[name]))


#: the integrators of ``engine="mujoco"``: armctl's name → MuJoCo's (``option/integrator``). "euler" is
#: semi-implicit Euler (q̇₁ = q̇ + h q̈, q₁ = q + h q̇₁, armctl's "euler"), joint damping implicit; "implicit" and
#: "implicitfast" are implicit in velocity; "discrete" solves the constraints in discrete time (MuJoCo ≥ 4).
MUJOCO_INTEGRATORS = {
    "rk4": "mjINT_RK4",
    "euler": "mjINT_EULER",
    "implicit": "mjINT_IMPLICIT",
    "implicitfast": "mjINT_IMPLICITFAST",
    "discrete": "mjINT_DISCRETE",
}


def available_integrators() -> tuple[str, ...]:
    """The names of :data:`MUJOCO_INTEGRATORS` the installed MuJoCo has."""
    mj = require_mujoco("the MuJoCo integrators")
    return tuple(k for k, v in MUJOCO_INTEGRATORS.items() if hasattr(mj.mjtIntegrator, v))
