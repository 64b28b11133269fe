"""Speed of the dynamics through armctl's public API against raw Pinocchio, on the Panda (7 joints).

Run: ``python -m armctl.bench.dynamics_speed``. Prints per-call medians and ratios measured in the same run
(interleaved rounds), the regressors again with ``Dynamics(model, compile=True)`` (generated C code), the
Lagrange backend's symbolic build time and its compiled inverse dynamics against the Pinocchio backend.
:data:`TARGETS` are the benchmark's own checks (its tests call :func:`beyond_targets`); they are not printed.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

import armctl
from armctl.bench.timing import interleaved, paired_ratio
from armctl.errors import BackendError

TARGETS = {
    "mass_matrix": 1.5,
    "inverse_dynamics": 1.5,
    "regressor": 1.5,
    "passivity_regressor": 4.0,
    "lagrange_compiled_inverse_dynamics": 10.0,
    "lagrange_build_seconds": 5.0,
}


def run(number: int = 200, rounds: int = 75, seed: int = 0, compile_if_needed: bool = True) -> dict[str, Any]:
    """Measure; returns a dict of figures (seconds and ratios). ``compile_if_needed=False`` skips the compiled
    Lagrange figure unless its library is already cached (the first compile takes ~20 s)."""
    import pinocchio as pin

    model = armctl.models.panda()
    dyn = armctl.Dynamics(model)
    pm, pd = model.to_pinocchio(), None
    pd = pm.createData()
    rng = np.random.default_rng(seed)
    q, qd, qdd = rng.uniform(-1.5, 1.5, (3, model.n))
    qd_r = 0.9 * qd  # made here, not inside the timed call
    out: dict[str, Any] = {"model": model.name, "n": model.n}
    pairs = {
        "mass_matrix": (lambda: dyn.mass_matrix(q), lambda: pin.crba(pm, pd, q)),
        "inverse_dynamics": (lambda: dyn.inverse_dynamics(q, qd, qdd), lambda: pin.rnea(pm, pd, q, qd, qdd)),
        "regressor": (lambda: dyn.regressor(q, qd, qdd), lambda: pin.computeJointTorqueRegressor(pm, pd, q, qd, qdd)),
        "passivity_regressor": (
            lambda: dyn.passivity_regressor(q, qd, qd_r, qdd),
            lambda: pin.computeJointTorqueRegressor(pm, pd, q, qd, qdd),
        ),
    }
    # the same regressors with Dynamics(model, compile=True): generated C code (built once, ~2 s, then cached)
    t0 = time.perf_counter()
    try:
        dc = armctl.Dynamics(model, compile=True)
    except BackendError as e:  # no C compiler: reported, the rest still measured
        out["compiled_unavailable"] = str(e)
    else:
        out["compiled_build_or_load_seconds"] = time.perf_counter() - t0
        raw = pairs["regressor"][1]
        pairs["compiled_regressor"] = (lambda: dc.regressor(q, qd, qdd), raw)
        pairs["compiled_passivity_regressor"] = (lambda: dc.passivity_regressor(q, qd, qd_r, qdd), raw)
    for name, (api, raw) in pairs.items():
        r = paired_ratio(api, raw, number, rounds)
        out[name] = {
            "api_s": r["candidate_s"],
            "raw_s": r["reference_s"],
            "ratio": r["ratio"],
            "ratio_iqr": (r["ratio_q1"], r["ratio_q3"]),
        }
    t0 = time.perf_counter()
    lag_vm = armctl.Dynamics(model, backend="lagrange")
    out["lagrange_build_seconds"] = time.perf_counter() - t0
    from armctl.dynamics.lagrange import LagrangeDynamics

    if not compile_if_needed and not LagrangeDynamics.is_compiled_cached(model):
        out["lagrange_compiled_inverse_dynamics"] = None
        out["lagrange_compile_or_load_seconds"] = None
        return out
    t0 = time.perf_counter()
    lag = armctl.Dynamics(model, backend="lagrange", compile=True)
    out["lagrange_compile_or_load_seconds"] = time.perf_counter() - t0
    t = interleaved(
        {
            "lag": lambda: lag.inverse_dynamics(q, qd, qdd),
            "pin": lambda: dyn.inverse_dynamics(q, qd, qdd),
            "vm": lambda: lag_vm.inverse_dynamics(q, qd, qdd),
        },
        max(number // 10, 50),
        rounds,
    )
    out["lagrange_compiled_inverse_dynamics"] = {
        "api_s": t["lag"],
        "pinocchio_backend_s": t["pin"],
        "ratio": t["lag"] / t["pin"],
        "casadi_vm_s": t["vm"],
    }
    return out


def report(fig: dict[str, Any]) -> str:
    lines = [
        f"dynamics speed on {fig['model']} ({fig['n']} joints): medians; ratios are medians of per-round "
        "ratios [quartiles]"
    ]
    for name in (
        "mass_matrix",
        "inverse_dynamics",
        "regressor",
        "passivity_regressor",
        "compiled_regressor",
        "compiled_passivity_regressor",
    ):
        if name not in fig:  # compile=True unavailable (no C compiler)
            continue
        f = fig[name]
        q1, q3 = f["ratio_iqr"]
        label = name.replace("compiled_", "") + (" (compile=True)" if name.startswith("compiled_") else "")
        lines.append(
            f"  {label:35s} api {f['api_s'] * 1e6:7.2f} µs  raw {f['raw_s'] * 1e6:7.2f} µs  "
            f"ratio {f['ratio']:5.2f} [{q1:.2f}, {q3:.2f}]"
        )
    if "compiled_unavailable" in fig:
        lines.append(f"  compile=True unavailable: {fig['compiled_unavailable']}")
    elif "compiled_build_or_load_seconds" in fig:
        lines.append(
            f"  compile=True: library built or loaded in {fig['compiled_build_or_load_seconds']:.2f} s "
            "(raw: Pinocchio's regressor in both rows)"
        )
    f = fig["lagrange_compiled_inverse_dynamics"]
    if f is None:
        lines.append("  lagrange compiled tau  skipped: not compiled yet (~20 s; run without --quick once)")
    else:
        lines.append(
            f"  lagrange compiled tau  {f['api_s'] * 1e6:7.2f} µs  pinocchio backend "
            f"{f['pinocchio_backend_s'] * 1e6:6.2f} µs  ratio of medians {f['ratio']:5.2f}; "
            f"CasADi VM {f['casadi_vm_s'] * 1e6:.1f} µs"
        )
    b = fig["lagrange_build_seconds"]
    load = fig["lagrange_compile_or_load_seconds"]
    lines.append(
        f"  lagrange symbolic build {b:.2f} s" + (f"; compile or cached load {load:.2f} s" if load is not None else "")
    )
    return "\n".join(lines)


def beyond_targets(fig: dict[str, Any]) -> list[str]:
    """The figures beyond their :data:`TARGETS` entry (the benchmark's tests check it)."""
    out = []
    for name in ("mass_matrix", "inverse_dynamics", "regressor", "passivity_regressor"):
        for key in (name, f"compiled_{name}"):
            if key in fig and fig[key]["ratio"] > TARGETS[name]:
                out.append(f"{key}: ratio {fig[key]['ratio']:.2f} > {TARGETS[name]}")
    f = fig.get("lagrange_compiled_inverse_dynamics")
    if f is not None and f["ratio"] > TARGETS["lagrange_compiled_inverse_dynamics"]:
        out.append(f"lagrange compiled inverse dynamics: ratio {f['ratio']:.2f}")
    if fig["lagrange_build_seconds"] > TARGETS["lagrange_build_seconds"]:
        out.append(f"lagrange symbolic build: {fig['lagrange_build_seconds']:.2f} s")
    return out


def main() -> None:
    print(report(run()))


if __name__ == "__main__":
    main()
