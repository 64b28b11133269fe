"""`SampledReference`: the reference a run's controller was given, at every sample (``res.reference``)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import cast

import numpy as np

from armctl._checks import FloatArray, readonly_fields
from armctl.references import Reference


@dataclass(frozen=True, eq=False)
class SampledReference:
    """The reference (q_d, q̇_d, q̈_d) at the sample times ``t`` (N,) [s]: ``q`` [rad or m], ``qd``, ``qdd``
    (each (N, n), read-only), row k being what the controller was given at t_k."""

    t: FloatArray
    q: FloatArray
    qd: FloatArray
    qdd: FloatArray

    def __post_init__(self) -> None:
        readonly_fields(self, ("t", "q", "qd", "qdd"))

    @classmethod
    def of(cls, t: FloatArray, references: Sequence[Reference | None], n: int) -> SampledReference:
        """Stack the References given at the times ``t`` (n joints; no references: empty arrays; None, a sample
        whose reference was not given: NaN)."""
        if not references:
            empty = np.zeros((0, n))
            return cls(np.asarray(t, dtype=float), empty, empty, empty)
        first = references[0]
        if first is not None and all(r is first for r in references):  # a fixed reference
            rows = len(references)
            return cls._holding(t, *(np.tile(a, (rows, 1)) for a in (first.q, first.qd, first.qdd)))
        # stacked when first read (see __getattr__): a run's result costs nothing for a reference nobody reads
        out = cls.__new__(cls)
        times = np.array(t, dtype=float)
        times.flags.writeable = False
        object.__setattr__(out, "t", times)
        object.__setattr__(out, "_given", (list(references), n))
        return out

    def __getattr__(self, name: str) -> FloatArray:
        """q, q̇ and q̈ of a SampledReference made by :meth:`of` from references that differ, stacked on the first
        read of any of them (one concatenation of the references' vectors per name, reshaped into the (N, n)
        rows; NaN rows for None)."""
        given = self.__dict__.get("_given")
        if given is None or name not in ("q", "qd", "qdd"):
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        references, n = given
        nan = np.full(n, np.nan)
        for key in ("q", "qd", "qdd"):
            a = np.concatenate([nan if r is None else getattr(r, key) for r in references]).reshape(-1, n)
            a.flags.writeable = False
            object.__setattr__(self, key, a)
        object.__delattr__(self, "_given")
        return cast(FloatArray, self.__dict__[name])

    @classmethod
    def _holding(cls, t: FloatArray, q: FloatArray, qd: FloatArray, qdd: FloatArray) -> SampledReference:
        """A SampledReference of ``t`` (copied) and of the new float64 arrays q, q̇, q̈ of :meth:`of` themselves
        (made read-only, not copied again)."""
        out = cls.__new__(cls)
        for name, a in (("t", np.array(t, dtype=float)), ("q", q), ("qd", qd), ("qdd", qdd)):
            a.flags.writeable = False
            object.__setattr__(out, name, a)
        return out

    def __len__(self) -> int:
        return len(self.t)

    def __getitem__(self, k: int) -> Reference:
        """The Reference of sample k."""
        return Reference(self.q[k], self.qd[k], self.qdd[k])

    def __repr__(self) -> str:
        n = self.q.shape[1] if self.q.ndim == 2 else 0
        return f"SampledReference({len(self.t)} samples, n = {n})"
