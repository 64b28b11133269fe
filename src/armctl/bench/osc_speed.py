"""Cost of one operational-space QP control step on the Panda, against one raw RNEA and against a bare proxsuite
solve of the same QPs, on two sets of states, with the controller as made by default (``compile="auto"``: the QP's
data from generated code where a C compiler builds it) and with ``compile=False`` (Pinocchio's terms, the QP rows
in NumPy), both on ``Dynamics(panda)``.

Run: ``python -m armctl.bench.osc_speed [--quick]``. With an active contact (figures ``contact``, ``scene``
and ``scene["tail"]``): see :mod:`~armctl.bench.osc_contact`.

Set-up: pose task on the tool frame (kp 400) + posture task (kp 100, weight 1e-3, the same level) + the URDF's
torque limits; the QP on [q̈; τ] has 14 variables, 7 equality and 7 inequality rows (the controller solves it on
q̈ alone). Two sets of states, each run through one controller in turn, as a loop would:

* ``circle``: the controller on its own model along a 10 cm circle (the QPs change smoothly from step to step);
  the circle is sampled at the control instants beforehand, so that a step pays a table lookup for its target
  (still checked by the task) instead of the trajectory's own arithmetic;
* ``random``: states near the ready pose, q = ready + N(0, 0.1 rad), q̇ = N(0, 0.3 rad/s), the pose target the
  ready pose's tool pose (each step's QP unrelated to the previous one).

Measured per set and dynamics, as CPU time of this process in interleaved rounds (ratios taken round by round,
then their median and quartiles):

* ``step``: ``controller(t, q, q̇, ref)`` — input checks, model terms, QP build, solve, optimality check, τ;
* ``rnea``: one raw ``pinocchio.rnea`` at the same states;
* ``bare_solve``: proxsuite dense ``update`` + ``solve`` of the same QPs (H, g, A, b, C, l, u of
  ``ctrl.build(...).problem(0)``), warm-started from the previous one — the solver alone, unchecked;
* ``check``: the optimality check of each step's solution, run again (``verify_last_step``);

and, on one pass: the QPs solved by each stage of the solver chain (``stages``; fallbacks are "cold",
"defaults", "second") and the steps whose τ differs from quadprog's cold optimum by more than 1e-4 N·m
(``wrong``, if quadprog is installed). On the circle with Pinocchio's terms also the closed-form OSC baseline
and proxsuite's one-shot cold ``dense.solve``, for reference. The figures of ``compile=False`` are under
``"numpy"``; ``"generated"`` says whether the default took generated code.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np

import armctl
from armctl.bench.osc_contact import check_time, contact_checks, report_lines
from armctl.bench.timing import interleaved_samples
from armctl.controllers.osc import (
    ClosedFormOSC,
    FramePoseTask,
    OperationalSpaceQP,
    PostureTask,
    QPArrays,
    TorqueLimit,
)

#: what the checks of this benchmark ask: the default step within 15 RNEA on both sets of states; with a
#: contact, the fixed-contact step and the panda_contact scene's controller within their ratios to RNEA, and the
#: scene's p99.9 per-call time within 4 medians
TARGETS = {"ratio_rnea": 15.0, "contact_ratio_rnea": 12.0, "scene_ratio_rnea": 25.0, "tail_ratio": 4.0}

Q_HOME = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
States = list[tuple[float, np.ndarray, np.ndarray]]


def _circle(center: np.ndarray, rot: np.ndarray, radius: float = 0.05, freq: float = 0.5) -> Any:
    """Pose trajectory t -> (pose, twist, acceleration): a horizontal circle through ``center``, constant
    orientation ``rot``."""
    w = 2 * math.pi * freq
    base = np.eye(4)
    base[:3, :3] = rot
    base[:3, 3] = center
    base[0, 3] -= radius

    def fn(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        c, s = math.cos(w * t), math.sin(w * t)
        pose = base.copy()
        pose[0, 3] += radius * c
        pose[1, 3] += radius * s
        twist = np.array([-radius * w * s, radius * w * c, 0.0, 0.0, 0.0, 0.0])
        acc = np.array([-radius * w * w * c, -radius * w * w * s, 0.0, 0.0, 0.0, 0.0])
        return pose, twist, acc

    return fn


class _Sampled:
    """A trajectory t -> (pose, twist, acceleration) sampled at the control instants k·dt (a table lookup per
    call), so that the step time counts the controller, not the user's trajectory code."""

    def __init__(self, fn: Any, dt: float, count: int) -> None:
        self.dt = dt
        self.table = [fn(k * dt) for k in range(count)]

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.table[min(round(t / self.dt), len(self.table) - 1)]


