"""The sweep's own process pool, and what runs a case in a worker.

Each worker process has its own pipe and holds at most two cases, the one it runs and the next, and says
when it starts one, so the pool knows which case each worker is running: a worker that dies (a signal,
``os._exit``, a crash in compiled code) is replaced and only its case is retried, once; a case past the
timeout has its worker killed and replaced, and the other workers run on. Cases travel pickled
(``pickle.dumps((run, case, summary))``) and results come back pickled, so nothing that fails to pickle is
ever handed to the pool's machinery.
"""

from __future__ import annotations

import faulthandler
import multiprocessing as mp
import os
import pickle
import queue
import signal
import tempfile
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from multiprocessing.connection import Connection, wait
from multiprocessing.process import BaseProcess
from typing import Any

from armctl.errors import ArmctlError, WorkerDiedError
from armctl.sim.case_failure import ErrorReport

RETRIES = 1  # a case whose worker died is run once more
DEPTH = 2  # cases handed to a worker at once: the one it runs and the next
SILENT_DEATHS = 3  # workers that may die before saying anything, before the pool gives up
STACK_SIGNAL = getattr(signal, "SIGUSR1", None)  # asks a worker for its stack (POSIX only)
STACK_WAIT = 1.0  # [s] the longest wait for that stack before the worker is killed


def run_one(run: Callable[..., Any], case: Mapping[str, Any], summary: Callable[[Any], Any] | None) -> Any:
    """``run(**case)``, or ``summary(run(**case))``."""
    out = run(**case)
    return out if summary is None else summary(out)


def run_pickled(blob: bytes) -> tuple[str, Any]:
    """Run a pickled ``(run, case, summary)`` in a worker. Returns ``("ok", pickled output)`` or
    ``("error", ErrorReport)``: it never raises, so nothing unpicklable is left for the executor to send."""
    try:
        run, case, summary = pickle.loads(blob)
        out = run_one(run, case, summary)
    except (Exception, SystemExit) as exc:
        return "error", ErrorReport.of(exc)
    try:
        return "ok", pickle.dumps(out)
    except Exception as exc:
        err = ArmctlError(
            f"the result, a {type(out).__name__}, cannot be pickled to travel back from the worker process "
            f"({type(exc).__name__}: {exc}); return something picklable with summary=..."
        )
        return "error", ErrorReport.of(err)


def run_pickled_again(blob: bytes) -> tuple[str, Any]:
    """:func:`run_pickled` under another name, for a case run a second time: an executor that names a task by
    its function and arguments (Dask) would otherwise hand back the first run's outcome."""
    return run_pickled(blob)


def _worker_main(conn: Connection, parent: int, stack_file: str | None) -> None:
    """A worker: run the cases ``(index, blob)`` that arrive, in order, answering ``("started",)`` and then the
    outcome for each; stop on None, or when the parent process is gone. A thread receives the cases, so that
    the next one waits here while this one runs and the pipe never fills. On ``STACK_SIGNAL`` the running
    case's Python stack is written to ``stack_file`` (by faulthandler, also while inside compiled code)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle: it stops the workers
    if stack_file is not None and STACK_SIGNAL is not None:
        faulthandler.register(STACK_SIGNAL, file=open(stack_file, "w"), all_threads=False)
    cases: queue.SimpleQueue[tuple[int, bytes] | None] = queue.SimpleQueue()
    threading.Thread(target=_receive, args=(conn, parent, cases), daemon=True).start()
    try:
        while (msg := cases.get()) is not None:
            conn.send(("started",))
            conn.send(run_pickled(msg[1]))
    except OSError:  # the parent is gone
        pass


def _receive(conn: Connection, parent: int, cases: queue.SimpleQueue[tuple[int, bytes] | None]) -> None:
    """The worker's receiving thread: cases into ``cases`` until None; if the parent process is gone, nobody
    waits for the running case's outcome any more, so the worker ends at once (no orphan runs on)."""
    if STACK_SIGNAL is not None:  # the stack signal is for the thread that runs the cases
        signal.pthread_sigmask(signal.SIG_BLOCK, {STACK_SIGNAL})
    try:
        while True:
            while not conn.poll(1.0):
                if os.getppid() != parent:
                    os._exit(0)
            msg = conn.recv()
            cases.put(msg)
            if msg is None:
                return
    except (EOFError, OSError):
        os._exit(0)


@dataclass
class _Worker:
    process: BaseProcess
    conn: Connection
    sent: deque[tuple[int, bytes]] = field(default_factory=deque)  # handed over, unfinished; the first runs
    started: float | None = None  # time.monotonic() when the first one started, None before
    spoke: bool = False  # it has sent anything
    stack_file: str | None = None

    def stack(self) -> str:
        """The Python stack of the worker's running case, as faulthandler writes it ("" if not available)."""
        pid = self.process.pid
        if self.stack_file is None or STACK_SIGNAL is None or pid is None or not self.process.is_alive():
            return ""
        os.kill(pid, STACK_SIGNAL)
        deadline = time.monotonic() + STACK_WAIT
        text, before = "", None
        while time.monotonic() < deadline and (not text or text != before):
            time.sleep(0.02)
            before = text
            with open(self.stack_file) as f:
                text = f.read()
        return text


def exit_text(code: int | None) -> str:
    """How a process ended, from its exit code."""
    if code is not None and code < 0:
        try:
            return f"killed by signal {signal.Signals(-code).name}"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exit code {code}"


