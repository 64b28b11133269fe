"""``armctl`` command line: ``armctl bench`` (the main job) and ``armctl demo``; ``armctl --version``."""

from __future__ import annotations

import argparse
import sys
import tempfile
import textwrap
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

    run_suite(quick=args.quick, out=Path(args.out), sections=args.section, scenes=args.scene)
    written = Path(args.out) / "figures.json"
    print(f"\nwrote {written} ({written.stat().st_size} bytes), the charts and report.html")
    return 0


def _bench_choice(kind: str, given: list[str] | None, valid: tuple[str, ...], extra: str = "") -> str | None:
    """Why a --scene or --section value is not one (None if every one is): the valid names, one line."""
    for name in given or ():
        if name not in valid:
            return f"unknown {kind} {name!r}; valid {kind}s: {', '.join(valid)}{extra}"
    return None


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
    from armctl.bench.sections import DURATION, SCENE_NAMES, SECTION_TITLES

    sections = "\n".join(f"  {k:17s} {t}" for k, t in SECTION_TITLES.items())
    b = sub.add_parser(
        "bench",
        help="run the benchmark and write figures.json, the charts and report.html",
        description=textwrap.fill(
            "Run armctl's benchmark: every scene × controller (tracking error, compute time, limits, a 3D playback "
            "of each scene), stability maps, TOPP convergence, the cost against the accuracy of the dynamics "
            "backends, integrators, models and plant engines, and the speed of the dynamics, the control steps and "
            "the QP step. Writes OUT/figures.json (every number), the charts and OUT/report.html (one page that "
            f"loads nothing from the network). A whole run takes {DURATION['full']} on 2 cores, --quick "
            f"{DURATION['quick']}; a first run also builds the generated C code, a few minutes more.",
            100,
        ),
        epilog=(
            f"sections (--section), in the order they run:\n{sections}\n"
            f"scenes (--scene): {', '.join(SCENE_NAMES)}\n\n"
            "examples:\n  armctl bench --quick --out bench-out\n  armctl bench --scene pendulum --out bench-out\n"
            "  armctl bench --section stability_maps --section topp_convergence --quick"
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    b.add_argument(
        "--quick",
        action="store_true",
        help=f"a short run ({DURATION['quick']} on 2 cores): coarser grids, shorter runs, fewer repetitions",
    )
    b.add_argument("--out", default="bench-out", help="output folder, created if missing (default: bench-out)")
    b.add_argument(
        "--section",
        action="append",
        metavar="NAME",
        help="run this section only (repeat for more; names below); default: every section",
    )
    b.add_argument(
        "--scene",
        action="append",
        metavar="NAME",
        help="run the scene matrix on this scene only (repeat for more; names below); alone, it runs the "
        "scenes section only",
    )
    b.set_defaults(func=_bench)
    models = ["pendulum", "planar_2r", "planar_3r", "puma560", "panda", "ur5"]
    d = sub.add_parser(
        "demo",
        help="print the dynamics terms of a built-in arm",
        description=(
            "Print the dynamics terms of a built-in arm at one state (q spread over ±0.5 rad, q̇ = 0.3 rad/s on "
            "every joint): the mass matrix M(q), the gravity torque g(q), the Coriolis and centrifugal torque "
            "C(q, q̇) q̇, the friction torque and the inverse dynamics τ(q, q̇, 0)."
        ),
    )
    d.add_argument("--model", default="panda", choices=models, help="the arm (default: panda)")
    d.add_argument(
        "--backend",
        default="pinocchio",
        choices=["pinocchio", "lagrange"],
        help="the dynamics backend: pinocchio (fast) or lagrange (symbolic, CasADi); default: pinocchio",
    )
    d.set_defaults(func=_demo)
    args = parser.parse_args(argv)
    if args.command is None:  # a bare ``armctl``: what it can do
        parser.print_help()
        return 0
    if args.command == "bench":  # before the (long) run: a bad --out would only fail at its end
        from armctl.bench.sections import SCENE_NAMES, available_sections, missing_extra

        engines = missing_extra("engines")
        extra = "" if engines is None else f" (engines needs MuJoCo: {engines['command']})"
        problem = (
            _bench_choice("section", args.section, available_sections(), extra)
            or _bench_choice("scene", args.scene, SCENE_NAMES)
            or (
                "--scene runs the scene matrix: add --section scenes, or drop --scene"
                if args.scene and args.section and "scenes" not in args.section
                else None
            )
            or _output_folder(args.out)
        )
        if problem is not None:
            b.error(problem)  # prints the usage and the one-line error, exits with status 2
    return int(args.func(args))


if __name__ == "__main__":
    sys.exit(main())
