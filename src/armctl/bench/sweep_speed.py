"""The sweep section of :mod:`armctl.bench.sim_speed`: many closed-loop runs through the sweep's own process pool
and through a Dask ``LocalCluster``, against the same runs one after the other in this process.

The cases are what a user writes: each carries its objects — the plant (the Panda with stick–slip joint friction,
viscous 0.2, Coulomb 0.3, static 0.4), a :class:`~armctl.controllers.ComputedTorque` on the friction-free model
with its own gains, and a :class:`~armctl.references.Quintic` move — and runs on ``simulate``'s default step; each
returns its final tracking error (``summary``, run in the worker).

Timing: the runs are split into blocks, and each block runs serially, on the pool and on the cluster in turn, so
that a change in a shared machine's load hits every way alike. The pool is the sweep's own (``executor=None``,
started within each block's timing); the cluster is started once, before the blocks, and its workers import armctl
before the first block (as a cluster that serves more than one sweep). The machine's ceiling is measured in the
same run (:func:`parallel_ceiling`): no code can scale beyond it.
"""

from __future__ import annotations

import math
import os
import statistics
import subprocess
import sys
import time
from typing import Any

import numpy as np

import armctl
from armctl.controllers import ComputedTorque
from armctl.references import Quintic
from armctl.sim import simulate, sweep

#: the Panda's start
Q0 = np.array([0.0, -0.4, 0.0, -2.0, 0.0, 1.6, 0.8])


def final_error(res: Any) -> float:
    """A case's summary: its largest joint error at the end [rad] (run in the worker)."""
    return float(np.abs(res.error[-1]).max())


def cases(runs: int, duration: float = 3.0) -> list[dict[str, Any]]:
    """``runs`` cases with their objects: plant, controller (gains from 100 to 900), Quintic reference."""
    model = armctl.models.panda().with_friction(viscous=0.2, coulomb=0.3, static=0.4)
    rigid = armctl.Dynamics(model.reduced(friction=False))
    out = []
    for i, kp in enumerate(np.geomspace(100.0, 900.0, runs)):
        goal = Q0 + 0.3 * np.sin(np.arange(7) + i)
        out.append(
            {
                "plant": model,
                "controller": ComputedTorque(rigid, kp, 2.0 * math.sqrt(kp)),
                "reference": Quintic(Q0, goal, min(2.0, duration)),
                "duration": duration,
            }
        )
    return out


def _import_armctl() -> None:
    import armctl.sim  # noqa: F401


def serial_block(runs: int, duration: float) -> None:
    """Run ``runs`` cases one after the other in this process (what :func:`parallel_ceiling` runs)."""
    for case in cases(runs, duration):
        simulate(**case)


def parallel_ceiling(runs: int, duration: float, workers: int = 2, rounds: int = 2) -> dict[str, Any]:
    """The machine's own limit on a sweep's speed-up: the same block of runs in independent Python processes, one
    alone and then ``workers`` at once (each the whole block). ceiling = workers × t_alone / t_together."""
    cmd = [sys.executable, "-c", f"from armctl.bench.sweep_speed import serial_block; serial_block({runs}, {duration})"]
    subprocess.run(cmd, check=True)  # warm the file cache and the compiled step's cache
    alone: list[float] = []
    together: list[float] = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True)
        alone.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        procs = [subprocess.Popen(cmd) for _ in range(workers)]
        if any(p.wait() != 0 for p in procs):
            raise RuntimeError("a block of the parallel-ceiling measurement failed")
        together.append(time.perf_counter() - t0)
    t_alone, t_together = statistics.median(alone), statistics.median(together)
    return {"alone_s": t_alone, "together_s": t_together, "ceiling": workers * t_alone / t_together}


def figures(runs: int = 100, duration: float = 3.0, workers: int = 2, blocks: int = 4) -> dict[str, Any]:
    """Serial, pool and cluster times of ``runs`` cases of ``duration`` [s] (see the module), the speed-ups, the
    machine's ceiling and load."""
    all_cases = cases(runs, duration)
    simulate(**{**all_cases[0], "duration": 0.01})  # build or load the generated step before any timing
    chunks = [all_cases[i::blocks] for i in range(blocks)]
    times = {"serial": 0.0, "pool": 0.0, "dask": 0.0}
    results: dict[str, list[Any]] = {k: [] for k in times}
    load = [os.getloadavg()[0]]
    client = cluster = None
    try:
        from dask.distributed import Client, LocalCluster

        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
        client.run(_import_armctl)  # the workers import armctl before the timing
        executor: Any = client.get_executor()
    except ImportError:
        executor = None
        times.pop("dask")
    try:
        for chunk in chunks:
            ways: dict[str, Any] = {"serial": "serial", "pool": None}
            if executor is not None:
                ways["dask"] = executor
            for way, ex in ways.items():
                t0 = time.perf_counter()
                out = sweep(
                    chunk,
                    summary=final_error,
                    executor=ex,
                    max_workers=workers if ex is None else None,
                    progress=False,
                    on_error="raise",
                )
                times[way] += time.perf_counter() - t0
                results[way] += list(out)
            load.append(os.getloadavg()[0])
    finally:
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
    for way in times:
        if results[way] != results["serial"]:
            raise RuntimeError(f"the {way} sweep and the serial one disagree")
    fig: dict[str, Any] = {"runs": runs, "duration_s": duration, "workers": workers, "load_average_1min": load}
    fig.update({f"{way}_s": t for way, t in times.items()})
    fig["pool_speedup"] = times["serial"] / times["pool"]
    if "dask" in times:
        fig["dask_speedup"] = times["serial"] / times["dask"]
    fig["ceiling"] = parallel_ceiling(max(4, runs // 10), duration, workers)
    return fig
