"""Sweep cases run on an Executor the caller gives (a thread pool, a ``ProcessPoolExecutor``, a Dask cluster's
``client.get_executor()``), and the :class:`~armctl.sim.CaseFailure` of a case that failed.

On Dask, a ``KilledWorker`` blames every case that was on a worker when it died, the ones that merely shared it
included: each such case runs once more alone, after the others, and only one that kills its worker alone too
is recorded as a dead worker.
"""

from __future__ import annotations

import pickle
import traceback
from collections.abc import Callable, Mapping
from concurrent.futures import BrokenExecutor, Executor, Future, ProcessPoolExecutor, as_completed
from typing import Any

from armctl.sim.case_failure import CaseFailure, ErrorReport, FailureKind, type_name
from armctl.sim.sweep_pool import run_one, run_pickled, run_pickled_again


def failure(
    i: int, case: Mapping[str, Any], exc: BaseException, kind: FailureKind = "raised", tries: int = 1
) -> CaseFailure:
    """The CaseFailure of case i, which failed with ``exc`` (``kind``: how; ``tries``: attempts)."""
    text = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))
    return CaseFailure(i, case, kind, type_name(type(exc)), str(exc), text, tries, exc)


def from_report(i: int, case: Mapping[str, Any], report: ErrorReport) -> CaseFailure:
    """The CaseFailure of case i, whose run raised in a worker (described by ``report``)."""
    return CaseFailure(i, case, "raised", report.error_type, report.message, report.traceback, 1, report.exception())


def through(
    executor: Executor,
    cases: list[Mapping[str, Any]],
    todo: list[int],
    blobs: list[bytes] | None,
    run: Callable[..., Any],
    summary: Callable[[Any], Any] | None,
    record: Callable[[int, Any], None],
) -> dict[int, int]:
    """Run every case on a given executor. Returns the cases a broken ProcessPoolExecutor left undone, with
    the attempts they had (1 if it broke under them, 0 if it was broken before they were submitted)."""
    futures: dict[Future[Any], int] = {}
    broken: dict[int, int] = {}
    try:
        for k, i in enumerate(todo):
            c = cases[i]
            try:  # threads: nothing is pickled, the case's own exception comes back from the future
                fut = (
                    executor.submit(run_one, run, c, summary)
                    if blobs is None
                    else executor.submit(run_pickled, blobs[i])
                )
            except BrokenExecutor:
                if not isinstance(executor, ProcessPoolExecutor):
                    raise
                broken.update(dict.fromkeys(todo[k:], 0))
                break
            futures[fut] = i
        pool = isinstance(executor, ProcessPoolExecutor)
        killed: list[int] = []  # Dask: cases whose workers all died under them (KilledWorker)
        for fut in as_completed(list(futures)):
            i = futures[fut]
            taken = take(fut, i, cases[i], blobs, record, pool)
            if taken == "broken":
                broken[i] = 1
            elif taken == "killed":
                killed.append(i)
        # A KilledWorker blames every case that was on a worker when it died, the innocent ones that shared it
        # included: each runs again alone, after the others, and only one that kills its workers alone too is
        # recorded as a dead worker
        for i in sorted(killed):
            fut = (
                executor.submit(run_pickled_again, blobs[i])
                if blobs is not None
                else executor.submit(run_one, run, cases[i], summary)
            )
            futures[fut] = i
            if take(fut, i, cases[i], blobs, record, pool, alone=True) == "broken":
                broken[i] = 1
    except BaseException:
        for fut in futures:
            fut.cancel()
        raise
    return broken


def take(
    fut: Future[Any],
    i: int,
    case: Mapping[str, Any],
    blobs: list[bytes] | None,
    record: Callable[[int, Any], None],
    pool: bool,
    alone: bool = False,
) -> str:
    """Record case i's outcome from its finished future; returns "recorded", or "broken" (``pool``: a
    ProcessPoolExecutor that broke, not recorded) or "killed" (Dask's KilledWorker, not ``alone``: not
    recorded)."""
    try:
        got = fut.result()
    except BrokenExecutor as exc:
        if pool:
            return "broken"
        record(i, failure(i, case, exc))
        return "recorded"
    except Exception as exc:  # the executor's own failure, or the run's exception from a thread
        died = type(exc).__name__ == "KilledWorker"
        if died and not alone:
            return "killed"
        record(i, failure(i, case, exc, "worker_died" if died else "raised", 2 if died else 1))
        return "recorded"
    if blobs is None:
        record(i, got)
    elif got[0] == "ok":
        record(i, pickle.loads(got[1]))
    else:
        record(i, from_report(i, case, got[1]))
    return "recorded"
