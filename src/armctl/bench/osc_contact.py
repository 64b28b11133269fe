"""Cost of operational-space QP steps with an active contact on the Panda, as a ratio to one raw RNEA measured in
the same run (part of ``python -m armctl.bench.osc_speed``).

* ``contact``: a fixed point contact at the tool (μ 0.3, a pyramid of 4 facets), a force target (0, 0, 10) N, a
  pose task on the tool frame (kp 400) and a posture task (kp 100, weight 1e-3) in the same level, the URDF's
  torque limits; states near the ready pose, q = ready + N(0, 0.1 rad), q̇ = N(0, 0.3 rad/s). The QP on
  [q̈; τ; f] has 17 variables, 10 equality and 12 inequality rows (the controller solves it on [q̈; f]).
  Measured as in :mod:`~armctl.bench.osc_speed` (interleaved rounds of CPU time, per-round ratios): the step, one
  raw RNEA at the same states, the optimality check run again in NumPy (``verify_last_step``; a step whose optimum
  the generated code checked paid for its check inside that code), the QPs by stage, and the steps whose τ
  differs from quadprog's optimum of the public problem by more than 1e-6 N·m.
* ``scene``: the ``panda_contact`` scene's own controller (a sliding contact with a force target and the pose
  task in one level, the posture below it, torque, position and velocity limits) replaying a window of
  recorded states from the middle of a run of the scene (in contact), against one raw RNEA at those states.
* ``tail``: the per-call times of that controller over a run of the scene, replayed call by call
  (:func:`~armctl.bench.tails.replay_tail`): p50, p99.9 and their ratio (``--quick``: 20 000 calls replayed over
  a run of 5 000 periods, four times, the controller reset at each pass, instead of a 20 000-period run: what
  happens once a run, the first call and the contact's onset, then happens four times).
"""

from __future__ import annotations

import statistics
import time
from typing import Any

import numpy as np

import armctl
from armctl.bench.tails import Q_HOME, replay_tail, tail_text
from armctl.bench.timing import interleaved_samples
from armctl.controllers.osc import (
    Contact,
    ContactForceTask,
    FramePoseTask,
    OperationalSpaceQP,
    PostureTask,
    TorqueLimit,
)

States = list[tuple[float, np.ndarray, np.ndarray]]


def contact_controller(dyn: armctl.Dynamics, compile: bool | str = "auto") -> OperationalSpaceQP:
    """The fixed-contact controller of the module's ``contact`` figures on ``dyn``."""
    pose = FramePoseTask(kp=400.0)
    pose.set_target(dyn.frame_pose(Q_HOME))
    contact = Contact(mu=0.3, facets=4)
    tasks = [pose, PostureTask(dyn.n, kp=100.0, weight=1e-3), ContactForceTask(contact, (0.0, 0.0, 10.0))]
    return OperationalSpaceQP(dyn, tasks, limits=[TorqueLimit()], contacts=[contact], compile=compile)


def contact_states(count: int, seed: int = 0) -> States:
    """``count`` states near the ready pose (q = ready + N(0, 0.1), q̇ = N(0, 0.3))."""
    rng = np.random.default_rng(seed)
    return [(0.0, Q_HOME + rng.normal(0.0, 0.1, 7), rng.normal(0.0, 0.3, 7)) for _ in range(count)]


def _ratio(num: list[float], den: list[float]) -> tuple[float, tuple[float, float]]:
    q1, med, q3 = statistics.quantiles([a / b for a, b in zip(num, den, strict=True)], n=4)
    return med, (q1, q3)


def _rnea(model: armctl.RobotModel, states: list[tuple[np.ndarray, np.ndarray]]) -> Any:
    import pinocchio as pin

    pm = model.to_pinocchio()
    pd = pm.createData()
    zero = np.zeros(model.n)
    it = [0]

    def rnea() -> None:
        k = it[0]
        it[0] = (k + 1) % len(states)
        pin.rnea(pm, pd, states[k][0], states[k][1], zero)

    return rnea


