"""Cost of one control step through the public API on the Panda, as a ratio to one raw Pinocchio RNEA call
measured in the same run (interleaved rounds), each law on the Pinocchio backend (its default path: the Slotine–Li
laws as one generated call), again on ``Dynamics(model, compile=True)``, and the Slotine–Li laws with
``compile=False`` (their NumPy path); and the spread of each law's per-call cost over a 20 000-step closed loop on the
Panda with the ``panda_topp`` scene's gains (p50, p99.9 and their ratio, :func:`~armctl.bench.tails.law_tail`, each
beside a NumPy floor of the same median timed between its calls, and the machine's CPU-clock jumps,
:func:`~armctl.bench.tails.clock_jumps`). Run:
``python -m armctl.bench.controller_speed``."""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from typing import Any

import numpy as np

import armctl
from armctl.bench.tails import clock_jumps, jumps_text, law_tail, tail_text
from armctl.bench.timing import paired_ratio
from armctl.errors import BackendError

#: the benchmark's own checks (its tests), not printed: the largest ratio to RNEA each law's step should keep
TARGETS = {"PDGravity": 3.0, "ComputedTorque": 4.0, "PassivityBased": 3.0, "Adaptive": 5.0}
#: and the largest p99.9 / p50 of a law's per-call CPU time over the long run
TAIL_TARGET = 4.0


def run(number: int = 200, rounds: int = 75, seed: int = 0, tail_steps: int = 20_000) -> dict[str, Any]:
    """Measure: per law (and per law on compiled dynamics) the step's cost, and with ``tail_steps`` > 0 the
    spread of its per-call cost over a closed loop of that many steps (``"tails"``; the laws with the ``panda_topp``
    scene's gains)."""
    import pinocchio as pin

    from armctl.controllers import Adaptive, ComputedTorque, PassivityBased, PDGravity

    model = armctl.models.panda()
    dyn = armctl.Dynamics(model)
    pm = model.to_pinocchio()
    pd = pm.createData()
    rng = np.random.default_rng(seed)
    q, qd, qdd = rng.uniform(-1.0, 1.0, (3, model.n))
    ref = armctl.Reference(q + 0.01, qd, qdd)
    variants = {"": dyn}
    out: dict[str, Any] = {"model": model.name}
    try:  # the same laws on Dynamics(model, compile=True): generated C code for g, the passivity terms, Y
        variants["compiled"] = armctl.Dynamics(model, compile=True)
    except BackendError as e:  # no C compiler
        out["compiled_unavailable"] = str(e)
    variants["numpy"] = dyn
    for variant, d in variants.items():
        controllers: dict[str, Any] = {
            "PDGravity": PDGravity(d, 100.0, 20.0),
            "ComputedTorque": ComputedTorque(d, 100.0, 20.0),
            "PassivityBased": PassivityBased(d, 5.0, 20.0),
            "Adaptive": Adaptive(d, 5.0, 20.0, 0.01),
        }
        if variant == "numpy":  # the laws that run generated code of their own by default, without it
            controllers = {
                "PassivityBased": PassivityBased(d, 5.0, 20.0, compile=False),
                "Adaptive": Adaptive(d, 5.0, 20.0, 0.01, compile=False),
            }
        for name, c in controllers.items():
            clock = itertools.count(1e-3, 1e-3)  # Python floats; the adaptive law integrates between calls

            def step(c: Any = c, clock: Iterator[float] = clock) -> Any:
                return c(next(clock), q, qd, ref)

            r = paired_ratio(
                step,
                lambda: pin.rnea(pm, pd, q, qd, qdd),
                number,
                rounds,
            )
            fig = {
                "step_s": r["candidate_s"],
                "rnea_s": r["reference_s"],
                "ratio": r["ratio"],
                "ratio_iqr": (r["ratio_q1"], r["ratio_q3"]),
            }
            if variant:
                out.setdefault(variant, {})[name] = fig
            else:
                out[name] = fig
    if tail_steps:
        from armctl.scenes import panda_topp  # the laws with the gains tuned for the Panda (stable closed loops)

        sc = panda_topp()
        laws = {"PDGravity": "pd_gravity", "ComputedTorque": "computed_torque", "PassivityBased": "passivity"}
        laws["Adaptive"] = "adaptive"
        out["tails"] = {name: law_tail(sc.controller(method), tail_steps) for name, method in laws.items()}
        out["clock_jumps"] = clock_jumps()
    return out


def report(fig: dict[str, Any]) -> str:
    lines = [f"control step on {fig['model']}, ratio to one raw RNEA (median of per-round ratios, quartiles)"]
    for label, figs in (
        ("", fig),
        (" (compile=True)", fig.get("compiled", {})),
        (" (law compile=False)", fig.get("numpy", {})),
    ):
        for name in TARGETS:
            if name not in figs:
                continue
            f = figs[name]
            q1, q3 = f["ratio_iqr"]
            lines.append(
                f"  {name + label:36s} {f['step_s'] * 1e6:7.2f} µs  RNEA {f['rnea_s'] * 1e6:5.2f} µs  ratio "
                f"{f['ratio']:5.2f} [{q1:.2f}, {q3:.2f}]"
            )
    if "compiled_unavailable" in fig:
        lines.append(f"  compile=True unavailable: {fig['compiled_unavailable']}")
    for name, t in fig.get("tails", {}).items():
        lines.append(f"  {name:30s} per call over a {t['calls']}-step closed loop: {tail_text(t)}")
    if "clock_jumps" in fig:
        lines.append(f"  {jumps_text(fig['clock_jumps'])}")
    return "\n".join(lines)


def beyond_targets(fig: dict[str, Any]) -> list[str]:
    """The laws whose ratio to RNEA is above its :data:`TARGETS` entry (the benchmark's tests check it)."""
    out = []
    for label, figs in (("", fig), (" (compile=True)", fig.get("compiled", {}))):
        for name, target in TARGETS.items():
            if name in figs and figs[name]["ratio"] > target:
                out.append(f"{name}{label}: ratio {figs[name]['ratio']:.2f} > {target}")
    for name, t in fig.get("tails", {}).items():
        if t["cpu"]["tail_ratio"] > TAIL_TARGET:
            out.append(f"{name}: p99.9 / p50 {t['cpu']['tail_ratio']:.2f} > {TAIL_TARGET}")
    return out


def main() -> None:
    print(report(run()))


if __name__ == "__main__":
    main()
