"""Fixtures of the operational-space QP tests: the Panda's Dynamics and a seeded generator (the helpers that
build them are in :mod:`tests.controllers.osc.helpers`)."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from tests.controllers.osc.helpers import Q_HOME, panda_dynamics

__all__ = ["Q_HOME", "panda", "panda_dynamics", "rng"]  # Q_HOME, panda_dynamics: also importable from here


@pytest.fixture
def panda() -> armctl.Dynamics:
    return panda_dynamics()


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(5)
