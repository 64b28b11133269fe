"""A sweep on a Dask cluster (a local one, worker processes) keeps one outcome per case: a run that raises and
a run that kills its worker each time (Dask's ``KilledWorker``) are recorded, the other results come back."""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import pytest

from armctl.errors import SweepWarning
from armctl.sim import CaseFailure, sweep
from tests.sim.helpers import failing_cases, failing_job

pytestmark = pytest.mark.one_step  # sweeps and the step functions themselves: not a choice of step


@pytest.mark.slow
def test_killed_worker_and_raising_run_on_dask_are_recorded(tmp_path: Path) -> None:
    import dask
    import distributed  # in the test extra: missing, the test fails rather than skips

    cs = failing_cases(tmp_path / "starts.log", {1: "raise", 3: "sigkill"}, n=5)
    with (
        # one retry, as the sweep's own pool gives; one task per worker at a time, so that a case queued on the
        # worker that dies is not counted as a suspect of its death
        dask.config.set({"distributed.scheduler.allowed-failures": 1, "distributed.scheduler.worker-saturation": 1.0}),
        distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cl,
        distributed.Client(cl) as client,
    ):
        with pytest.warns(SweepWarning, match="1 raised, 1 worker died"):
            out = sweep(cs, run=failing_job, executor=client.get_executor(), progress=False)
        # Dask's workers receive cases through cloudpickle, so a lambda is not refused there
        lam = sweep([{"x": 2}], run=lambda x: x + 1, executor=client.get_executor(), progress=False)
    assert [out[i] for i in (0, 2, 4)] == [0, 4, 16] and lam == [3]
    raised, killed = out[1], out[3]
    assert isinstance(raised, CaseFailure) and raised.kind == "raised" and raised.case is cs[1]
    assert (raised.error_type, raised.message) == ("ValueError", "x = 1 is not allowed")
    assert "in failing_job" in raised.traceback  # the worker's traceback
    assert isinstance(killed, CaseFailure) and killed.kind == "worker_died" and killed.case is cs[3]
    assert killed.error_type == "distributed.scheduler.KilledWorker" and "workers died" in killed.message


def killer_and_neighbour(x: int, log: str) -> int:
    """x², after noting the start in ``log``. Case 0 kills its worker process: on its first start once case 1
    has started too (so that case 1 is on the worker when it dies; at most 5 s), later at once. Case 1 takes
    0.5 s."""
    with open(log, "a") as f:
        f.write(f"{x}\n")
    if x == 0:
        deadline = time.monotonic() + 5.0
        while Path(log).read_text().split().count("0") == 1 and time.monotonic() < deadline:
            if "1" in Path(log).read_text().split():
                break
            time.sleep(0.01)
        os.kill(os.getpid(), signal.SIGKILL)
    if x == 1:
        time.sleep(0.5)
    return x * x


@pytest.mark.slow
def test_a_case_that_shared_a_dying_worker_is_not_lost(tmp_path: Path) -> None:
    """One worker with two threads, and no retry by Dask: the killer kills the worker while the innocent case
    runs beside it, and Dask gives up on both (KilledWorker). The sweep runs each of them again alone: the
    innocent one returns its result, and only the killer is recorded as a dead worker."""
    import dask
    import distributed

    log = tmp_path / "starts.log"
    cs = [{"x": x, "log": str(log)} for x in range(3)]
    with (
        dask.config.set({"distributed.scheduler.allowed-failures": 0}),
        distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=True, dashboard_address=None) as cl,
        distributed.Client(cl) as client,
    ):
        with pytest.warns(SweepWarning, match=r"3 cases: 2 ok, 1 failed \(0 raised, 1 worker died"):
            out = sweep(cs, run=killer_and_neighbour, executor=client.get_executor(), progress=False)
    killed = out[0]
    assert isinstance(killed, CaseFailure) and killed.kind == "worker_died" and killed.case is cs[0]
    assert killed.error_type == "distributed.scheduler.KilledWorker"
    assert out[1:] == [1, 4] and out.failures == [killed]
    starts = log.read_text().split()
    assert starts.count("0") == 2 and starts.count("1") == 2  # together on the dying worker, then each alone
