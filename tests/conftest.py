"""Fixtures shared by every test: one BLAS thread, a compiled-code cache, and the built-in arms by name (the
helpers that build them, once per test run, are in :mod:`tests.helpers.arms`)."""

from __future__ import annotations

import os
import tempfile

# Small SVD/QR calls run ~20× slower with a multi-threaded BLAS on a loaded 2-core machine (seen here): one
# thread, set before NumPy loads
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import pytest  # noqa: E402

from tests.helpers.arms import MODEL_NAMES, dynamics, model  # noqa: E402

# compiled CasADi code is cached across runs (CI keeps ~/.cache between steps of one run at least)
os.environ.setdefault("ARMCTL_CACHE", os.path.join(tempfile.gettempdir(), "armctl-cache"))


@pytest.fixture(params=MODEL_NAMES)
def model_name(request: pytest.FixtureRequest) -> str:
    return str(request.param)


__all__ = ["MODEL_NAMES", "dynamics", "model", "model_name"]
