"""`sweep`: many simulations through any ``concurrent.futures.Executor``, with a progress bar.

Each case is a mapping of keyword arguments for ``run`` (by default :func:`armctl.sim.simulate`). Cases are
sent to the executor's workers, so with a process pool (the default) everything in a case must pickle:
Dynamics and RobotModel objects do (a Dynamics is rebuilt from its model in the worker), controllers do if
their class is importable, and references must be Reference objects or module-level callables, not lambdas.
``summary`` runs in the worker on each result, so that only what is needed travels back. With a thread
pool, cases must not share a Dynamics object (its workspace is not thread-safe): give each its own, or pass
the plant as a RobotModel (``simulate`` then builds one per run).

A run that diverges is a result (``res.diverged``), not an error; an exception in a case (a bad input) stops
the sweep and is raised with the case's index.
"""

from __future__ import annotations

import os
import pickle
import sys
import time
import traceback
from collections.abc import Callable, Iterable, Mapping
from concurrent.futures import Executor, Future, ProcessPoolExecutor, ThreadPoolExecutor, as_completed
from typing import Any, TextIO

import numpy as np

from armctl.errors import ArmctlError, InvalidParameterError


class ProgressBar:
    """A one-line text progress bar: ``[#######.....]  70/100  12.3 s, ~5.1 s left``."""

    def __init__(self, total: int, stream: TextIO | None = None, width: int = 30, label: str = "runs") -> None:
        self.total, self.width, self.label = total, width, label
        self.stream = sys.stderr if stream is None else stream
        self.done = 0
        self.start = time.perf_counter()

    def update(self, done: int) -> None:
        self.done = done
        elapsed = time.perf_counter() - self.start
        filled = int(self.width * done / self.total) if self.total else self.width
        left = f", ~{elapsed / done * (self.total - done):.1f} s left" if 0 < done < self.total else ""
        self.stream.write(
            f"\r[{'#' * filled}{'.' * (self.width - filled)}] {done:>{len(str(self.total))}}/"
            f"{self.total} {self.label}  {elapsed:.1f} s{left}  "
        )
        if done >= self.total:
            self.stream.write("\n")
        self.stream.flush()


def _run_case(run: Callable[..., Any], case: Mapping[str, Any], summary: Callable[[Any], Any] | None) -> Any:
    out = run(**case)
    return out if summary is None else summary(out)


def _run_case_in_worker(run: Callable[..., Any], case: Mapping[str, Any], summary: Callable[[Any], Any] | None) -> Any:
    """:func:`_run_case` in a pool's worker: an exception that cannot be pickled (which a process pool would
    report only as a broken pool, without its message) comes back as an ArmctlError carrying its type,
    message and traceback."""
    try:
        return _run_case(run, case, summary)
    except Exception as exc:
        try:
            pickle.loads(pickle.dumps(exc))
        except Exception:
            text = (
                f"{type(exc).__name__}: {exc} (raised in a worker, and it cannot be pickled, so it is passed "
                f"on as text; the worker's traceback:\n{traceback.format_exc()})"
            )
        else:
            raise
    # raised here, outside the handler, so that it carries no context: a pickler that follows exception
    # chains (tblib's, which dask installs) would meet the unpicklable exception again
    raise ArmctlError(text)


def sweep(
    cases: Iterable[Mapping[str, Any]],
    *,
    run: Callable[..., Any] | None = None,
    summary: Callable[[Any], Any] | None = None,
    executor: Executor | str | None = None,
    max_workers: int | None = None,
    progress: bool | TextIO = True,
) -> list[Any]:
    """Run ``run(**case)`` for every case and return the outputs (or ``summary(output)``) in case order.

    executor: an Executor (used as given and not shut down; e.g. a ThreadPoolExecutor, or a Dask
    ``client.get_executor()``), ``"serial"`` (in this process, one after the other) or None: a
    ProcessPoolExecutor with ``max_workers`` processes (default: the number of CPUs), shut down at the end.
    progress: True (a bar on stderr), False, or a text stream to draw the bar on.
    """
    if run is None:
        from armctl.sim.simulate import simulate as run
    for name, fn in (("run", run), ("summary", summary)):
        if fn is not None and not callable(fn):
            raise InvalidParameterError(f"{name} must be a function, got {fn!r}", value=fn)
    try:
        case_list = list(cases)
    except TypeError:
        raise InvalidParameterError(
            f"cases must be an iterable of keyword-argument mappings, got {cases!r}", value=cases
        ) from None
    if not (isinstance(progress, bool | np.bool_) or callable(getattr(progress, "write", None))):
        raise InvalidParameterError(f"progress must be True, False or a text stream, got {progress!r}", value=progress)
    for i, c in enumerate(case_list):
        if not isinstance(c, Mapping):
            raise InvalidParameterError(
                f"case {i} must be a mapping of keyword arguments, got {type(c).__name__}", value=c
            )
    bar = None
    if progress:
        bar = ProgressBar(len(case_list), None if progress is True else progress)  # type: ignore[arg-type]
    if executor == "serial":
        out = []
        for i, c in enumerate(case_list):
            out.append(_checked(i, lambda c=c: _run_case(run, c, summary)))  # type: ignore[misc]
            if bar:
                bar.update(i + 1)
        return out
    if executor is not None and not callable(getattr(executor, "submit", None)):
        raise InvalidParameterError(
            f"executor must be an Executor (with a submit method), 'serial' or None, got {executor!r}", value=executor
        )
    own = executor is None
    if max_workers is not None and (
        isinstance(max_workers, bool) or not isinstance(max_workers, int) or max_workers < 1
    ):
        raise InvalidParameterError(f"max_workers must be a positive integer, got {max_workers!r}", value=max_workers)
    pool: Executor = ProcessPoolExecutor(max_workers or os.cpu_count() or 1) if own else executor  # type: ignore[assignment]
    results: list[Any] = [None] * len(case_list)
    try:
        # threads share this process: nothing is pickled, so exceptions travel as they are
        work = _run_case if isinstance(pool, ThreadPoolExecutor) else _run_case_in_worker
        futures: dict[Future[Any], int] = {pool.submit(work, run, c, summary): i for i, c in enumerate(case_list)}
        if bar:
            bar.update(0)
        for done, fut in enumerate(as_completed(futures), start=1):
            i = futures[fut]
            results[i] = _checked(i, fut.result)
            if bar:
                bar.update(done)
    except BaseException:
        for fut in futures if "futures" in locals() else ():
            fut.cancel()
        raise
    finally:
        if own:
            pool.shutdown(wait=True, cancel_futures=True)
    return results


def _checked(i: int, fn: Callable[[], Any]) -> Any:
    try:
        return fn()
    except Exception as exc:
        if hasattr(exc, "add_note"):
            exc.add_note(f"(in sweep case {i})")
        raise
