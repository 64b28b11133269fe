"""The spread of a controller's per-call cost over a long run: every call timed on its own, the median p50 and the
99.9th percentile p99.9 of the samples, and their ratio, on two clocks: the thread's CPU time (``cpu``: what the
call itself costs, a machine's other processes left out; each reading costs about a microsecond, which the
samples include) and the wall clock (``wall``: also the time the thread waited for a core, the tail a loaded
machine adds).

* :func:`law_tail`: a closed loop of a joint-space law on its own model, the Panda tracking a sinusoid from its
  ready pose (forward dynamics and semi-implicit Euler at a tenth of the control period, τ held), ``steps`` calls;
* :func:`replay_tail`: recorded states (t, q, q̇, reference) handed in order to a fresh controller, the way the
  run that recorded them called it, until ``steps`` calls (a run shorter than that is replayed again from its
  start, through a reset controller).

A tail that is long compared with the median (p99.9 / p50 well above 1) is what a real-time loop pays for: the
step's budget has to cover it.

Each run also times a *floor* between the controller's calls, on the same clocks and under the same machine: NumPy
work of the same median and nothing else (:class:`Floor`: products of a 7×7 matrix by a 7-vector, as many as take
the controller's median over the run's first :data:`CALIBRATION` calls, scaled once on the floor's own next ones).
A NumPy loop allocates no Python object a
collector tracks and keeps no state, so its tail is what the machine adds to any call that long (interrupts, other
processes taking the core, the caches they leave cold); a controller's tail well beyond its floor's is the
controller's own. The garbage collections that run during the timed loop are counted (``gc_runs``); the loop runs
with the collector as Python leaves it (no ``gc.disable`` or ``gc.freeze``).
"""

from __future__ import annotations

import gc
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any

import numpy as np

import armctl

#: integration steps per control period in :func:`law_tail` (semi-implicit Euler: the wrist's damping, K_D over
#: its small inertia, needs steps of a tenth of a millisecond)
_SUBSTEPS = 10
#: the Panda's ready posture
Q_HOME = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
#: the controller's calls whose median sets the floor's work (they are among the controller's samples; the floor is
#: timed from the next call on)
CALIBRATION = 200


def summary(cpu_ns: Sequence[int], wall_ns: Sequence[int]) -> dict[str, Any]:
    """Per clock (``"cpu"``, ``"wall"``): p50, p99.9 [s] of per-call times in ns and their ratio; and the number
    of calls."""
    out: dict[str, Any] = {"calls": len(cpu_ns)}
    for name, samples in (("cpu", cpu_ns), ("wall", wall_ns)):
        p50, p999 = (float(v) * 1e-9 for v in np.percentile(np.asarray(samples, dtype=float), [50.0, 99.9]))
        out[name] = {"p50_s": p50, "p999_s": p999, "tail_ratio": p999 / p50}
    return out


