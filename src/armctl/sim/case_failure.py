"""How a sweep case failed: :class:`CaseFailure`, the entry a :class:`~armctl.sim.SweepResult` holds in place of
the case's result, and :class:`ErrorReport`, an exception described where it was raised in a form that travels
between processes (type, message and traceback as text, the exception itself pickled when it can be).

These are the small types that the sweep's runners, its store and its tables share; they depend on nothing
else of the simulator.
"""

from __future__ import annotations

import builtins
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
