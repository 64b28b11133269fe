"""Interaction control: controllers that shape how the arm responds to the wrench its environment exerts, or
that regulate that wrench.

=================================  ==============================================================================
:class:`CartesianImpedance`        a frame as a mass–spring–damper about its target, null-space joint stiffness
:class:`JointImpedance`            every joint a spring and damper about the joint reference
:class:`Admittance`                a compliant frame M_d ẍ_c + D_d ẋ_c + K_d (x_c − x_d) = −h, tracked by a stiff
                                   inner motion loop
:class:`ForceControl`              force regulation along chosen directions (PI on the force error, inner motion
                                   loop), position along the others
:class:`ParallelForcePosition`     a force loop with integral action in parallel with a position loop
=================================  ==============================================================================

h is the wrench [f; m] the arm exerts on its environment (the sign of :meth:`armctl.Dynamics.inverse_dynamics`'
``wrench`` and of a :class:`~armctl.sim.ForceSensor`'s reading), in world axes at the controlled frame.
"""

from armctl.controllers.interaction.admittance import Admittance
from armctl.controllers.interaction.cartesian_impedance import CartesianImpedance
from armctl.controllers.interaction.force_control import ForceControl
from armctl.controllers.interaction.joint_impedance import JointImpedance
from armctl.controllers.interaction.parallel import ParallelForcePosition

__all__ = ["Admittance", "CartesianImpedance", "ForceControl", "JointImpedance", "ParallelForcePosition"]