def _wrong(ctrl: OperationalSpaceQP, seq: States, taus: list[np.ndarray], ref: armctl.Reference) -> int | None:
    """Steps whose τ is more than 1e-6 N·m off quadprog's optimum of the public QP (None without quadprog)."""
    try:
        import qpsolvers
    except ImportError:  # pragma: no cover - the test extra installs it
        return None
    if "quadprog" not in qpsolvers.available_solvers:  # pragma: no cover
        return None
    wrong = 0
    for (t, q, qd), tau in zip(seq, taus, strict=True):
        p = ctrl.build(t, q, qd, ref).problem(0)
        sol = qpsolvers.solve_problem(p.to_qpsolvers(), "quadprog")
        if not sol.found or sol.x is None:
            wrong += 1
            continue
        rows = [i for i, name in enumerate(p.ineq_names) if name.startswith("torque_limit[")]
        best = np.clip(sol.x[p.variables["tau"]], p.l[rows], p.u[rows])
        wrong += float(np.abs(tau - best).max()) > 1e-6
    return wrong


def check_time(ctrl: OperationalSpaceQP, seq: States, ref: armctl.Reference, rounds: int) -> float:
    """Process seconds per step of the optimality check of the step just made (``verify_last_step``): each state of
    ``seq`` stepped, then checked 20 times; the median over max(1, ``rounds`` // 3) passes of the mean per step."""
    checks = []
    for _ in range(max(1, rounds // 3)):
        total = 0.0
        for t, q, qd in seq:
            ctrl(t, q, qd, ref)
            t0 = time.process_time()
            for _ in range(20):
                ctrl.verify_last_step()
            total += (time.process_time() - t0) / 20
        checks.append(total / len(seq))
    return statistics.median(checks)


def measure_contact(count: int = 400, rounds: int = 15, compile: bool | str = "auto") -> dict[str, Any]:
    """The ``contact`` figures (module docstring)."""
    dyn = armctl.Dynamics(armctl.models.panda())
    ctrl = contact_controller(dyn, compile)
    seq = contact_states(count)
    ref = armctl.Reference(Q_HOME)
    it = [0]

    def step() -> None:
        k = it[0]
        it[0] = (k + 1) % count
        t, q, qd = seq[k]
        ctrl(t, q, qd, ref)

    rnea = _rnea(dyn.model, [(q, qd) for _, q, qd in seq])
    samples = interleaved_samples({"step": step, "rnea": rnea}, number=count, rounds=rounds, clock=time.process_time)
    out: dict[str, Any] = {k + "_s": statistics.median(v) for k, v in samples.items()}
    out["ratio_rnea"], out["ratio_rnea_iqr"] = _ratio(samples["step"], samples["rnea"])
    ctrl.reset()
    taus = [ctrl(t, q, qd, ref) for t, q, qd in seq]
    out["stages"] = ctrl.fallback_counts
    out["wrong"] = _wrong(ctrl, seq, taus, ref)
    out["check_s"] = check_time(ctrl, seq, ref, rounds)
    out["check_share"] = out["check_s"] / out["step_s"]
    return out


def measure_scene(
    samples: int = 200, rounds: int = 15, tail_steps: int = 20_000, simulated: int | None = None
) -> dict[str, Any]:
    """The ``scene`` figures and, with ``tail_steps`` > 0, the ``tail``: ``tail_steps`` calls of the controller
    replayed over a run of ``simulated`` control periods of the scene (default ``tail_steps``; at least the
    scene's own duration, beyond which it holds its last target), its states again from the start, the controller
    reset, when they run out."""
    from armctl.scenes import panda_contact

    sc = panda_contact()
    periods = tail_steps if simulated is None else simulated
    duration = max(periods * sc.control_dt, float(sc.duration)) if tail_steps else float(sc.duration)
    res = sc.run("osc_qp", duration=duration)
    # the window from the middle of the scene's own duration (the run is the scene's run up to there)
    own = min(len(res.t), round(float(sc.duration) / sc.control_dt) + 1)
    count = min(samples, own)
    start = (own - count) // 2
    window = [
        (float(res.t[k]), res.q_measured[k], res.qd_measured[k], sc.reference(float(res.t[k])))
        for k in range(start, start + count)
    ]
    ctrl = sc.controller("osc_qp")
    it = [0]

    def step() -> None:
        k = it[0]
        if k == 0:
            ctrl.reset()
        it[0] = (k + 1) % len(window)
        t, q, qd, r = window[k]
        ctrl(t, q, qd, r)

    rnea = _rnea(sc.dynamics("exact").model, [(q, qd) for _, q, qd, _ in window])
    timed = interleaved_samples({"step": step, "rnea": rnea}, len(window), rounds, clock=time.process_time)
    out: dict[str, Any] = {k + "_s": statistics.median(v) for k, v in timed.items()}
    out["ratio_rnea"], out["ratio_rnea_iqr"] = _ratio(timed["step"], timed["rnea"])
    out["samples"] = len(window)
    if tail_steps:
        states = [
            (float(t), q, qd, sc.reference(float(t)))
            for t, q, qd in zip(res.t[:-1], res.q_measured[:-1], res.qd_measured[:-1], strict=True)
        ]
        ctrl_tail = sc.controller("osc_qp")

        def again() -> Any:  # the same controller from its start, as a longer run would keep it
            ctrl_tail.reset()
            return ctrl_tail

        out["tail"] = replay_tail(again, states, tail_steps)
        out["tail"]["simulated"] = len(states)
    return out


def contact_checks(fig: dict[str, Any], targets: dict[str, float]) -> dict[str, bool]:
    """The checks of the figures with an active contact against ``targets`` (``contact_ratio_rnea``,
    ``scene_ratio_rnea``, ``tail_ratio``), by name; none if they were not measured."""
    out = {}
    if "contact" in fig:
        c = fig["contact"]
        out[f"contact: step / RNEA <= {targets['contact_ratio_rnea']:g}"] = (
            c["ratio_rnea"] <= targets["contact_ratio_rnea"]
        )
        for label, g in (("contact", c), ("contact (compile=False)", c["numpy"])):
            if g["wrong"] is not None:
                out[f"{label}: every torque the optimum"] = g["wrong"] == 0
    if "scene" in fig:
        out[f"panda_contact: step / RNEA <= {targets['scene_ratio_rnea']:g}"] = (
            fig["scene"]["ratio_rnea"] <= targets["scene_ratio_rnea"]
        )
        if "tail" in fig["scene"]:
            out[f"panda_contact: p99.9 / p50 <= {targets['tail_ratio']:g}"] = (
                fig["scene"]["tail"]["cpu"]["tail_ratio"] <= targets["tail_ratio"]
            )
    return out


def report_lines(fig: dict[str, Any]) -> list[str]:
    """The report's lines of the figures with an active contact (none if they were not measured)."""
    us = 1e6
    lines = []
    if "contact" in fig:
        lines.append(
            "  fixed contact (μ 0.3, 4 facets), desired force (0, 0, 10) N, pose + posture, torque limits (QP on "
            "[q̈; τ; f]: 17 variables, 10 equalities, 12 inequalities; solved on [q̈; f]), random states:"
        )
        for f, label in ((fig["contact"], "default"), (fig["contact"]["numpy"], "compile=False")):
            stages = ", ".join(f"{k} {v}" for k, v in sorted(f["stages"].items()))
            wrong = "" if f["wrong"] is None else f"; τ off quadprog's optimum by > 1e-6 N·m: {f['wrong']}"
            lines += [
                f"    step ({label})".ljust(30) + f"{f['step_s'] * us:8.1f} µs   {f['ratio_rnea']:6.2f} x RNEA "
                f"[{f['ratio_rnea_iqr'][0]:.2f}, {f['ratio_rnea_iqr'][1]:.2f}]   RNEA {f['rnea_s'] * us:.2f} µs",
                f"      optimality check        {f['check_s'] * us:8.2f} µs   ({f['check_share']:.1%} of the step); "
                f"QPs by stage: {stages}{wrong}",
            ]
    if "scene" in fig:
        f = fig["scene"]
        lines += [
            f"  panda_contact scene's controller ({f['samples']} recorded states in contact, replayed):",
            f"    step                      {f['step_s'] * us:8.1f} µs   {f['ratio_rnea']:6.2f} x RNEA "
            f"[{f['ratio_rnea_iqr'][0]:.2f}, {f['ratio_rnea_iqr'][1]:.2f}]   RNEA {f['rnea_s'] * us:.2f} µs",
        ]
        if "tail" in f:
            t = f["tail"]
            run = "" if t.get("simulated", t["calls"]) >= t["calls"] else f", replayed over a {t['simulated']}-step run"
            lines.append(f"    per call over {t['calls']} calls{run}: {tail_text(t)}")
    return lines
