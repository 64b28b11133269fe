"""`sweep`: many simulations through any ``concurrent.futures.Executor``, one outcome per case.

Each case is a mapping of keyword arguments for ``run`` (by default :func:`armctl.sim.simulate`). A case
that fails, because ``run`` raised, its worker process died or it ran past ``timeout``, is recorded as a
:class:`~armctl.sim.CaseFailure` in its place, and the other cases' results come back.

Cases sent to worker processes are pickled, so everything in them must pickle: Dynamics and RobotModel objects
do (a Dynamics is rebuilt from its model in the worker), controllers do if their class is importable, and
references must be Reference objects or module-level callables, not lambdas. A case that does not pickle is
refused before anything starts, naming the case and the key. ``summary`` runs in the worker on each result,
so that only what is needed travels back. With a thread pool, cases may share a Dynamics object (each thread
evaluates on a workspace of its own), but not a controller: a controller holds the state of its run (integrals,
estimates, logs), so give each case its own.
"""

from __future__ import annotations

import dataclasses
import os
import pickle
import warnings
from collections.abc import Callable, Iterable, Mapping
from concurrent.futures import Executor, ProcessPoolExecutor, ThreadPoolExecutor
from typing import Any, Literal, TextIO, cast

import numpy as np

from armctl.errors import InvalidParameterError, RunTimeoutError, SweepWarning, WorkerDiedError
from armctl.sim import sweep_checks as checks
from armctl.sim.case_failure import CaseFailure
from armctl.sim.sweep_executor import failure, from_report, through
from armctl.sim.sweep_pool import WorkerPool, run_one
from armctl.sim.sweep_progress import Progress
from armctl.sim.sweep_result import SweepResult
from armctl.sim.sweep_store import SweepStore

ON_ERROR = ("record", "raise")