class _Timer:
    """Per-call samples on both clocks, the controller's and the floor's (see the module)."""

    def __init__(self, steps: int) -> None:
        self.cpu = np.empty(steps, dtype=np.int64)
        self.wall = np.empty(steps, dtype=np.int64)
        self.floor_cpu = np.empty(max(steps - CALIBRATION, 0), dtype=np.int64)  # (the first CALIBRATION: scaling)
        self.floor_wall = np.empty_like(self.floor_cpu)
        self.floor: Floor | None = None
        self.gc_runs = 0

    def after(self, k: int) -> None:
        """After the controller's call k: from the calibration's end on, time the floor (its work set on the
        controller's first :data:`CALIBRATION` calls, then scaled once on its own next :data:`CALIBRATION` samples,
        which are left out: a product costs more between a controller's calls than alone)."""
        if k < CALIBRATION:
            if k == CALIBRATION - 1:
                self.floor = Floor(float(np.median(self.cpu[:CALIBRATION])) * 1e-9)
            return
        floor = self.floor
        if floor is None:
            return
        wall, cpu = time.perf_counter_ns, time.thread_time_ns
        w0, c0 = wall(), cpu()
        floor()
        c1, w1 = cpu(), wall()
        j = k - CALIBRATION
        self.floor_cpu[j], self.floor_wall[j] = c1 - c0, w1 - w0
        if j == CALIBRATION - 1:
            target, got = np.median(self.cpu[:CALIBRATION]), np.median(self.floor_cpu[:CALIBRATION])
            floor.reps = max(1, round(floor.reps * float(target) / max(float(got), 1.0)))

    @contextmanager
    def counting_collections(self) -> Iterator[None]:
        """Count the garbage collections that start within the block."""

        def count(phase: str, info: dict[str, Any]) -> None:
            if phase == "start":
                self.gc_runs += 1

        gc.callbacks.append(count)
        try:
            yield
        finally:
            gc.callbacks.remove(count)

    def summary(self) -> dict[str, Any]:
        out = summary(self.cpu.tolist(), self.wall.tolist())
        out["gc_runs"] = self.gc_runs
        kept = slice(CALIBRATION, None)
        if self.floor is not None and len(self.floor_cpu[kept]):
            floor = summary(self.floor_cpu[kept].tolist(), self.floor_wall[kept].tolist())
            out["floor"] = {**floor, "products": self.floor.reps}
        return out


class Floor:
    """NumPy work of a median CPU time ``median_s`` [s]: ``reps`` products of a 7×7 matrix by a 7-vector (a call
    allocates each product's array and nothing a garbage collector tracks)."""

    def __init__(self, median_s: float, probes: int = 2000) -> None:
        rng = np.random.default_rng(0)
        self.a, self.x = rng.standard_normal((7, 7)), rng.standard_normal(7)
        self.reps = 1
        cpu = time.thread_time_ns
        one = []
        for _ in range(probes):  # the median of one product, timed as the calls are (the clock's cost included)
            c0 = cpu()
            self()
            one.append(cpu() - c0)
        clock = []
        for _ in range(probes):
            c0 = cpu()
            clock.append(cpu() - c0)
        per, overhead = float(np.median(one)), float(np.median(clock))
        self.reps = max(1, round((median_s * 1e9 - overhead) / max(per - overhead, 1.0)))

    def __call__(self) -> None:
        dot, a, x = np.dot, self.a, self.x
        for _ in range(self.reps):
            dot(a, x)


def law_tail(ctrl: Any, steps: int = 20_000, dt: float = 1e-3) -> dict[str, Any]:
    """Per-call times of the joint-space law ``ctrl`` closing the loop on its own model (the Panda) for ``steps``
    control periods of ``dt`` [s] (the reference: each joint 0.2 rad about the ready pose at 0.5 Hz)."""
    kernel = ctrl.dynamics.kernel
    n = ctrl.n
    w = 2.0 * np.pi * 0.5
    q, qd = Q_HOME.copy(), np.zeros(n)
    refs = []
    for k in range(steps):  # made beforehand: the loop times the controller, not the reference
        t = k * dt
        s, c = np.sin(w * t), np.cos(w * t)
        refs.append(armctl.Reference(Q_HOME + 0.2 * s, np.full(n, 0.2 * w * c), np.full(n, -0.2 * w * w * s)))
    timer = _Timer(steps)
    wall, cpu = time.perf_counter_ns, time.thread_time_ns
    h = dt / _SUBSTEPS
    with timer.counting_collections():
        for k in range(steps):
            w0, c0 = wall(), cpu()
            tau = ctrl(k * dt, q, qd, refs[k])
            c1, w1 = cpu(), wall()
            timer.cpu[k], timer.wall[k] = c1 - c0, w1 - w0
            timer.after(k)
            for _ in range(_SUBSTEPS):  # τ held over the period
                qd = qd + h * kernel.aba(q, qd, tau)
                q = q + h * qd
    return timer.summary()


