"""What a sweep returns: one outcome per case, a :class:`~armctl.sim.CaseFailure` where a case failed.

:class:`SweepResult` is a list in case order. A case that ran holds what ``run`` (or ``summary``) returned;
a case that failed holds a :class:`~armctl.sim.CaseFailure` (:mod:`armctl.sim.case_failure`): the exception's
type, message and traceback text, the case itself, and how it failed (it raised, its worker process died, or it
ran past the timeout).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

from armctl.sim.case_failure import KINDS, CaseFailure
from armctl.sim.sweep_store import read_outcomes
from armctl.sim.sweep_table import sweep_dataframe


class SweepResult(list[Any]):
    """The outcomes of a sweep in case order: each case's result, or a :class:`CaseFailure`.

    A plain list in every other respect (it compares equal to a list of the same items). ``failures`` lists
    the failed cases, ``counts`` counts the outcomes by kind, ``all_ok`` is True when no case failed;
    ``cases`` holds the cases themselves (set by :func:`~armctl.sim.sweep`), ``store`` the folder the outcomes
    were written to (``sweep(..., store=PATH)``), ``to_dataframe()`` makes a table of them.
    """

    #: the sweep's cases, in order (None for a list built otherwise)
    cases: list[Mapping[str, Any]] | None = None
    #: the folder the outcomes were written to, or None
    store: str | None = None
    #: the cases not finished (their entries are None): only in a store loaded with ``partial=True``
    pending: frozenset[int] = frozenset()

    @classmethod
    def load(cls, path: str | os.PathLike[str], partial: bool = False) -> SweepResult:
        """The outcomes a sweep wrote to its store (``sweep(..., store=path)``; see :mod:`armctl.sim.sweep_store`).

        Parameters
        ----------
        path : str or path-like
            The store's folder.
        partial : bool, optional
            Accept a store whose sweep did not finish: the unfinished cases are None and listed in
            :attr:`pending` (their rows in :meth:`to_dataframe` have the outcome ``"not_run"``).

        Returns
        -------
        SweepResult
            In case order; ``cases`` holds each case's settings as the store shows them (numbers and strings as
            they were, other objects by name or repr).

        Raises
        ------
        InvalidParameterError
            Not a store, or (without ``partial``) a store with unfinished cases.
        """
        stored = read_outcomes(path, partial)
        out = cls(stored.outcomes)
        out.cases = list(stored.settings)
        out.store = stored.path
        out.pending = stored.pending
        return out

    @property
    def failures(self) -> list[CaseFailure]:
        """The cases that failed, in case order."""
        return [o for o in self if isinstance(o, CaseFailure)]

    @property
    def counts(self) -> dict[str, int]:
        """Outcomes by kind: ``{"ok": …, "raised": …, "worker_died": …, "timed_out": …}``."""
        out = dict.fromkeys(("ok", *KINDS), 0)
        for o in self:
            out[o.kind if isinstance(o, CaseFailure) else "ok"] += 1
        return out

    @property
    def all_ok(self) -> bool:
        """True when every case gave a result."""
        return not any(isinstance(o, CaseFailure) for o in self)

    def describe(self) -> str:
        """One line: the counts, and the first failures.

        Returns
        -------
        str
        """
        c = self.counts
        text = f"{len(self)} cases: {c['ok']} ok, {len(self) - c['ok']} failed"
        if len(self) > c["ok"]:
            text += f" ({c['raised']} raised, {c['worker_died']} worker died, {c['timed_out']} timed out)"
            fails = self.failures
            text += "; " + "; ".join(str(f) for f in fails[:3]) + ("; …" if len(fails) > 3 else "")
        return text

    def to_dataframe(self) -> Any:
        """One row per case, indexed by the case's position (``pip install "armctl[data]"``; see
        :mod:`armctl.sim.sweep_table`).

        Returns
        -------
        pandas.DataFrame
            Columns: the case's settings (scalars as they are, other objects by their name or repr), ``outcome``
            (``"ok"``, ``"raised"``, ``"worker_died"``, ``"timed_out"``), ``error_type`` and ``message`` of a
            failure, and the scalar metrics of each result (the summary's numbers, or a full run's status and
            tracking error).

        Raises
        ------
        OptionalDependencyError
            pandas is not installed.
        """
        return sweep_dataframe(self, self.cases, self.pending)

    def __repr__(self) -> str:
        return f"SweepResult({self.describe()})"

    __str__ = __repr__