class WorkerPool:
    """Up to ``n`` worker processes, each holding at most ``DEPTH`` cases (one running, the next waiting, so
    that a worker does not idle while the parent answers). A case whose worker dies while running it is
    retried once (the cases waiting behind it are handed out again, not counted as tried); a case running
    longer than ``timeout`` seconds has its worker killed. Leaving the context stops every worker."""

    def __init__(self, n: int, timeout: float | None = None) -> None:
        self.n, self.timeout = n, timeout
        self.ctx = mp.get_context()
        self.workers: list[_Worker] = []
        self.silent_deaths = 0  # workers that died before saying anything

    def __enter__(self) -> WorkerPool:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _start(self) -> _Worker:
        ours, theirs = self.ctx.Pipe()
        stack_file = None
        if self.timeout is not None and STACK_SIGNAL is not None:
            fd, stack_file = tempfile.mkstemp(prefix="armctl-sweep-stack-", suffix=".txt")
            os.close(fd)
        args = (theirs, os.getpid(), stack_file)
        proc = self.ctx.Process(target=_worker_main, args=args, name="armctl-sweep-worker")
        proc.start()
        theirs.close()
        w = _Worker(proc, ours, stack_file=stack_file)
        self.workers.append(w)
        return w

    def _drop(self, w: _Worker) -> None:
        if w.process.is_alive():
            w.process.kill()
        w.process.join()
        w.conn.close()
        if w.stack_file is not None:
            os.unlink(w.stack_file)
        self.workers.remove(w)

    def close(self) -> None:
        """Stop every worker: idle ones are asked to leave, busy ones are killed."""
        for w in self.workers:
            if not w.sent:
                try:
                    w.conn.send(None)
                except OSError:
                    pass
        deadline = time.monotonic() + 2.0
        for w in list(self.workers):
            if not w.sent:
                w.process.join(max(0.0, deadline - time.monotonic()))
            self._drop(w)

    def run(self, tasks: list[tuple[int, bytes]], tries: dict[int, int] | None = None) -> Iterator[tuple[int, tuple]]:
        """Run the pickled cases ``(index, blob)``; yield ``(index, outcome)`` as each one ends, in the order they
        end. outcome: ``("ok", pickled output)``, ``("error", ErrorReport)``, ``("died", text, attempts, "")`` or
        ``("timed_out", text, attempts, stack)`` (the run's Python stack when it was stopped).
        ``tries``: attempts already made per case (elsewhere)."""
        todo = deque(tasks)
        tries = dict(tries or {})
        while todo or any(w.sent for w in self.workers):
            self._hand_out(todo)
            busy = [w for w in self.workers if w.sent]
            started = [w.started for w in busy if w.started is not None]
            left = None
            if self.timeout is not None and started:
                left = max(0.0, min(started) + self.timeout - time.monotonic())
            ready = set(wait([w.conn for w in busy] + [w.process.sentinel for w in busy], left))
            for w in busy:
                if w.conn in ready or w.process.sentinel in ready:
                    yield from self._collect(w, todo, tries)
            if self.timeout is not None:
                now = time.monotonic()
                for w in [w for w in self.workers if w.started is not None and now - w.started >= self.timeout]:
                    i = w.sent[0][0]
                    stack = w.stack()
                    todo.extendleft(reversed(list(w.sent)[1:]))
                    self._drop(w)
                    text = f"the run took longer than timeout={self.timeout:g} s; its worker process was stopped"
                    yield i, ("timed_out", text, tries[i], stack)

    def _hand_out(self, todo: deque[tuple[int, bytes]]) -> None:
        """Hand cases to idle workers, then to new ones up to ``n``, then one more to each busy worker."""
        while todo:
            w = next((w for w in self.workers if not w.sent), None)
            if w is None and len(self.workers) < self.n:
                w = self._start()
            if w is None:
                w = next((w for w in self.workers if len(w.sent) < DEPTH), None)
                if w is None:
                    return
            task = todo.popleft()
            try:
                w.conn.send(task)
            except OSError:  # it died; this case goes back, not started
                todo.appendleft(task)
                if w.sent:
                    return  # the next wait() sees it die, with the case it was running
                self._drop(w)
                self._died_silently(w, "a worker process died while idle")
                continue
            w.sent.append(task)

    def _died_silently(self, w: _Worker, how: str) -> None:
        self.silent_deaths += not w.spoke
        if self.silent_deaths > SILENT_DEATHS:
            raise WorkerDiedError(f"the sweep's worker processes die before running any case ({how})")

    def _collect(
        self, w: _Worker, todo: deque[tuple[int, bytes]], tries: dict[int, int]
    ) -> Iterator[tuple[int, tuple]]:
        """Read what worker ``w`` sent; if it died, replace it: the case it was running is retried once (or
        reported), those waiting behind it go back to ``todo``."""
        try:
            while w.sent and w.conn.poll():
                msg = w.conn.recv()
                w.spoke = True
                if msg[0] == "started":
                    w.started = time.monotonic()
                    tries[w.sent[0][0]] = tries.get(w.sent[0][0], 0) + 1
                    continue
                (i, _), w.started = w.sent.popleft(), None
                yield i, msg
            if not w.sent or w.process.is_alive():
                return
        except (EOFError, OSError):
            pass
        w.process.join()
        how = exit_text(w.process.exitcode)
        running = w.sent.popleft() if w.started is not None else None
        todo.extendleft(reversed(w.sent))
        self._drop(w)
        if running is None:  # it died between cases
            self._died_silently(w, how)
            return
        i = running[0]
        if tries[i] <= RETRIES:
            todo.appendleft(running)
        else:
            text = f"the worker process running this case died ({how}), on each of its {tries[i]} attempts"
            yield i, ("died", text, tries[i], "")
