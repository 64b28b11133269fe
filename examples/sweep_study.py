"""
A 1 000-run study that survives an interruption
===============================================

A parameter study as a data scientist runs it: PD + gravity compensation on the pendulum, 25 stiffnesses × 40
dampings, each run 0.3 s long, on the sweep's own process pool. Every outcome is written to a store folder as it
finishes, so the study survives Ctrl-C: here a thread presses it after 300 runs, and the same call with
``resume=True`` runs only the 700 others. The outcomes become a pandas DataFrame (one row per run: the gains, the
outcome, the metrics), a Parquet file and a chart of the tracking error over the gains.

Needs ``pip install "armctl[data]"`` (pandas, pyarrow).

Run: python examples/sweep_study.py [--out DIR] [--show]
"""

from __future__ import annotations

import _thread
import argparse
import shutil
import threading
import warnings
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import armctl
from armctl.controllers import PDGravity
from armctl.errors import SimulationWarning
from armctl.references import Quintic
from armctl.sim import SimResult, simulate, sweep
from armctl.sim.tables import run_metrics

PENDULUM = armctl.models.pendulum()
REFERENCE = Quintic([0.0], [0.5], duration=0.25)  # 0.5 rad in 0.25 s
STIFFNESS = np.logspace(0.5, 3.0, 25)  # K_p [N·m/rad]
DAMPING = np.logspace(-1.5, 1.5, 40)  # K_d [N·m·s/rad]
INTERRUPT_AFTER = 300  # runs


def run(kp: float, kd: float) -> SimResult:
    """One run of the study: the pendulum under PD + gravity for 0.3 s, with its 20 N·m torque limit,
    controlled at 500 Hz. A saturated motor is in the result's status, so its warning is not repeated here."""
    controller = PDGravity(armctl.Dynamics(PENDULUM), kp, kd)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SimulationWarning)
        return simulate(PENDULUM, controller, REFERENCE, 0.3, control_dt=2e-3, max_velocity=50.0)


def press_ctrl_c_after(store: Path, runs: int, done: threading.Event) -> None:
    """Interrupt the main thread (as Ctrl-C does) once the store holds ``runs`` outcomes."""
    while not done.wait(0.01):
        if len(list((store / "outcomes").glob("*.pkl"))) >= runs:
            _thread.interrupt_main()
            return


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=Path("example-out"), help="folder for the files written")
    parser.add_argument("--show", action="store_true", help="show the chart in a window")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    store = args.out / "sweep_study_store"
    shutil.rmtree(store, ignore_errors=True)  # a fresh study each time the example runs

    cases = [{"kp": float(kp), "kd": float(kd)} for kp in STIFFNESS for kd in DAMPING]
    options = {"run": run, "summary": run_metrics, "store": store, "progress": False}

    # the first attempt, interrupted: every finished outcome is already in the store
    done = threading.Event()
    threading.Thread(target=press_ctrl_c_after, args=(store, INTERRUPT_AFTER, done), daemon=True).start()
    try:
        sweep(cases, **options)
    except KeyboardInterrupt as exc:
        print("interrupted:", *getattr(exc, "__notes__", exc.args))
    finally:
        done.set()

    # the same call with resume=True runs only the cases the store does not hold
    results = sweep(cases, resume=True, **options)
    print(results)

    table = results.to_dataframe()  # one row per case: kp, kd, outcome, status, error_rms, tau_peak, ...
    print(table[["kp", "kd", "outcome", "status", "error_rms", "tau_peak"]].head())
    print(table.groupby("status")["error_rms"].describe()[["count", "mean", "min", "max"]])
    best = table[table["status"] == "ok"].sort_values("error_rms").iloc[0]
    print(f"smallest RMS error without saturating: K_p = {best.kp:.4g}, K_d = {best.kd:.4g}: {best.error_rms:.3g} rad")
    parquet = args.out / "sweep_study.parquet"
    table.to_parquet(parquet)

    # the tracking error over the gains; the cells whose motor saturated are hatched
    grid = table.pivot(index="kd", columns="kp", values="error_rms")
    saturated = table.pivot(index="kd", columns="kp", values="status") != "ok"
    fig, ax = plt.subplots(figsize=(7, 4.5), layout="constrained")
    mesh = ax.pcolormesh(grid.columns, grid.index, np.log10(grid.to_numpy()), shading="nearest", cmap="viridis")
    ax.contourf(grid.columns, grid.index, saturated.to_numpy(), levels=[0.5, 1.5], hatches=["//"], colors="none")
    inertia = float(armctl.Dynamics(PENDULUM).mass_matrix([0.0])[0, 0])
    ax.plot(STIFFNESS, 2 * np.sqrt(inertia * STIFFNESS), "w--", lw=1, label="critical damping $2\\sqrt{J K_p}$")
    ax.set(xscale="log", yscale="log", xlabel="$K_p$ [N·m/rad]", ylabel="$K_d$ [N·m·s/rad]")
    ax.set_title("PD + gravity on the pendulum (hatched: torque saturated)")
    ax.legend(loc="lower right")
    fig.colorbar(mesh, ax=ax, label="log₁₀ RMS error [rad]")
    chart = args.out / "sweep_study.png"
    fig.savefig(chart, dpi=110)
    for path in (store, parquet, chart):
        print(f"wrote {path}")
    if args.show:
        plt.show()


if __name__ == "__main__":
    main()
