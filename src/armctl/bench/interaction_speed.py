"""Cost of one step of the interaction controllers through the public API on the Panda, as a ratio to one raw
Pinocchio RNEA call measured in the same run (paired rounds). Run: ``python -m armctl.bench.interaction_speed``.

Rows: Cartesian impedance with a given damping (the stiffness alone, no Λ), with the default damping (Λ(q) and
its double diagonalisation at every step) and with null-space stiffness; joint impedance; force control and
parallel force/position control with the computed-torque inner loop; admittance with the computed-torque inner
loop. The force-reading laws are called with a measured wrench, as in a user's loop. The momentum observer's
``update(t, q, qd, tau_applied)`` (:func:`observer_rows`): as generated code (its default), and on the Pinocchio
kernel (``compile=False``), with collision thresholds."""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from typing import Any

import numpy as np

import armctl
from armctl.bench.timing import paired_ratio

#: the benchmark's own checks (its tests), not printed: the largest ratio to RNEA each step should keep
TARGETS = {"CartesianImpedance": 3.0, "ForceControl (inner CT)": 4.0, "MomentumObserver.update": 2.0}

Q_READY = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])


def controllers(dyn: armctl.Dynamics) -> dict[str, Any]:
    """The timed laws by row name."""
    from armctl.controllers import (
        Admittance,
        CartesianImpedance,
        ForceControl,
        JointImpedance,
        ParallelForcePosition,
    )

    k = [800.0, 800.0, 800.0, 50.0, 50.0, 50.0]
    d = [60.0, 60.0, 60.0, 5.0, 5.0, 5.0]
    return {
        "CartesianImpedance": CartesianImpedance(dyn, k, d),
        "CartesianImpedance (damping from Λ(q))": CartesianImpedance(dyn, k),
        "CartesianImpedance (null space)": CartesianImpedance(dyn, k, d, nullspace_stiffness=10.0),
        "JointImpedance": JointImpedance(dyn, 300.0, 30.0),
        "ForceControl (inner CT)": ForceControl(dyn, [0.0, 0.0, -10.0], 2e-4, 1e-3, directions=[0.0, 0.0, 1.0]),
        "ParallelForcePosition (inner CT)": ParallelForcePosition(dyn, [0.0, 0.0, -10.0], 2e-4, 1e-3),
        "Admittance (inner CT)": Admittance(dyn, k),
    }


def run(number: int = 200, rounds: int = 41, seed: int = 0) -> dict[str, Any]:
    import pinocchio as pin

    from armctl.controllers import Measurement

    model = armctl.models.panda()
    dyn = armctl.Dynamics(model)
    pm = model.to_pinocchio()
    pd = pm.createData()
    rng = np.random.default_rng(seed)
    q = Q_READY + rng.uniform(-0.2, 0.2, model.n)
    qd, qdd = rng.uniform(-0.5, 0.5, (2, model.n))
    ref = armctl.Reference(Q_READY)
    meas = Measurement(wrench=np.array([0.0, 0.0, -10.0, 0.0, 0.0, 0.0]), world_axes=True)
    out: dict[str, Any] = {"model": model.name}
    for name, c in controllers(dyn).items():
        clock = itertools.count(1e-3, 1e-3)
        m = meas if c.reads else None

        def step(c: Any = c, clock: Iterator[float] = clock, m: Any = m) -> Any:
            return c(next(clock), q, qd, ref, measurement=m)

        r = paired_ratio(step, lambda: pin.rnea(pm, pd, q, qd, qdd), number, rounds)
        out[name] = _row(r)
    out.update(observer_rows(number, rounds, seed))
    return out


def _row(r: dict[str, float]) -> dict[str, Any]:
    return {
        "step_s": r["candidate_s"],
        "rnea_s": r["reference_s"],
        "ratio": r["ratio"],
        "ratio_iqr": (r["ratio_q1"], r["ratio_q3"]),
    }


def observer_rows(number: int = 200, rounds: int = 41, seed: int = 0) -> dict[str, Any]:
    """One ``MomentumObserver.update`` on the Panda at 1 kHz against one raw RNEA: as generated code (the default,
    ``compile="auto"``; skipped, with the reason, where it cannot be built) and on the Pinocchio kernel
    (``compile=False``)."""
    import pinocchio as pin

    from armctl.controllers import MomentumObserver
    from armctl.errors import BackendError

    model = armctl.models.panda()
    pm = model.to_pinocchio()
    pd = pm.createData()
    rng = np.random.default_rng(seed)
    q = Q_READY + rng.uniform(-0.2, 0.2, model.n)
    qd, tau = rng.uniform(-0.5, 0.5, (2, model.n))
    out: dict[str, Any] = {}
    dyn = armctl.Dynamics(model)
    variants = {"MomentumObserver.update": True, "MomentumObserver.update (compile=False)": False}
    for name, compiled in variants.items():
        try:
            obs = MomentumObserver(dyn, 50.0, thresholds=1e3, compile=compiled)
        except BackendError as exc:
            out["observer_compile_unavailable"] = str(exc)
            continue
        clock = itertools.count(0.0, 1e-3)

        def update(obs: Any = obs, clock: Iterator[float] = clock) -> Any:
            return obs.update(next(clock), q, qd, tau)

        out[name] = _row(paired_ratio(update, lambda: pin.rnea(pm, pd, q, qd, tau), number, rounds))
    return out


def report(fig: dict[str, Any]) -> str:
    lines = [f"interaction control step on {fig['model']}, ratio to one raw RNEA (median of per-round ratios)"]
    for name, f in fig.items():
        if not isinstance(f, dict):
            continue
        q1, q3 = f["ratio_iqr"]
        lines.append(
            f"  {name:40s} {f['step_s'] * 1e6:7.2f} µs  RNEA {f['rnea_s'] * 1e6:5.2f} µs  ratio "
            f"{f['ratio']:5.2f} [{q1:.2f}, {q3:.2f}]"
        )
    return "\n".join(lines)


def beyond_targets(fig: dict[str, Any]) -> list[str]:
    """The rows whose ratio to RNEA is above its :data:`TARGETS` entry."""
    return [
        f"{name}: ratio {fig[name]['ratio']:.2f} > {target}"
        for name, target in TARGETS.items()
        if name in fig and fig[name]["ratio"] > target
    ]


def main() -> None:
    print(report(run()))


if __name__ == "__main__":
    main()
