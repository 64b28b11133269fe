"""Joint-space references: :class:`Reference`, the desired (q, q̇, q̈) at one instant, and the generators,
callables ``t -> Reference`` for closed-loop runs and tuning:

* :class:`Quintic` — minimum-jerk point-to-point move (zero velocity and acceleration at both ends);
* :class:`Sinusoid` — q_d = c + a sin(2π f t + φ) per joint;
* :class:`WaypointSpline` — a cubic spline through timed waypoints (zero end velocities by default).

Time-optimal references along geometric paths come from :mod:`armctl.planning`. ``Reference`` is also
``armctl.Reference``.
"""

from armctl.references.quintic import Quintic
from armctl.references.reference import Reference
from armctl.references.sinusoid import Sinusoid
from armctl.references.spline import BC_TYPES as BC_TYPES  # the end conditions WaypointSpline names
from armctl.references.spline import WaypointSpline

__all__ = ["Quintic", "Reference", "Sinusoid", "WaypointSpline"]
