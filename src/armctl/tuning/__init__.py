"""Tuning on python-control: linear models of the error dynamics, gains, sampled-data margins."""

from armctl.tuning.sampled import SampledDataAnalysis, sampled_pd_loop

__all__ = ["SampledDataAnalysis", "sampled_pd_loop"]