def _controller(dyn: armctl.Dynamics, pose: FramePoseTask, compile: bool | str = "auto") -> OperationalSpaceQP:
    tasks = [pose, PostureTask(dyn.n, kp=100.0, weight=1e-3)]
    return OperationalSpaceQP(dyn, tasks, limits=[TorqueLimit()], compile=compile)


def circle_controller(
    dyn: armctl.Dynamics, count: int, dt: float = 1e-3, compile: bool | str = "auto"
) -> tuple[OperationalSpaceQP, FramePoseTask]:
    """The controller following the circle (sampled at ``count`` control instants) on ``dyn``, and its pose
    task."""
    pose0 = dyn.frame_pose(Q_HOME)
    pose = FramePoseTask(kp=400.0)
    pose.set_trajectory(_Sampled(_circle(pose0[:3, 3], pose0[:3, :3]), dt, count))
    return _controller(dyn, pose, compile), pose


def states(count: int, dt: float = 1e-3) -> tuple[States, Any, Any]:
    """``count`` (t, q, q̇) along the circle, from the controller acting on its own model (semi-implicit
    Euler), and the QP and closed-form controllers to time."""
    dyn = armctl.Dynamics(armctl.models.panda())
    ctrl, pose = circle_controller(dyn, count, dt)
    closed = ClosedFormOSC(dyn, pose, PostureTask(dyn.n, kp=100.0, weight=1e-3))
    ref = armctl.Reference(Q_HOME)
    q, qd = Q_HOME.copy(), np.zeros(dyn.n)
    seq = []
    for k in range(count):
        t = k * dt
        seq.append((t, q.copy(), qd.copy()))
        tau = ctrl(t, q, qd, ref)
        qd = qd + dt * dyn.forward_dynamics(q, qd, tau)
        q = q + dt * qd
    ctrl.reset()
    return seq, ctrl, closed


def random_states(
    count: int, seed: int = 0, dyn: armctl.Dynamics | None = None, compile: bool | str = "auto"
) -> tuple[States, OperationalSpaceQP]:
    """``count`` states near the ready pose (q = ready + N(0, 0.1), q̇ = N(0, 0.3)) and the controller on ``dyn``
    (default: the Panda's Pinocchio dynamics), whose pose target is the ready pose's tool pose."""
    dyn = dyn if dyn is not None else armctl.Dynamics(armctl.models.panda())
    pose = FramePoseTask(kp=400.0)
    pose.set_target(dyn.frame_pose(Q_HOME))
    rng = np.random.default_rng(seed)
    seq = [(0.0, Q_HOME + rng.normal(0.0, 0.1, dyn.n), rng.normal(0.0, 0.3, dyn.n)) for _ in range(count)]
    return seq, _controller(dyn, pose, compile)


def _ratio(num: list[float], den: list[float]) -> tuple[float, tuple[float, float]]:
    """Median and quartiles of the per-round ratios."""
    q1, med, q3 = statistics.quantiles([a / b for a, b in zip(num, den, strict=True)], n=4)
    return med, (q1, q3)


def _cycle(seq: States) -> Callable[[], tuple[float, np.ndarray, np.ndarray]]:
    count, i = len(seq), [0]

    def nxt() -> tuple[float, np.ndarray, np.ndarray]:
        k = i[0]
        i[0] = (k + 1) % count
        return seq[k]

    return nxt


def _writable(qp: QPArrays) -> tuple[np.ndarray, ...]:
    """(H, g, A, b, C, l, u) of ``qp`` as writable copies, in proxsuite's order of arguments."""
    return tuple(np.array(a) for a in (qp.H, qp.g, qp.A, qp.b, qp.C, qp.l, qp.u))


