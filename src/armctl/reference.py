"""Deprecated alias of :mod:`armctl.references`, where :class:`Reference` now lives with its generators.

``from armctl.references import Reference`` still works in this release and warns; write
``from armctl import Reference`` or ``from armctl.references import Reference``.
"""

import warnings

from armctl.references.reference import Reference

__all__ = ["Reference"]

warnings.warn(
    "armctl.reference is deprecated and will be removed in the next release: import Reference from armctl or "
    "armctl.references",
    DeprecationWarning,
    stacklevel=2,
)