def sweep(
    cases: Iterable[Mapping[str, Any]],
    run: Callable[..., Any] | None = None,
    executor: Executor | str | None = None,
    max_workers: int | None = None,
    progress: bool | TextIO = True,
    *,
    summary: Callable[[Any], Any] | None = None,
    on_error: Literal["record", "raise"] = "record",
    timeout: float | None = None,
    store: str | os.PathLike[str] | None = None,
    resume: bool = False,
) -> SweepResult:
    """Run ``run(**case)`` for every case; return one outcome per case, in case order.

    Parameters
    ----------
    cases : iterable of mappings
        Keyword arguments for ``run``, one mapping per run. Every key must be a parameter of ``run`` and every
        required parameter given; this is checked for all cases before anything runs.
    run : callable, optional
        The function to run (default :func:`armctl.sim.simulate`).
    executor : Executor, "serial" or None
        None: the sweep's own pool of ``max_workers`` processes, stopped at the end. A worker process that
        dies is replaced and its case retried once; ``timeout`` is enforced. ``"serial"``: in this process,
        one case after the other (a run that ends its process, by ``os._exit`` or a crash, ends the caller's
        too). An Executor (a ``ThreadPoolExecutor``, a ``ProcessPoolExecutor``, a Dask
        ``client.get_executor()``) is used as given and not shut down. If a ``ProcessPoolExecutor`` breaks
        (a worker died), the cases it had not finished continue on a pool of the sweep's own, as their retry.
        On Dask, a case that gets a ``KilledWorker`` (the scheduler's own retries spent: each worker that ran
        it died) runs once more alone, after the other cases, because Dask blames every case that shared a
        dying worker: only one that kills its worker alone too is recorded as a dead worker.
    max_workers : int, optional
        Processes of the sweep's own pool (default: the number of CPUs, at most one per case).
    progress : bool or text stream
        True: progress on stderr; False: none; or a stream to write it on. On a terminal it is a live bar;
        elsewhere (a log file) a line at the start, the end and at most every 30 s.
    summary : callable, optional
        ``summary(output)`` is returned instead of the output; it runs in the worker, so that only what is
        needed travels back.
    on_error : {"record", "raise"}
        ``"record"`` (default): a failed case is a :class:`~armctl.sim.CaseFailure` in the
        result, and a :class:`~armctl.errors.SweepWarning` names the failed cases at the end. ``"raise"``: the
        first failure stops the sweep and is raised, with a note naming the case's index: the run's own
        exception, or :class:`~armctl.errors.WorkerDiedError` / :class:`~armctl.errors.RunTimeoutError`.
    timeout : float, optional
        Longest run [s], from the moment the case starts in its worker. A run past it has its worker process
        killed (and replaced) and is recorded as timed out; it is not retried. Enforced on the sweep's own
        pool only (``executor=None``; ``max_workers=1`` runs one case at a time): a run in this process or in
        a thread cannot be stopped, and another executor's workers are not the sweep's to kill.
    store : str or path-like, optional
        A folder where each case's outcome is written as soon as it finishes (see
        :mod:`armctl.sim.sweep_store`): its settings, how it ended, and the value returned for it (``summary``'s
        output, or the full result without ``summary``). A new or empty folder is made a store of these cases.
        :meth:`SweepResult.load <armctl.sim.SweepResult.load>` reads it back.
    resume : bool
        With ``store``: run only the cases whose outcome the store does not hold yet, and return all of them.
        The store must have been made from the same cases (compared case by case, key by key; the error names
        the first difference). Without ``resume``, a store that already holds outcomes is refused.

    Returns
    -------
    SweepResult
        A list with, for case ``i``, ``summary(run(**cases[i]))`` (or the output without ``summary``), or a
        :class:`~armctl.sim.CaseFailure`; ``.failures`` lists the failures, ``.counts`` counts
        ok / raised / worker_died / timed_out.

    Raises
    ------
    InvalidParameterError
        A bad argument; a case that is not a mapping, has a key that is not a parameter of ``run`` (a
        close match is suggested), lacks a required one, or (for worker processes) does not pickle; a store
        made from other cases, or holding outcomes without ``resume=True``.
    KeyboardInterrupt
        The sweep was interrupted (Ctrl-C): the sweep's own workers are stopped, every outcome finished so far is
        in the store, and a note says how many and how to resume.
    Exception
        With ``on_error="raise"``, the first failure.
    """
    if run is None:
        from armctl.sim.simulate import simulate

        run = simulate
    for name, fn in (("run", run), ("summary", summary)):
        if fn is not None and not callable(fn):
            raise InvalidParameterError(f"{name} must be a function, got {fn!r}", value=fn)
    case_list = checks.case_list(cases)
    if not (isinstance(progress, bool | np.bool_) or callable(getattr(progress, "write", None))):
        raise InvalidParameterError(f"progress must be True, False or a text stream, got {progress!r}", value=progress)
    if on_error not in ON_ERROR:
        raise InvalidParameterError(f"on_error must be 'record' or 'raise', got {on_error!r}", value=on_error)
    if max_workers is not None and (
        isinstance(max_workers, bool) or not isinstance(max_workers, int) or max_workers < 1
    ):
        raise InvalidParameterError(f"max_workers must be a positive integer, got {max_workers!r}", value=max_workers)
    if executor is not None and executor != "serial" and not callable(getattr(executor, "submit", None)):
        raise InvalidParameterError(
            f"executor must be an Executor (with a submit method), 'serial' or None, got {executor!r}", value=executor
        )
    checks.check_timeout(timeout, executor)
    checks.check_keywords(case_list, run)
    if not isinstance(resume, bool | np.bool_):
        raise InvalidParameterError(f"resume must be True or False, got {resume!r}", value=resume)
    if resume and store is None:
        raise InvalidParameterError("resume=True needs the store to resume from: pass store=PATH", value=resume)
    kept = SweepStore.open(store, case_list, bool(resume)) if store is not None else None
    done = kept.load(case_list) if kept is not None else {}
    todo = [i for i in range(len(case_list)) if i not in done]
    blobs = None
    if executor is None or isinstance(executor, ProcessPoolExecutor):
        blobs = checks.pickled(case_list, run, summary, pickle.dumps)
    elif executor != "serial" and not isinstance(executor, ThreadPoolExecutor):
        blobs = checks.pickled(case_list, run, summary, checks.other_pickler())

    out = SweepResult(done.get(i) for i in range(len(case_list)))
    out.cases = case_list
    out.store = None if kept is None else str(kept.path)
    bar = Progress(len(case_list), None if progress is True else progress, done=len(done)) if progress else None

    def record(i: int, outcome: Any) -> None:
        out[i] = outcome
        if kept is not None:
            kept.write(i, outcome)
        failed = isinstance(outcome, CaseFailure)
        if bar:
            bar.update(failed)
        if failed and on_error == "raise":
            exc = outcome.exception
            if hasattr(exc, "add_note"):
                exc.add_note(f"(in sweep case {i})")
            raise exc

    workers = min(max_workers or os.cpu_count() or 1, max(len(todo), 1))
    try:
        if executor == "serial":
            for i in todo:
                record(i, _call_here(i, case_list[i], run, summary))
        elif executor is None:
            assert blobs is not None  # pickled above for the sweep's own pool
            _own_pool([(i, blobs[i]) for i in todo], {}, case_list, workers, timeout, record)
        else:
            broken = through(cast(Executor, executor), case_list, todo, blobs, run, summary, record)
            if broken:  # a ProcessPoolExecutor broke: the cases it left run on a pool of ours
                assert blobs is not None  # a ProcessPoolExecutor's cases were pickled above
                tasks = [(i, blobs[i]) for i in sorted(broken)]
                _own_pool(tasks, broken, case_list, workers, None, record)
    except KeyboardInterrupt as exc:
        note = _interrupted(len(case_list), kept, sum(o is not None for o in out))
        if hasattr(exc, "add_note"):  # (Python ≥ 3.11; before, the note is the exception's message)
            exc.add_note(note)
        else:
            exc.args = (*exc.args, note)
        raise
    finally:
        if bar:
            bar.close()
    if out.failures:
        warnings.warn(
            f"sweep of {out.describe()}; the failed cases are CaseFailure entries", SweepWarning, stacklevel=2
        )
    return out


