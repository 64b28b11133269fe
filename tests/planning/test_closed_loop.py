"""Closed loop: the panda, with joint friction, tracks its time-optimal trajectory under computed-torque control
in the simulator (stick-slip friction); planned with a 10 % torque margin, the commanded torques stay within the
effort limits.

The gains are per joint, higher on the light wrist: computed torque scales its PD by M(q), so on a joint with
little inertia behind it, stiction (which the controller cannot compensate while the joint is stuck, q̇ = 0)
needs a large error to break; ω_n = 30 rad/s on the heavy joints and 60–100 rad/s on the wrist keep the error
near a milliradian at a 1 kHz control rate. The path keeps panda_joint2 bent (q[1] < 0), away from
panda_joint1 and panda_joint3 being coaxial, where M is nearly singular in their difference and the same effect
holds both joints stuck.
"""

from __future__ import annotations

import math

import numpy as np

from armctl.controllers import ComputedTorque
from armctl.planning import time_optimal
from armctl.sim import simulate
from tests.planning.helpers import panda

WAYPOINTS = np.array(
    [
        [0.0, -0.6, 0.0, -2.2, 0.0, 1.6, 0.8],
        [0.8, -0.3, 0.4, -1.8, 0.5, 1.9, 0.2],
        [1.2, -0.9, -0.3, -2.4, -0.4, 1.3, 1.2],
        [0.3, -0.5, 0.5, -1.5, 0.3, 2.2, 0.0],
    ]
)


def test_panda_tracks_the_time_optimal_trajectory_within_limits() -> None:
    dyn = panda(friction=True)  # the planner's, the controller's and the plant's model: the same arm
    limit = dyn.model.effort_limit
    traj = time_optimal(dyn, WAYPOINTS, vel_limit="model", torque_limit="model", torque_margin=0.1)
    assert traj.check.ok(1e-2)
    control_dt = 1e-3
    duration = control_dt * math.ceil((traj.duration + 0.2) / control_dt)
    wn = np.array([30.0, 30.0, 30.0, 30.0, 60.0, 60.0, 100.0])
    ctrl = ComputedTorque(dyn, kp=wn**2, kd=2 * wn)
    res = simulate(dyn, ctrl, traj, duration, control_dt=control_dt)
    assert not res.diverged
    err = np.abs(res.q - traj.sample(res.t).q).max()
    assert err < 5e-3, f"tracking error {err:.3g} rad"
    used = np.abs(res.tau) / limit  # the controller's command, before any saturation
    assert used.max() <= 1.0, f"commanded torque reaches {100 * used.max():.1f} % of a limit"
    assert used.max() > 0.85  # and the time-optimal motion does use the torque it was given
