"""Tuning on python-control: linear models of the error dynamics, gains, sampled-data margins; bounds on the
dynamic model over the joint ranges and the stability conditions they give; and :func:`sweep` (the
simulator's, :func:`armctl.sim.sweep`, here too) to run many closed loops for a gain study."""

from armctl.sim.sweep import sweep
from armctl.tuning.bounds import Bound, ModelBounds, model_bounds
from armctl.tuning.linear import closed_loop_poles, linearize, lqr_gains, pd_from_bandwidth
from armctl.tuning.sampled import SampledDataAnalysis, sampled_pd_loop, spectral_radius

__all__ = [
    "Bound",
    "ModelBounds",
    "SampledDataAnalysis",
    "closed_loop_poles",
    "linearize",
    "lqr_gains",
    "model_bounds",
    "pd_from_bandwidth",
    "sampled_pd_loop",
    "spectral_radius",
    "sweep",
]
