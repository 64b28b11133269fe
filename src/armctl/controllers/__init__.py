"""Controllers: ``tau = controller(t, q, qd, ref)``.

=================================  ====================================================================================
:class:`PDGravity`                 set-point PD with gravity compensation (Takegaki–Arimoto)
:class:`PDDesiredGravity`          set-point PD with gravity compensated at the set-point, g(q_d)
:class:`ComputedTorque`            inverse dynamics + PD (+ integral)
:class:`PassivityBased`            Slotine–Li: M q̈_r + C q̇_r + g − K_D s
:class:`Adaptive`                  Slotine–Li adaptive law on the passivity regressor, with projection, σ-modification,
                                   dead-zone and composite adaptation
:class:`OperationalSpaceQP`        operational-space control as a QP (proxsuite): tasks, priorities, limits, contacts;
                                   see :mod:`armctl.controllers.osc`
:class:`ClosedFormOSC`             Khatib's closed-form operational-space control (the QP's baseline)
:class:`CartesianImpedance`        a frame as a mass–spring–damper about its target, null-space joint stiffness,
                                   optional inertia shaping (see :mod:`armctl.controllers.interaction`)
:class:`JointImpedance`            every joint a spring and damper about the joint reference
:class:`Admittance`                a compliant frame driven by the measured wrench, tracked by an inner motion loop
:class:`ForceControl`              force control (PI on the force error) with an inner motion loop
:class:`ParallelForcePosition`     parallel force/position control, integral action on the force error
:class:`MomentumObserver`          the generalized-momentum observer of the external joint torques: collision
                                   detection and isolation, the contact wrench without a force sensor
:class:`CollisionReaction`         a controller that reacts to the observer's detection (gravity compensation, reflex)
=================================  ====================================================================================

Write your own by subclassing :class:`Controller` and implementing ``compute(t, q, qd, ref)``; a controller that
reads a force sensor or the applied torques declares it in ``reads`` and finds them in ``self.measurement``
(:class:`Measurement`).
"""

from armctl.controllers.adaptive import Adaptive
from armctl.controllers.base import Controller
from armctl.controllers.collision_reaction import CollisionReaction
from armctl.controllers.computed_torque import ComputedTorque
from armctl.controllers.interaction import (
    Admittance,
    CartesianImpedance,
    ForceControl,
    JointImpedance,
    ParallelForcePosition,
)
from armctl.controllers.measurement import Measurement
from armctl.controllers.momentum_observer import Collision, MomentumObserver
from armctl.controllers.osc import ClosedFormOSC, OperationalSpaceQP
from armctl.controllers.passivity import PassivityBased
from armctl.controllers.pd import PDGravity
from armctl.controllers.pd_desired_gravity import PDDesiredGravity

__all__ = [
    "Adaptive",
    "Admittance",
    "CartesianImpedance",
    "ClosedFormOSC",
    "Collision",
    "CollisionReaction",
    "ComputedTorque",
    "Controller",
    "ForceControl",
    "JointImpedance",
    "Measurement",
    "MomentumObserver",
    "OperationalSpaceQP",
    "PDDesiredGravity",
    "PDGravity",
    "ParallelForcePosition",
    "PassivityBased",
]
