"""Tuning on python-control: linear models of the error dynamics, gains, sampled-data margins."""

from armctl.tuning.linear import closed_loop_poles, linearize, lqr_gains, pd_from_bandwidth
from armctl.tuning.sampled import SampledDataAnalysis, sampled_pd_loop, spectral_radius

__all__ = ["SampledDataAnalysis", "closed_loop_poles", "linearize", "lqr_gains", "pd_from_bandwidth",
           "sampled_pd_loop", "spectral_radius"]
