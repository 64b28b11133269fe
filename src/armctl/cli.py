"""``armctl`` command line: ``armctl bench`` (the main job) and ``armctl demo``; ``armctl --version``."""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path


def _demo(args: argparse.Namespace) -> int:
    import numpy as np

    import armctl

    model = getattr(armctl.models, args.model)()
    dyn = armctl.Dynamics(model, backend=args.backend)
    q = np.linspace(-0.5, 0.5, model.n)
    qd = np.full(model.n, 0.3)
    np.set_printoptions(precision=4, suppress=True, linewidth=120)
    print(f"{model.name}: {model.n} joints, backend {dyn.backend}, tool frame {model.tool_frame!r}")
    print("q         =", q)
    print("M(q)      =\n", dyn.mass_matrix(q))
    print("g(q)      =", dyn.gravity_torque(q))
    print("C(q,qd)qd =", dyn.coriolis_matrix(q, qd) @ qd)
    print("friction  =", dyn.friction_torque(qd))
    print("tau(q,qd,0) =", dyn.inverse_dynamics(q, qd, np.zeros(model.n)), " (= C qd + g + friction)")
    return 0


def _output_folder(out: str) -> str | None:
    """Why ``out`` cannot be the bench's output folder (None if it can): it must be a non-empty path to a folder
    that exists or can be created, and that can be written to. Creates the folder (as the bench would)."""
    if not out.strip():
        return "--out must name a folder, got an empty path; give e.g. --out bench-out"
    path = Path(out)
    if path.exists() and not path.is_dir():
        return f"--out {out!r} exists and is not a folder; give a new or existing folder"
    try:
        path.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=path):  # writable? (root may pass os.access on a read-only mount)
            pass
    except OSError as e:
        return f"--out {out!r} cannot be created or written to ({e.strerror or e}); give a writable folder"
    return None


def _bench(args: argparse.Namespace) -> int:
    from armctl.bench.suite import run_suite

    run_suite(quick=args.quick, out=Path(args.out))
    written = Path(args.out) / "figures.json"
    print(f"\nwrote {written} ({written.stat().st_size} bytes), the charts and report.html")
    return 0


def _version() -> str:
    """The installed armctl's version (``armctl.__version__``)."""
    from armctl import __version__

    return __version__


def main(argv: list[str] | None = None) -> int:
    """Run the command line with ``argv`` (default: ``sys.argv[1:]``); returns the exit status."""
    parser = argparse.ArgumentParser(
        prog="armctl", description="armctl: model-based control and planning of robot manipulators."
    )
    parser.add_argument("--version", action="version", version=f"armctl {_version()}")
    sub = parser.add_subparsers(dest="command", title="commands")
    b = sub.add_parser("bench", help="run the benchmark suite and write figures.json, charts and report.html")
    b.add_argument(
        "--quick", action="store_true", help="a short run (1–2 minutes on 2 cores): coarser grids, fewer repetitions"
    )
    b.add_argument("--out", default="bench-out", help="output folder (default: bench-out)")
    b.set_defaults(func=_bench)
    d = sub.add_parser("demo", help="print the dynamics terms of a built-in arm")
    d.add_argument(
        "--model", default="panda", choices=["pendulum", "planar_2r", "planar_3r", "puma560", "panda", "ur5"]
    )
    d.add_argument("--backend", default="pinocchio", choices=["pinocchio", "lagrange"])
    d.set_defaults(func=_demo)
    args = parser.parse_args(argv)
    if args.command is None:  # a bare ``armctl``: what it can do
        parser.print_help()
        return 0
    if args.command == "bench":  # before the (long) run: a bad --out would only fail at its end
        problem = _output_folder(args.out)
        if problem is not None:
            b.error(problem)  # prints the usage and the one-line error, exits with status 2
    return int(args.func(args))


if __name__ == "__main__":
    sys.exit(main())
