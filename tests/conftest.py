"""Shared fixtures: built-in models and Dynamics objects, built once per test run (they are immutable)."""

from __future__ import annotations

import os
import tempfile
from functools import cache

# Small SVD/QR calls run ~20× slower with a multi-threaded BLAS on a loaded 2-core machine (seen here): one
# thread, set before NumPy loads
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import pytest  # noqa: E402

import armctl  # noqa: E402

# compiled CasADi code is cached across runs (CI keeps ~/.cache between steps of one run at least)
os.environ.setdefault("ARMCTL_CACHE", os.path.join(tempfile.gettempdir(), "armctl-cache"))

MODEL_NAMES = ("pendulum", "planar_2r", "planar_3r", "puma560", "panda", "ur5")


@cache
def model(name: str) -> armctl.RobotModel:
    return getattr(armctl.models, name)()


@cache
def dynamics(name: str, backend: str = "pinocchio", **options: object) -> armctl.Dynamics:
    return armctl.Dynamics(model(name), backend=backend, **options)


@pytest.fixture(params=MODEL_NAMES)
def model_name(request: pytest.FixtureRequest) -> str:
    return str(request.param)
