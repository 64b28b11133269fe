"""Tuning on python-control: linear models of the error dynamics, gains, sampled-data margins (of joint loops, and of
force control and impedance against a compliant environment: :mod:`armctl.tuning.force_stability`,
:mod:`armctl.tuning.impedance_stability`); bounds on the dynamic model over the joint ranges (:func:`model_bounds`)
and the textbook stability conditions they give (:mod:`armctl.tuning.conditions`); and the tuned presets the scenes
read (:mod:`armctl.tuning.presets`).

Many closed loops for a gain study run through :func:`armctl.sim.sweep` (``armctl.tuning.sweep`` is a deprecated
alias of it).
"""

import warnings
from typing import Any

from armctl.tuning.bounds import Bound, ModelBounds, model_bounds
from armctl.tuning.conditions import (
    computed_torque_condition,
    pd_desired_gravity_condition,
    pid_condition,
    sampled_data_condition,
)
from armctl.tuning.force_stability import critical_force_gain, force_loop_matrix, force_loop_radius, normal_inertia
from armctl.tuning.impedance_stability import critical_environment_stiffness, impedance_loop_matrix, impedance_model
from armctl.tuning.inertia_estimate import robust_inertia_estimate
from armctl.tuning.linear import closed_loop_poles, linearize, lqr_gains, pd_from_bandwidth
from armctl.tuning.sampled import SampledDataAnalysis, sampled_pd_loop, spectral_radius
from armctl.tuning.verdict import Verdict

__all__ = [
    "Bound",
    "ModelBounds",
    "SampledDataAnalysis",
    "Verdict",
    "closed_loop_poles",
    "computed_torque_condition",
    "critical_environment_stiffness",
    "critical_force_gain",
    "force_loop_matrix",
    "force_loop_radius",
    "impedance_loop_matrix",
    "impedance_model",
    "linearize",
    "lqr_gains",
    "model_bounds",
    "normal_inertia",
    "pd_desired_gravity_condition",
    "pd_from_bandwidth",
    "pid_condition",
    "robust_inertia_estimate",
    "sampled_data_condition",
    "sampled_pd_loop",
    "spectral_radius",
]


def __getattr__(name: str) -> Any:
    if name == "sweep":  # deprecated alias: one public home, armctl.sim.sweep
        warnings.warn(
            "armctl.tuning.sweep is deprecated and will be removed in the next release: use armctl.sim.sweep",
            DeprecationWarning,
            stacklevel=2,
        )
        from armctl.sim.sweep import sweep

        return sweep
    raise AttributeError(f"module 'armctl.tuning' has no attribute {name!r}")
