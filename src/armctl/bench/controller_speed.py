"""Cost of one control step through the public API on the Panda, as a ratio to one raw Pinocchio RNEA call
measured in the same run (interleaved rounds), each law on the Pinocchio backend and again on
``Dynamics(model, compile=True)``. Run: ``python -m armctl.bench.controller_speed``."""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from typing import Any

import numpy as np

import armctl
from armctl.bench.timing import paired_ratio
from armctl.errors import BackendError

#: the benchmark's own checks (its tests), not printed: the largest ratio to RNEA each law's step should keep
TARGETS = {"PDGravity": 3.0, "ComputedTorque": 4.0, "PassivityBased": 7.0, "Adaptive": 14.0}


def run(number: int = 200, rounds: int = 75, seed: int = 0) -> dict[str, Any]:
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
    for variant, d in variants.items():
        controllers = {
            "PDGravity": PDGravity(d, 100.0, 20.0),
            "ComputedTorque": ComputedTorque(d, 100.0, 20.0),
            "PassivityBased": PassivityBased(d, 5.0, 20.0),
            "Adaptive": Adaptive(d, 5.0, 20.0, 0.01),
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
    return out


def report(fig: dict[str, Any]) -> str:
    lines = [f"control step on {fig['model']}, ratio to one raw RNEA (median of per-round ratios, quartiles)"]
    for label, figs in (("", fig), (" (compile=True)", fig.get("compiled", {}))):
        for name in TARGETS:
            if name not in figs:
                continue
            f = figs[name]
            q1, q3 = f["ratio_iqr"]
            lines.append(
                f"  {name + label:30s} {f['step_s'] * 1e6:7.2f} µs  RNEA {f['rnea_s'] * 1e6:5.2f} µs  ratio "
                f"{f['ratio']:5.2f} [{q1:.2f}, {q3:.2f}]"
            )
    if "compiled_unavailable" in fig:
        lines.append(f"  compile=True unavailable: {fig['compiled_unavailable']}")
    return "\n".join(lines)


def beyond_targets(fig: dict[str, Any]) -> list[str]:
    """The laws whose ratio to RNEA is above its :data:`TARGETS` entry (the benchmark's tests check it)."""
    out = []
    for label, figs in (("", fig), (" (compile=True)", fig.get("compiled", {}))):
        for name, target in TARGETS.items():
            if name in figs and figs[name]["ratio"] > target:
                out.append(f"{name}{label}: ratio {figs[name]['ratio']:.2f} > {target}")
    return out


def main() -> None:
    print(report(run()))


if __name__ == "__main__":
    main()
