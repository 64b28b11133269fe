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
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

import armctl

#: integration steps per control period in :func:`law_tail` (semi-implicit Euler: the wrist's damping, K_D over
#: its small inertia, needs steps of a tenth of a millisecond)
_SUBSTEPS = 10
#: the Panda's ready posture
Q_HOME = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])


def summary(cpu_ns: Sequence[int], wall_ns: Sequence[int]) -> dict[str, Any]:
    """Per clock (``"cpu"``, ``"wall"``): p50, p99.9 [s] of per-call times in ns and their ratio; and the number
    of calls."""
    out: dict[str, Any] = {"calls": len(cpu_ns)}
    for name, samples in (("cpu", cpu_ns), ("wall", wall_ns)):
        p50, p999 = (float(v) * 1e-9 for v in np.percentile(np.asarray(samples, dtype=float), [50.0, 99.9]))
        out[name] = {"p50_s": p50, "p999_s": p999, "tail_ratio": p999 / p50}
    return out


class _Timer:
    """Per-call samples on both clocks."""

    def __init__(self, steps: int) -> None:
        self.cpu = np.empty(steps, dtype=np.int64)
        self.wall = np.empty(steps, dtype=np.int64)

    def summary(self) -> dict[str, Any]:
        return summary(self.cpu.tolist(), self.wall.tolist())


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
    for k in range(steps):
        w0, c0 = wall(), cpu()
        tau = ctrl(k * dt, q, qd, refs[k])
        c1, w1 = cpu(), wall()
        timer.cpu[k], timer.wall[k] = c1 - c0, w1 - w0
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
        for t, q, qd, ref in states:
            if k == steps:
                break
            w0, c0 = wall(), cpu()
            ctrl(t, q, qd, ref)
            c1, w1 = cpu(), wall()
            timer.cpu[k], timer.wall[k] = c1 - c0, w1 - w0
            k += 1
    return timer.summary()


def tail_text(t: dict[str, Any]) -> str:
    """One line of a tail's figures: p50, p99.9 and their ratio on the CPU clock, and the wall clock's ratio."""
    c, w = t["cpu"], t["wall"]
    return (
        f"CPU p50 {c['p50_s'] * 1e6:.2f} µs, p99.9 {c['p999_s'] * 1e6:.2f} µs, p99.9 / p50 {c['tail_ratio']:.2f}; "
        f"wall p99.9 / p50 {w['tail_ratio']:.2f}"
    )
