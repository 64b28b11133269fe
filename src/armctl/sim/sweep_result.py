"""What a sweep returns: one outcome per case, a :class:`CaseFailure` where a case failed.

:class:`SweepResult` is a list in case order. A case that ran holds what ``run`` (or ``summary``) returned;
a case that failed holds a :class:`CaseFailure`: the exception's type, message and traceback text, the case
itself, and how it failed (it raised, its worker process died, or it ran past the timeout).
"""

from __future__ import annotations

import builtins
import os
import pickle
import traceback as tb
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar, Literal

from armctl.errors import ArmctlError

FailureKind = Literal["raised", "worker_died", "timed_out"]
KINDS: tuple[FailureKind, ...] = ("raised", "worker_died", "timed_out")


@dataclass(frozen=True, eq=False)
class CaseFailure:
    """A sweep case that gave no result.

    Attributes
    ----------
    index : int
        The case's position in the sweep's ``cases``.
    case : Mapping[str, Any]
        The case itself (the mapping of keyword arguments handed to ``run``).
    kind : {"raised", "worker_died", "timed_out"}
        ``"raised"``: ``run`` (or ``summary``) raised. ``"worker_died"``: the process running it died
        (a signal such as SIGKILL, ``os._exit``, a crash in compiled code), also on its retry; on Dask, a
        ``KilledWorker`` also when it ran again alone. ``"timed_out"``: it ran longer than the sweep's
        ``timeout`` and its process was stopped.
    error_type : str
        The exception's class, e.g. ``"ValueError"`` or ``"armctl.errors.InvalidParameterError"``.
    message : str
        The exception's message.
    traceback : str
        The traceback text, as formatted where the exception was raised (in the worker for a process pool).
    attempts : int
        How often the case was started: 2 when its worker died and it was retried once.
    exception : BaseException
        The exception object: the original where it could travel back from the worker, else an
        :class:`~armctl.errors.ArmctlError` whose message holds the type, message and traceback; for a
        dead worker :class:`~armctl.errors.WorkerDiedError`, for a time-out
        :class:`~armctl.errors.RunTimeoutError`.
    """

    index: int
    case: Mapping[str, Any] = field(repr=False)
    kind: FailureKind
    error_type: str
    message: str
    traceback: str = field(repr=False)
    attempts: int = 1
    exception: BaseException | None = field(default=None, repr=False)
    ok: ClassVar[bool] = False

    def __str__(self) -> str:
        if self.kind == "raised":
            return f"case {self.index} raised {self.error_type}: {self.message}"
        return f"case {self.index}: {self.message}"


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
        from armctl.sim.sweep_store import load

        return load(path, partial)

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
        :mod:`armctl.sim.tables`).

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
        from armctl.sim.tables import sweep_dataframe

        return sweep_dataframe(self, self.cases, self.pending)

    def __repr__(self) -> str:
        return f"SweepResult({self.describe()})"

    __str__ = __repr__


@dataclass(frozen=True)
class ErrorReport:
    """An exception described where it was raised, in a form that always travels between processes: its
    type, message and traceback as text, and the exception itself pickled (None when it does not pickle)."""

    error_type: str
    message: str
    traceback: str
    pickled: bytes | None = None

    @classmethod
    def of(cls, exc: BaseException) -> ErrorReport:
        """Describe ``exc``, with the exception pickled if it survives a round trip."""
        blob: bytes | None = pickle.dumps(exc) if _round_trips(exc) else None
        text = "".join(tb.format_exception(type(exc), exc, exc.__traceback__))
        return cls(type_name(type(exc)), str(exc), text, blob)

    def exception(self) -> BaseException:
        """The exception: the original where it pickled, else an ArmctlError that carries it as text."""
        if self.pickled is not None:
            try:
                return pickle.loads(self.pickled)
            except Exception:
                pass
        return ArmctlError(
            f"{self.error_type}: {self.message} (raised in a worker, and it cannot be pickled, so it is passed on "
            f"as text; the worker's traceback:\n{self.traceback})"
        )


def _round_trips(exc: BaseException) -> bool:
    try:
        pickle.loads(pickle.dumps(exc))
    except Exception:
        return False
    return True


def type_name(cls: type) -> str:
    """``ValueError`` for a builtin, ``module.Class`` for anything else."""
    if cls.__module__ == "builtins" and getattr(builtins, cls.__name__, None) is cls:
        return cls.__name__
    return f"{cls.__module__}.{cls.__qualname__}"