def measure(seq: States, ctrl: OperationalSpaceQP, rounds: int, extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """The figures of one set of states (module docstring); ``extra``: more candidates to time, by name."""
    import pinocchio as pin
    from proxsuite import proxqp

    ref = armctl.Reference(Q_HOME)
    count = len(seq)
    qps = [_writable(ctrl.build(t, q, qd, ref).arrays(0)) for t, q, qd in seq]
    bare = proxqp.dense.QP(qps[0][0].shape[0], qps[0][3].shape[0], qps[0][5].shape[0])
    bare.settings.eps_abs = ctrl.solver.eps_abs
    bare.settings.eps_rel = 0.0
    bare.init(*qps[0])
    bare.solve()
    bare.settings.initial_guess = proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
    pm = ctrl.dynamics.model.to_pinocchio()
    pd = pm.createData()
    zero = np.zeros(ctrl.n)
    nxt = {k: _cycle(seq) for k in ("step", "rnea", "check")}
    qp_index = [0]

    def step() -> None:
        ctrl(*nxt["step"](), ref)

    def rnea() -> None:
        _, q, qd = nxt["rnea"]()
        pin.rnea(pm, pd, q, qd, zero)

    def bare_solve() -> None:
        k = qp_index[0]
        qp_index[0] = (k + 1) % count
        bare.update(*qps[k])
        bare.solve()

    candidates = {"step": step, "rnea": rnea, "bare_solve": bare_solve, **(extra or {})}
    samples = interleaved_samples(candidates, number=count, rounds=rounds, clock=time.process_time)
    out: dict[str, Any] = {f"{k}_s": statistics.median(v) for k, v in samples.items()}
    out["ratio_rnea"], out["ratio_rnea_iqr"] = _ratio(samples["step"], samples["rnea"])
    out["ratio_bare"], out["ratio_bare_iqr"] = _ratio(samples["step"], samples["bare_solve"])
    # one pass from a fresh controller: the stages of the solver chain, the fallbacks, and τ against quadprog
    ctrl.reset()
    fallbacks = 0
    taus = []
    for t, q, qd in seq:
        taus.append(ctrl(t, q, qd, ref))
        fallbacks += ctrl.last_log["qp_fallbacks"]
    out["stages"] = ctrl.fallback_counts
    out["fallbacks"] = fallbacks
    out["wrong"] = _wrong(ctrl, seq, taus, ref)
    # the optimality check of each step's solution, timed on its own (the step just made)
    out["check_s"] = check_time(ctrl, seq, ref, rounds)
    out["check_share"] = out["check_s"] / out["step_s"]
    ctrl.reset()
    return out


def _wrong(ctrl: OperationalSpaceQP, seq: States, taus: list[np.ndarray], ref: armctl.Reference) -> int | None:
    """Steps whose τ is more than 1e-4 N·m from quadprog's cold optimum of the same QP (None without quadprog)."""
    try:
        import qpsolvers
    except ImportError:  # pragma: no cover - a dependency
        return None
    if "quadprog" not in qpsolvers.available_solvers:
        return None
    wrong = 0
    for (t, q, qd), tau in zip(seq, taus, strict=True):
        p = ctrl.build(t, q, qd, ref).problem(0)
        sol = qpsolvers.solve_problem(p.to_qpsolvers(), "quadprog")
        wrong += not sol.found or sol.x is None or float(np.abs(tau - sol.x[p.variables["tau"]]).max()) > 1e-4
    return wrong


def run(
    count: int = 400, rounds: int = 15, quick: bool = False, contact: bool = True, tail_steps: int = 20_000
) -> dict[str, Any]:
    """Measure; returns a dict of figures per set of states (seconds per call and ratios). ``quick``: 100 states,
    5 rounds, the tail's calls replayed over a run of 5 000 periods (not one of ``tail_steps``). ``contact``:
    also the figures with an active contact (:mod:`~armctl.bench.osc_contact`), the scene's tail over
    ``tail_steps`` calls (0: none)."""
    from proxsuite import proxqp

    simulated = None
    if quick:
        count, rounds, simulated = 100, 5, 5_000
    seq, ctrl, closed = states(count)
    ref = armctl.Reference(Q_HOME)
    closed_next = _cycle(seq)
    cold = [_writable(ctrl.build(t, q, qd, ref).arrays(0)) for t, q, qd in seq]
    cold_index = [0]

    def closed_form() -> None:
        closed(*closed_next(), ref)

    def cold_solve() -> None:
        k = cold_index[0]
        cold_index[0] = (k + 1) % count
        proxqp.dense.solve(*cold[k], eps_abs=ctrl.solver.eps_abs, eps_rel=0.0)

    circle = measure(seq, ctrl, rounds, {"closed_form": closed_form, "cold_solve": cold_solve})
    rseq, rctrl = random_states(count)
    random = measure(rseq, rctrl, rounds)
    out = {
        "model": "panda",
        "qp_size": {"variables": 14, "equalities": 7, "inequalities": 7},
        "states": count,
        "rounds": rounds,
        "circle": circle,
        "random": random,
    }
    out["generated"] = ctrl.uses_generated_code
    dyn = ctrl.dynamics
    out["numpy"] = {
        "circle": measure(seq, circle_controller(dyn, count, compile=False)[0], rounds),
        "random": measure(rseq, random_states(count, dyn=dyn, compile=False)[1], rounds),
    }
    if contact:
        from armctl.bench.osc_contact import measure_contact, measure_scene  # the scenes: imported on use

        fixed = measure_contact(count, rounds)
        fixed["numpy"] = measure_contact(count, rounds, compile=False)
        out["contact"] = fixed
        out["scene"] = measure_scene(min(count, 200), rounds, tail_steps, simulated)
    return out


def checks(fig: dict[str, Any]) -> dict[str, bool]:
    """This benchmark's checks against :data:`TARGETS`, by name: the default step within 15 RNEA on each set of
    states, and no step's τ off quadprog's optimum, on either path."""
    out = {}
    limit = TARGETS["ratio_rnea"]
    for name in ("circle", "random"):
        out[f"{name}: step / RNEA <= {limit:g}"] = fig[name]["ratio_rnea"] <= limit
        for label, g in ((name, fig[name]), (f"{name} (compile=False)", fig.get("numpy", {}).get(name))):
            if g is not None and g["wrong"] is not None:
                out[f"{label}: every torque the optimum"] = g["wrong"] == 0
    out.update(contact_checks(fig, TARGETS))
    return out


#: the sets of states and their titles
SETS = (("circle", "along a 10 cm circle"), ("random", "random states near the ready pose"))


def report(fig: dict[str, Any]) -> str:
    us = 1e6
    s = fig["qp_size"]
    lines = [
        f"OSC QP step on {fig['model']}: pose + posture + torque limits (QP on [q̈; τ]: {s['variables']} variables, "
        f"{s['equalities']} equalities, {s['inequalities']} inequalities; solved on q̈ alone); {fig['states']} "
        f"states per set, {fig['rounds']} rounds; ratios: median of per-round ratios [quartiles]"
    ]
    how = "generated QP data" if fig.get("generated") else "no C compiler: Pinocchio's terms and NumPy"
    sets = [(fig[name], f"{title} ({how})") for name, title in SETS]
    sets += [(fig["numpy"][name], f"{title}, compile=False") for name, title in SETS if "numpy" in fig]
    for f, title in sets:
        stages = ", ".join(f"{k} {v}" for k, v in sorted(f["stages"].items()))
        wrong = "" if f["wrong"] is None else f"; τ off quadprog's optimum by > 1e-4 N·m: {f['wrong']}"
        lines += [
            f"  {title}:",
            f"    step                      {f['step_s'] * us:8.1f} µs   {f['ratio_rnea']:6.2f} x RNEA "
            f"[{f['ratio_rnea_iqr'][0]:.2f}, {f['ratio_rnea_iqr'][1]:.2f}]   {f['ratio_bare']:5.2f} x bare solve "
            f"[{f['ratio_bare_iqr'][0]:.2f}, {f['ratio_bare_iqr'][1]:.2f}]",
            f"    raw RNEA                  {f['rnea_s'] * us:8.2f} µs",
            f"    bare proxsuite solve      {f['bare_solve_s'] * us:8.1f} µs   (warm, unchecked)",
            f"    optimality check          {f['check_s'] * us:8.2f} µs   ({f['check_share']:.1%} of the step)",
            f"    QPs by stage: {stages}; fallbacks {f['fallbacks']}{wrong}",
        ]
        if "closed_form_s" in f:
            lines += [
                f"    closed-form OSC baseline  {f['closed_form_s'] * us:8.1f} µs",
                f"    proxsuite dense.solve     {f['cold_solve_s'] * us:8.1f} µs   (one-shot, cold)",
            ]
    lines += report_lines(fig)
    return "\n".join(lines)


def beyond_targets(fig: dict[str, Any]) -> list[str]:
    """The checks of :func:`checks` that fail (the benchmark's tests call this; the bench does not print it)."""
    return [name for name, ok in checks(fig).items() if not ok]


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer states and rounds")
    ap.add_argument("--json", help="also write the figures to this file")
    a = ap.parse_args(argv)
    fig = run(quick=a.quick)
    print(report(fig))
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(fig, fh, indent=2)


if __name__ == "__main__":
    main()
