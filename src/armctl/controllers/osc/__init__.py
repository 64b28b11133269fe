"""Operational-space control as a QP (DAQP, then proxsuite), with contacts, limits and strict priorities:
``from armctl.controllers.osc import OperationalSpaceQP, FramePoseTask, PostureTask``.
"""

# The parts, for a reader of the source: ``state`` (model terms of one step), ``tasks/`` (error + Jacobian),
# ``limits/`` (bounds on q̈ or τ), ``contact`` (force variables, contact rows, friction cones), ``build`` (the QP),
# ``problem`` (the inspectable QP), ``reduced`` (the same QP on q̈ alone), ``contact_qp`` and ``contact_public``
# (with contacts, on [q̈; f], and back), ``eliminated`` (what those two share: a step from generated data or
# NumPy), ``generated`` and ``generated_contact`` (their data as generated code, ``compile``; ``generated_data``
# what they share), ``scale`` (out-of-scale task rows refused), ``solve`` (proxsuite / qpsolvers), ``daqp_solver``
# (DAQP from an active set, the chain's first stage), ``active_set`` (a dual active-set solver in NumPy),
# ``optimality`` (the KKT check), ``chain`` (verified optimum, with fallbacks), ``diagnose`` (conflicting rows),
# ``hierarchy`` (cascaded priorities), ``controller`` (the controller), ``closed_form`` (Khatib's baseline),
# ``run_report`` (their end-of-run summary), ``docstrings`` (docstring sections written once).

from armctl.controllers.osc.active_set import DualActiveSetSolver
from armctl.controllers.osc.build import QPBuilder, StepQP
from armctl.controllers.osc.chain import QPFailure, SolverChain
from armctl.controllers.osc.closed_form import ClosedFormOSC
from armctl.controllers.osc.contact import Contact
from armctl.controllers.osc.controller import OperationalSpaceQP, default_limits
from armctl.controllers.osc.daqp_solver import DaqpSolver
from armctl.controllers.osc.diagnose import conflicting_rows
from armctl.controllers.osc.hierarchy import OSCSolution
from armctl.controllers.osc.limits import AccelerationLimit, JointPositionLimit, JointVelocityLimit, Limit, TorqueLimit
from armctl.controllers.osc.problem import QPArrays, QPProblem
from armctl.controllers.osc.solve import ProxQPSolver, QPSolution, QPSolver, QpsolversSolver
from armctl.controllers.osc.tasks import (
    ContactForceTask,
    FrameOrientationTask,
    FramePoseTask,
    FramePositionTask,
    MotionTask,
    PostureTask,
    Task,
)

__all__ = [
    "AccelerationLimit",
    "ClosedFormOSC",
    "Contact",
    "ContactForceTask",
    "DaqpSolver",
    "DualActiveSetSolver",
    "FrameOrientationTask",
    "FramePoseTask",
    "FramePositionTask",
    "JointPositionLimit",
    "JointVelocityLimit",
    "Limit",
    "MotionTask",
    "OSCSolution",
    "OperationalSpaceQP",
    "PostureTask",
    "ProxQPSolver",
    "QPArrays",
    "QPBuilder",
    "QPFailure",
    "QPProblem",
    "QPSolution",
    "QPSolver",
    "QpsolversSolver",
    "SolverChain",
    "StepQP",
    "Task",
    "TorqueLimit",
    "conflicting_rows",
    "default_limits",
]
