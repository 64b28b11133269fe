"""One outcome per case: a run that raises, a worker process that dies (``os._exit``, SIGKILL) and a run that
hangs past the timeout are each recorded as that case's failure, in real processes, and every other case's
result comes back."""

from __future__ import annotations

import os
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pytest

from armctl.errors import RunTimeoutError, SweepWarning, WorkerDiedError
from armctl.sim import CaseFailure, sweep
from tests.sim.helpers import failing_cases, failing_job

pytestmark = pytest.mark.one_step  # sweeps and the step functions themselves: not a choice of step


def _starts(log: Path) -> list[int]:
    """How often each case started, by its x."""
    xs = [int(v) for v in log.read_text().split()]
    return [xs.count(x) for x in range(max(xs) + 1)]


def test_a_raising_run_is_recorded_and_the_others_come_back(tmp_path: Path) -> None:
    for executor in (None, "serial"):
        log = tmp_path / f"{executor}.log"
        cs = failing_cases(log, {3: "raise"})
        with pytest.warns(SweepWarning, match="case 3 raised ValueError: x = 3 is not allowed"):
            out = sweep(cs, run=failing_job, executor=executor, max_workers=2, progress=False)
        assert [out[i] for i in (0, 1, 2, 4, 5)] == [0, 1, 4, 16, 25]
        fail = out[3]
        assert isinstance(fail, CaseFailure) and (fail.index, fail.kind, fail.attempts) == (3, "raised", 1)
        assert (fail.error_type, fail.message) == ("ValueError", "x = 3 is not allowed")
        assert fail.case is cs[3]
        assert "in failing_job" in fail.traceback and 'raise ValueError(f"x = {x} is not allowed")' in fail.traceback
        assert isinstance(fail.exception, ValueError) and str(fail.exception) == "x = 3 is not allowed"
        assert out.counts == {"ok": 5, "raised": 1, "worker_died": 0, "timed_out": 0}
        assert _starts(log) == [1] * 6  # a raising run is not retried


def test_a_worker_that_dies_is_replaced_its_case_retried_once_and_recorded(tmp_path: Path) -> None:
    log = tmp_path / "starts.log"
    cs = failing_cases(log, {1: "exit", 2: "exit-once", 4: "sigkill"}, n=8)
    with pytest.warns(SweepWarning, match="2 worker died"):
        out = sweep(cs, run=failing_job, max_workers=2, progress=False)
    assert [out[i] for i in (0, 2, 3, 5, 6, 7)] == [0, 4, 9, 25, 36, 49]  # case 2 survived on its retry
    for i, how in ((1, "exit code 7"), (4, "killed by signal SIGKILL")):
        fail = out[i]
        assert isinstance(fail, CaseFailure) and fail.kind == "worker_died" and fail.attempts == 2
        assert fail.error_type == "armctl.errors.WorkerDiedError" and how in fail.message
        assert fail.case is cs[i] and how in fail.traceback
    # each dead case started twice (once more after its worker died), the rest once: the pool knows which
    # case each worker held, so a case running beside a dying one is not run again
    assert _starts(log) == [1, 2, 2, 1, 2, 1, 1, 1]
    with pytest.raises(WorkerDiedError, match="exit code 7") as info:
        sweep(cs[:3], run=failing_job, max_workers=2, progress=False, on_error="raise")
    assert "(in sweep case 1)" in info.value.__notes__


def test_a_bystander_beside_a_dying_worker_is_not_disturbed(tmp_path: Path) -> None:
    log = tmp_path / "starts.log"
    with pytest.warns(SweepWarning):
        out = sweep(failing_cases(log, {0: "slow", 1: "sigkill"}, n=2), run=failing_job, max_workers=2, progress=False)
    assert out[0] == 0 and out[1].kind == "worker_died"
    assert _starts(log) == [1, 2]


def test_a_run_past_the_timeout_is_stopped_and_recorded_with_its_stack(tmp_path: Path) -> None:
    log = tmp_path / "starts.log"
    cs = failing_cases(log, {1: "hang"}, n=4)
    with pytest.warns(SweepWarning, match="1 timed out"):
        out = sweep(cs, run=failing_job, max_workers=2, timeout=2.0, progress=False)
    assert [out[i] for i in (0, 2, 3)] == [0, 4, 9]
    fail = out[1]
    assert isinstance(fail, CaseFailure) and fail.kind == "timed_out" and fail.attempts == 1
    assert fail.error_type == "armctl.errors.RunTimeoutError" and "timeout=2 s" in fail.message
    assert isinstance(fail.exception, RunTimeoutError) and fail.case is cs[1]
    # the stack of the hanging run when it was stopped, as faulthandler wrote it in the worker
    assert "The run's stack when it was stopped" in fail.traceback and "in failing_job" in fail.traceback
    assert _starts(log) == [1, 1, 1, 1]  # a run that timed out is not retried
    with pytest.raises(RunTimeoutError) as info:
        sweep(cs[:2], run=failing_job, max_workers=2, timeout=1.0, progress=False, on_error="raise")
    assert "(in sweep case 1)" in info.value.__notes__


def test_a_broken_process_pool_executor_hands_its_cases_to_a_pool_of_the_sweep(tmp_path: Path) -> None:
    """A ProcessPoolExecutor breaks when one worker dies, failing every case it held: those run again on the
    sweep's own pool, where the one that kills its worker is found and recorded."""
    log = tmp_path / "starts.log"
    with ProcessPoolExecutor(2) as pool:
        with pytest.warns(SweepWarning, match="1 worker died"):
            out = sweep(
                failing_cases(log, {2: "exit", 4: "raise"}),
                run=failing_job,
                executor=pool,
                max_workers=2,
                progress=False,
            )
        assert [out[i] for i in (0, 1, 3, 5)] == [0, 1, 9, 25]
        assert out[2].kind == "worker_died" and "exit code 7" in out[2].message
        assert out[4].kind == "raised" and out[4].message == "x = 4 is not allowed"
        assert _starts(log)[2] == 2
        # the caller's pool stays broken; a later sweep given it runs on a pool of its own
        again = sweep(
            failing_cases(tmp_path / "again.log", {}, n=3),
            run=failing_job,
            executor=pool,
            max_workers=2,
            progress=False,
        )
        assert again == [0, 1, 4]


def test_a_result_that_does_not_pickle_is_a_failure_of_its_case() -> None:
    with pytest.warns(SweepWarning):
        out = sweep([{"n": 1}, {"n": 2}], run=_lock_or_number, max_workers=2, progress=False)
    assert out[1] == 2
    assert out[0].kind == "raised" and "cannot be pickled to travel back" in out[0].message
    assert "summary=" in out[0].message  # the way out


def _lock_or_number(n: int) -> object:
    import threading

    return threading.Lock() if n == 1 else n


def test_the_outcome_summary() -> None:
    with pytest.warns(SweepWarning):
        out = sweep([{"x": 2, "log": os.devnull}, {"x": 3, "log": os.devnull, "mode": "raise"}], run=failing_job)
    assert out == [4, out[1]] and len(out.failures) == 1 and not out.all_ok
    assert repr(out) == (
        "SweepResult(2 cases: 1 ok, 1 failed (1 raised, 0 worker died, 0 timed out); "
        "case 1 raised ValueError: x = 3 is not allowed)"
    )
    assert repr(sweep([], run=failing_job)) == "SweepResult(0 cases: 0 ok, 0 failed)"
