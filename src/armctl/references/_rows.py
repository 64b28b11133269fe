"""The vectors a generator is built from: real, finite, of one length."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, real_array, vector
from armctl.errors import ShapeError


def row(x: ArrayLike, name: str, n: int | None = None, *, broadcast: bool = False) -> FloatArray:
    """``x`` as a finite vector of ``n`` entries (``n`` None: any length >= 1; a scalar is one entry or, with
    ``broadcast``, the value of every entry, as is a one-entry vector)."""
    a = real_array(x, name)
    if (a.ndim == 0 and (n is None or n == 1)) or (broadcast and a.shape in ((), (1,))):
        a = np.full(1 if n is None else n, a.item())
    if n is None:
        if a.ndim != 1 or not a.shape[0]:
            raise ShapeError(
                f"{name} must be a vector of at least one joint value, got shape {a.shape}: {x!r}", value=x
            )
        n = a.shape[0]
    return vector(a, n, name)
