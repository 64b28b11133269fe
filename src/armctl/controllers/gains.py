"""Gains set all at once, with what a law derives from them recomputed directly: :class:`GainSet`.

A controller (or an OSC task) lists its gains in :attr:`GainSet.gain_names`. Its constructor sets them together,
``self.set_gains(kp=..., kd=...)``; reading ``ctrl.kp`` gives the checked matrix (read-only), and assigning it,
``ctrl.kp = 400.0``, is ``ctrl.set_gains(kp=400.0)``. :meth:`GainSet.set_gains` checks each value (a scalar,
an (n,) diagonal or an n×n symmetric positive definite matrix), keeps it with its cheap form
(:func:`~armctl._checks.compact_gain`, in ``_<name>``), and then calls the owner's ``_derive()`` once,
every gain being set: the matrices a law precomputes from its gains are made there, so a gain reassigned
between calls takes effect at the next one. Nothing calls into a half-built object.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from armctl._checks import FloatArray, compact_gain, gain_matrix, readonly


def gain(name: str, doc: str) -> Any:
    """The property ``name`` of a :class:`GainSet`: reads the checked matrix, assigns through
    :meth:`GainSet.set_gains` (``doc``: its docstring)."""

    def get(self: GainSet) -> FloatArray | None:
        return getattr(self, f"_{name}_matrix")

    def set_(self: GainSet, value: Any) -> None:
        self.set_gains(**{name: value})

    return property(get, set_, doc=doc)


class GainSet:
    """Mixin of the objects with gains (see the module)."""

    #: gain name → whether it may be None (no such term)
    gain_names: ClassVar[dict[str, bool]] = {}
    n: int  # the number of joints (set by the controller or task that owns the gains)

    def _gain_spec(self, name: str) -> tuple[int, str]:
        """(rows, label): the number of rows of the gain ``name`` (n, the joints, unless the owner says otherwise)
        and how errors name it."""
        return int(self.n), name

    def set_gains(self, **gains: Any) -> None:
        """Check and set the gains given (name → a scalar, an (n,) diagonal or an n×n symmetric positive definite
        matrix, or None for an optional one), then recompute what the law derives from them (``_derive``).

        Parameters
        ----------
        **gains
            The gains to set, by name (see :attr:`gain_names`).

        Raises
        ------
        InvalidParameterError, ShapeError, NonFiniteError
            A gain that is not symmetric positive definite, of the wrong size or not finite; a name that is no
            gain of this object.
        """
        checked: dict[str, FloatArray | None] = {}
        for name, value in gains.items():
            if name not in self.gain_names:
                from armctl.errors import UnknownNameError

                raise UnknownNameError("gain", name, tuple(self.gain_names))
            if value is None and self.gain_names[name]:
                checked[name] = None
            else:  # a read-only copy: the derived forms follow assignments only
                rows, label = self._gain_spec(name)
                checked[name] = readonly(np.array(gain_matrix(value, rows, label)))
        for name, full in checked.items():  # all checked before any is set
            setattr(self, f"_{name}_matrix", full)
            setattr(self, f"_{name}", None if full is None else compact_gain(full))
        self._derive()

    def _derive(self) -> None:
        """Recompute what the law derives from the gains, all of them set (none by default)."""
