"""``armctl`` command line: ``armctl bench`` (the main job) and ``armctl demo``."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any


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
    print("tau(q,qd,0) =", dyn.inverse_dynamics(q, qd, np.zeros(model.n)))
    return 0


def _bench(args: argparse.Namespace) -> int:
    from armctl.bench.suite import run_suite

    figures: dict[str, Any] = run_suite(quick=args.quick, out=Path(args.out))
    print(f"\nwrote {Path(args.out) / 'figures.json'} ({len(json.dumps(figures))} bytes)")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="armctl", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    b = sub.add_parser("bench", help="run the benchmark suite and write figures.json, charts and report.html")
    b.add_argument("--quick", action="store_true", help="a sub-minute run with fewer repetitions")
    b.add_argument("--out", default="bench-out", help="output folder (default: bench-out)")
    b.set_defaults(func=_bench)
    d = sub.add_parser("demo", help="print the dynamics terms of a built-in arm")
    d.add_argument("--model", default="panda", choices=["pendulum", "planar_2r", "planar_3r", "puma560", "panda",
                                                         "ur5"])
    d.add_argument("--backend", default="pinocchio", choices=["pinocchio", "lagrange"])
    d.set_defaults(func=_demo)
    args = parser.parse_args(argv)
    return int(args.func(args))


if __name__ == "__main__":
    sys.exit(main())
