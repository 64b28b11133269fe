"""armctl: model-based control and planning of robot manipulators.

The spine is the Lagrange model M(q)q̈ + C(q,q̇)q̇ + g(q) = τ − F_v q̇ − F_c sgn(q̇) − J(q)ᵀh_e:
:class:`RobotModel` describes an arm, :class:`Dynamics` evaluates it.
"""

import importlib
from typing import Any

from armctl import controllers, errors, models, planning, references
from armctl.dynamics import Dynamics
from armctl.errors import ArmctlError
from armctl.model import RobotModel
from armctl.references import Reference
from armctl.sim import SimResult, simulate

__version__ = "0.1.0"
__all__ = [
    "ArmctlError",
    "Dynamics",
    "Reference",
    "RobotModel",
    "SimResult",
    "bench",
    "controllers",
    "errors",
    "models",
    "planning",
    "references",
    "scenes",
    "simulate",
    "tuning",
]

# subpackages imported on first use (PEP 562), so that ``import armctl`` does not pay for python-control,
# matplotlib or the scenes' models: ``armctl.tuning.linearize(...)`` works without importing armctl.tuning
_LAZY = ("bench", "scenes", "tuning")


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return importlib.import_module(f"armctl.{name}")
    raise AttributeError(f"module 'armctl' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
