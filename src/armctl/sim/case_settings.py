"""How a sweep case's settings are shown: in the table of :meth:`SweepResult.to_dataframe
<armctl.sim.SweepResult.to_dataframe>` and in a sweep store's manifest (:mod:`armctl.sim.sweep_store`).

Numbers, strings and booleans appear as they are; other objects by their ``name`` (a RobotModel, a scene), a
function or class by its qualified name, a small array as a list, an object without a repr of its own by its
class's name, anything else by its repr (the first :data:`SHOWN` characters).
"""

from __future__ import annotations

import numbers
from typing import Any

import numpy as np

SHOWN = 120  # characters of a setting's repr kept in a table


def is_scalar(x: Any) -> bool:
    """True for None, a string, a boolean or a number (NumPy's scalars included): what a table cell holds as it is."""
    return x is None or isinstance(x, str | bool | numbers.Number | np.generic)


def plain(x: Any) -> Any:
    """A NumPy scalar as the Python number it holds; anything else unchanged."""
    return x.item() if isinstance(x, np.generic) else x


def setting(value: Any) -> Any:
    """How a case's setting appears in a table: a scalar as it is; an object by its ``name`` (a RobotModel, a
    scene), a function or class by its qualified name, a small array as a list, an object without a repr of its
    own by its class's name; anything else by its repr (the first :data:`SHOWN` characters)."""
    if is_scalar(value):
        return plain(value)
    name = getattr(value, "name", None)
    if isinstance(name, str) and name:
        return name
    if isinstance(value, np.ndarray):
        return repr(value.tolist()) if value.size <= 12 else f"ndarray{value.shape}"
    if callable(value) and hasattr(value, "__qualname__"):
        return f"{getattr(value, '__module__', '')}.{value.__qualname__}".lstrip(".")
    if type(value).__repr__ is object.__repr__:  # "<… object at 0x…>": only its class says anything
        return type(value).__qualname__
    text = repr(value)
    return text if len(text) <= SHOWN else text[: SHOWN - 1] + "…"