def replay_tail(
    make: Callable[[], Any],
    states: Sequence[tuple[float, np.ndarray, np.ndarray, Any]],
    steps: int = 20_000,
) -> dict[str, Any]:
    """Per-call times of the controller ``make()`` given the recorded ``states`` (t, q, q̇, reference) in order,
    ``steps`` calls in all (the states again from the start, through a fresh controller, when they run out)."""
    timer = _Timer(steps)
    wall, cpu = time.perf_counter_ns, time.thread_time_ns
    k = 0
    while k < steps:
        ctrl = make()
        with timer.counting_collections():
            for t, q, qd, ref in states:
                if k == steps:
                    break
                w0, c0 = wall(), cpu()
                ctrl(t, q, qd, ref)
                c1, w1 = cpu(), wall()
                timer.cpu[k], timer.wall[k] = c1 - c0, w1 - w0
                timer.after(k)
                k += 1
    return timer.summary()


def clock_jumps(seconds: float = 0.5, threshold_s: float = 5e-6) -> dict[str, float]:
    """What the machine adds to a thread's CPU time while it runs: the thread reads its CPU clock back to back for
    ``seconds`` [s] of wall time, and every step between two readings longer than ``threshold_s`` [s] is a *jump*
    (an interrupt, the kernel's work for another task, a virtual machine's exit: time the thread is charged for
    but did not spend on its own code). Returns the jumps a second (``per_s``), their median (``median_s``) [s]
    and the share of calls of 1 µs a jump lands in (``per_us``: ``per_s`` · 1e-6). A call of median d [µs] is hit
    with a probability of about ``per_us`` · d; where that exceeds 0.1 %, its p99.9 is about d plus a jump."""
    cpu, wall = time.thread_time_ns, time.perf_counter_ns
    limit = int(threshold_s * 1e9)
    jumps: list[int] = []
    end = wall() + int(seconds * 1e9)
    start = wall()
    prev = cpu()
    while wall() < end:
        c = cpu()
        if c - prev > limit:
            jumps.append(c - prev)
        prev = c
    elapsed = (wall() - start) * 1e-9
    per_s = len(jumps) / elapsed
    return {
        "per_s": per_s,
        "median_s": float(np.median(jumps)) * 1e-9 if jumps else 0.0,
        "per_us": per_s * 1e-6,
    }


def jumps_text(j: dict[str, float]) -> str:
    """One line of :func:`clock_jumps`."""
    return (
        f"the machine's CPU-clock jumps (a spin loop reading the thread's CPU clock): {j['per_s']:.0f} a second, "
        f"median {j['median_s'] * 1e6:.1f} µs — a call of d µs is hit with a probability of about "
        f"{100 * j['per_us']:.3f} % per µs of d"
    )


def tail_text(t: dict[str, Any]) -> str:
    """One line of a tail's figures: p50, p99.9 and their ratio on the CPU clock, and the wall clock's ratio; the
    floor's (see the module) and the garbage collections during the loop, where measured."""
    c, w = t["cpu"], t["wall"]
    text = (
        f"CPU p50 {c['p50_s'] * 1e6:.2f} µs, p99.9 {c['p999_s'] * 1e6:.2f} µs, p99.9 / p50 {c['tail_ratio']:.2f}; "
        f"wall p99.9 / p50 {w['tail_ratio']:.2f}"
    )
    f = t.get("floor")
    if f is not None:
        text += (
            f"; NumPy floor of the same median ({f['products']} np.dot, timed between the calls): CPU p50 "
            f"{f['cpu']['p50_s'] * 1e6:.2f} µs, p99.9 / p50 {f['cpu']['tail_ratio']:.2f}"
        )
    if "gc_runs" in t:
        text += f"; garbage collections during the loop: {t['gc_runs']} (collector on)"
    return text
