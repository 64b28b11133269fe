"""What :func:`~armctl.sim.sweep.sweep` checks before anything runs: the cases are mappings whose keys are
parameters of ``run``, the timeout can be enforced on the executor, and (for worker processes) each case
pickles. Each refusal names the case and the key."""

from __future__ import annotations

import difflib
import inspect
import math
import numbers
import pickle
from collections.abc import Callable, Iterable, Mapping
from concurrent.futures import Executor
from typing import Any

from armctl.errors import InvalidParameterError


def case_list(cases: Iterable[Mapping[str, Any]]) -> list[Mapping[str, Any]]:
    """The cases as a list, each a mapping."""
    try:
        case_list = list(cases)
    except TypeError:
        raise InvalidParameterError(
            f"cases must be an iterable of keyword-argument mappings, got {cases!r}", value=cases
        ) from None
    for i, c in enumerate(case_list):
        if not isinstance(c, Mapping):
            raise InvalidParameterError(
                f"case {i} must be a mapping of keyword arguments, got {type(c).__name__}", value=c
            )
    return case_list


def check_timeout(timeout: float | None, executor: Executor | str | None) -> None:
    """A timeout is a positive finite number of seconds, and only for the sweep's own pool."""
    if timeout is None:
        return
    if (
        isinstance(timeout, bool)
        or not isinstance(timeout, numbers.Real)
        or not (timeout > 0 and math.isfinite(timeout))
    ):
        raise InvalidParameterError(f"timeout must be a positive number of seconds, got {timeout!r}", value=timeout)
    if executor is not None:
        where = "in this process" if executor == "serial" else f"on {type(executor).__name__}"
        raise InvalidParameterError(
            f"timeout is enforced only on the sweep's own process pool (executor=None): a run {where} cannot be "
            f"stopped by the sweep. Pass executor=None (max_workers=1 runs one case at a time)",
            value=timeout,
        )


def check_keywords(cases: list[Mapping[str, Any]], run: Callable[..., Any]) -> None:
    """Refuse, by name, a case whose keywords ``run`` does not take, or that lacks one it needs."""
    try:
        sig = inspect.signature(run)
    except (TypeError, ValueError):  # no signature to check against (some builtins)
        return
    kinds = (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
    names = [p.name for p in sig.parameters.values() if p.kind in kinds]
    any_keyword = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in sig.parameters.values())
    what = getattr(run, "__qualname__", None) or repr(run)
    for i, c in enumerate(cases):
        for key in c:
            if not isinstance(key, str):
                raise InvalidParameterError(f"sweep case {i} has a key that is not a string: {key!r}", value=key)
            if not any_keyword and key not in names:
                close = difflib.get_close_matches(key, names, n=1)
                hint = f" (did you mean {close[0]!r}?)" if close else ""
                raise InvalidParameterError(
                    f"sweep case {i}: {key!r} is not a keyword of {what}{hint}; its keywords: {', '.join(names)}",
                    value=key,
                )
        try:
            sig.bind(**c)
        except TypeError as exc:
            raise InvalidParameterError(f"sweep case {i} does not fit {what}: {exc}", value=c) from None


def other_pickler() -> Callable[[Any], bytes]:
    """How cases travel to another executor's workers: cloudpickle when installed (as Dask sends them)."""
    try:
        import cloudpickle
    except ImportError:
        return pickle.dumps
    return cloudpickle.dumps


def pickled(
    cases: list[Mapping[str, Any]], run: Callable[..., Any], summary: Callable[[Any], Any] | None, dumps: Callable
) -> list[bytes]:
    """Each case pickled with run and summary; a case that does not pickle is refused, naming what does not."""

    def refuse(i: int | None, what: str, obj: Any, exc: Exception) -> None:
        where = "the sweep's" if i is None else f"sweep case {i}:"
        text = repr(obj)
        raise InvalidParameterError(
            f"{where} {what} ({text[:80] + '…' if len(text) > 80 else text}) cannot be pickled to be sent to a "
            f"worker process ({type(exc).__name__}: {exc}). Use module-level functions and classes (not lambdas "
            f"or local definitions), or run in this process: executor='serial' or a ThreadPoolExecutor",
            value=obj,
        ) from None

    for name, fn in (("run", run), ("summary", summary)):
        try:
            dumps(fn)
        except Exception as exc:
            refuse(None, name, fn, exc)
    blobs = []
    for i, c in enumerate(cases):
        try:
            blobs.append(dumps((run, dict(c), summary)))
        except Exception as exc:
            for key, value in c.items():
                try:
                    dumps(value)
                except Exception as e:
                    refuse(i, f"its {key!r}", value, e)
            refuse(i, "the case", c, exc)
    return blobs
