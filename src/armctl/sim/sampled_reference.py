"""`SampledReference`: the reference a run's controller was given, at every sample (``res.reference``)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from armctl._checks import FloatArray
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
        for name in ("t", "q", "qd", "qdd"):
            a = np.array(getattr(self, name), dtype=float)
            a.flags.writeable = False
            object.__setattr__(self, name, a)

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
        # one concatenation of the references' vectors, reshaped into the (N, n) rows
        nan = np.full(n, np.nan)
        parts = ([nan if r is None else getattr(r, name) for r in references] for name in ("q", "qd", "qdd"))
        return cls._holding(t, *(np.concatenate(x).reshape(-1, n) for x in parts))

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
