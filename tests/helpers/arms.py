"""The built-in arms and their Dynamics, built once per test run (they are immutable)."""

from __future__ import annotations

from functools import cache

import armctl

MODEL_NAMES = ("pendulum", "planar_2r", "planar_3r", "puma560", "panda", "ur5")


@cache
def model(name: str) -> armctl.RobotModel:
    return getattr(armctl.models, name)()  # type: ignore[no-any-return]


@cache
def dynamics(name: str, backend: str = "pinocchio", **options: object) -> armctl.Dynamics:
    return armctl.Dynamics(model(name), backend=backend, **options)  # type: ignore[arg-type]