def _interrupted(n: int, kept: SweepStore | None, finished: int) -> str:
    """The note of a sweep interrupted with ``finished`` of its ``n`` cases done."""
    if kept is None:
        return (
            f"sweep interrupted: {finished} of {n} cases had finished, and they are not kept; pass store=PATH to "
            "keep each outcome as it finishes, and resume=True to run only the others"
        )
    return (
        f"sweep interrupted: {kept.written} of {n} cases are stored in {str(kept.path)!r}; run the same sweep with "
        f"store={str(kept.path)!r}, resume=True to run the other {n - kept.written}"
    )


def _call_here(i: int, case: Mapping[str, Any], run: Callable[..., Any], summary: Callable[[Any], Any] | None) -> Any:
    try:
        return run_one(run, case, summary)
    except Exception as exc:
        return failure(i, case, exc)


def _own_pool(
    tasks: list[tuple[int, bytes]],
    tries: dict[int, int],
    cases: list[Mapping[str, Any]],
    workers: int,
    timeout: float | None,
    record: Callable[[int, Any], None],
) -> None:
    with WorkerPool(workers, timeout) as pool:
        for i, outcome in pool.run(tasks, tries):
            kind = outcome[0]
            if kind == "ok":
                record(i, pickle.loads(outcome[1]))
            elif kind == "error":
                record(i, from_report(i, cases[i], outcome[1]))
            else:
                died = kind == "died"
                exc = (WorkerDiedError if died else RunTimeoutError)(outcome[1], value=cases[i])
                lost = failure(i, cases[i], exc, "worker_died" if died else "timed_out", outcome[2])
                if outcome[3]:
                    text = f"{lost.traceback}\nThe run's stack when it was stopped:\n{outcome[3]}"
                    lost = dataclasses.replace(lost, traceback=text)
                record(i, lost)
