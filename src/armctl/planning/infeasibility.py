"""Explaining a failed TOPP-RA solve: which constraint binds, and where along the path.

TOPP-RA's backward pass computes the controllable sets K_i, the path velocities² at s_i from which the end
can be reached at rest; it fails at the first stage i (from the end) where K_i is empty, or at the start when
0 ∉ K_0. toppra then returns None with a log line (toppra issue #26). Here the stage's own problem is re-solved as
the least-violation linear program

    min t   s.t.  (a_r u + b_r x + c_r − g_r) / h_r ≤ t  for every row r at s_i (and s_{i+1}),
                  0 ≤ x ≤ x_max(s_i),   K_{i+1} ∋ x + 2 Δ_i u,

with h_r the half-range of row r's bound: t* > 0 is the normalised excess that cannot be avoided, and the
rows with non-zero duals are the binding constraints. If t* ≤ 0 the stage was feasible and the failure was
numerical (toppra issues #14, #17, #226): that is a :class:`~armctl.errors.SolverError`, not an infeasibility.

Before any solve, :func:`rest_overload` checks the two rest states a rest-to-rest trajectory includes (at its
start pose for t < 0, at its end pose for t > T): toppra, free to choose s̈ at the ends, would otherwise
"throw" the arm through an end pose it cannot hold.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from armctl._checks import FloatArray
from armctl.errors import ArmctlError, InfeasibleError, SolverError
from armctl.planning.problem import RowLabel, TimeScalingProblem


def _row_scales(problem: TimeScalingProblem) -> FloatArray:
    lim = problem.limits.planned()
    return np.array([0.5 * float(lim[r.kind].upper[r.joint] - lim[r.kind].lower[r.joint]) for r in problem.labels])


Binding = list[tuple[int, int, float]]  # (row, gridpoint, dual)


def _stage_lp(
    problem: TimeScalingProblem,
    rows: tuple[FloatArray, FloatArray, FloatArray],
    i: int,
    k_next: FloatArray | None,
    x_fixed: float | None,
) -> tuple[float, FloatArray, Binding]:
    """Least-violation LP at stage i: (t*, (u*, x*), [(row, gridpoint, dual), …] sorted by |dual|)."""
    from scipy.optimize import linprog

    a, b, c = rows
    g, h, s = problem.g, _row_scales(problem), problem.s
    N = problem.grid
    delta = s[min(i + 1, N)] - s[i]
    A, ub, tag = [], [], []
    points = [(i, 0.0)]
    if problem.discretization == "interpolation" and i < N:
        points.append((i + 1, 2.0 * delta))  # rows at s_{i+1}, x_{i+1} = x + 2Δu
    for p, two_delta in points:
        for r in range(g.shape[0]):
            A.append([(a[p, r] + two_delta * b[p, r]) / h[r], b[p, r] / h[r], -1.0])
            ub.append((g[r] - c[p, r]) / h[r])
            tag.append((r, p))
    if i < N and k_next is not None:  # the next velocity² must be controllable
        A += [[2.0 * delta, 1.0, 0.0], [-2.0 * delta, -1.0, 0.0]]
        ub += [float(k_next[1]), -float(k_next[0])]
    x_hi = float(problem.x_max[i]) if x_fixed is None else x_fixed
    x_lo = 0.0 if x_fixed is None else x_fixed
    res = linprog(
        [0.0, 0.0, 1.0],
        A_ub=np.array(A),
        b_ub=np.array(ub),
        bounds=[(-1e8, 1e8), (x_lo, x_hi), (-1.0, None)],
        method="highs",
    )
    if res.status != 0:  # the hard bounds alone conflict: the velocity sets themselves are empty
        return np.inf, np.full(2, np.nan), []
    duals = res.ineqlin.marginals[: len(tag)]
    binding = [(tag[k][0], tag[k][1], float(duals[k])) for k in np.argsort(duals) if abs(duals[k]) > 1e-12]
    return float(res.x[2]), res.x[:2], binding


def _joint(problem: TimeScalingProblem, j: int) -> str:
    return f"joint {j} ({problem.dyn.model.joint_names[j]!r})"


def _where(problem: TimeScalingProblem, p: int) -> str:
    s = float(problem.s[p])
    k = problem.path.piece(s)
    return f"s = {s:.3g} (between waypoints {k} and {k + 1})"


def _limit_text(problem: TimeScalingProblem, kind: str, bound: float) -> str:
    margin = problem.limits.torque_margin if kind == "torque" else 0.0
    return f"the limit is {bound:.4g}" + (
        f" ({100 * (1 - margin):.3g} % of the range, torque_margin={margin})" if margin else ""
    )


def _message(problem: TimeScalingProblem, label: RowLabel, p: int, need: float) -> tuple[str, dict[str, Any]]:
    lim = problem.limits.planned()[label.kind]
    bound = float(lim.upper[label.joint] if label.side == "upper" else lim.lower[label.joint])
    limit_txt = _limit_text(problem, label.kind, bound)
    value = {
        "constraint": label.kind,
        "joint": label.joint,
        "side": label.side,
        "s": float(problem.s[p]),
        "needed": need,
        "limit": bound,
    }
    head = f"{_joint(problem, label.joint)} {label.kind} at {_where(problem, p)}"
    if label.kind == "torque":
        grav = float(problem.gravity[p, label.joint])
        fric = float(problem.coulomb[p, label.joint, 1 if label.side == "upper" else 0])
        static = grav + fric
        value.update(gravity=grav, coulomb=fric)
        beyond = static > bound if label.side == "upper" else static < bound
        if beyond:
            value["needed"] = static
            what = "gravity alone needs" if fric == 0 else f"gravity and Coulomb friction alone need ({fric:+.3g})"
            return f"{head}: {what} {static:.4g} N·m, {limit_txt}", value
        return (
            f"{head}: following the path needs at least {need:.4g} N·m there (gravity {grav:.4g} N·m), {limit_txt}",
            value,
        )
    return f"{head}: following the path needs at least {need:.4g} {lim.unit} there, {limit_txt}", value


def _static_overload(problem: TimeScalingProblem) -> tuple[int, int, float] | None:
    """The (row, gridpoint, normalised excess) where gravity and Coulomb friction alone (at rest) exceed a
    torque bound the most, or None."""
    torque = [r for r, lab in enumerate(problem.labels) if lab.kind == "torque"]
    if not torque:
        return None
    h = _row_scales(problem)[torque]
    excess = (problem.c[:, torque] - problem.g[torque]) / h
    p, k = np.unravel_index(int(np.argmax(excess)), excess.shape)
    return (torque[k], int(p), float(excess[p, k])) if excess[p, k] > 0 else None


def rest_overload(problem: TimeScalingProblem) -> InfeasibleError | None:
    """The error to raise when the arm cannot be held at rest at the start or the end pose of the path within
    the (margin-reduced) torque bounds, or None.

    A rest-to-rest trajectory rests at its start pose before t = 0 and at its end pose after T (q̇ = q̈ = 0), so
    these two states must fit the bounds by themselves, whatever happens in between (only there: the path
    may pass dynamically through poses the arm could not hold). At rest the torque is gravity alone, g(q):
    friction is counted neither against the arm (nothing moves) nor for it (stiction may hold a real arm, but
    its level is too uncertain to plan on) — as in the dense check (:func:`~armctl.planning.verify.rest_samples`).
    The error's ``value["excess"]`` is the normalised violation there, utilisation − 1 = (|g| − L)/L for bounds
    ±L (relative to the half-range for asymmetric ones), as in the dense check and the error raised mid-path.
    """
    bounds = problem.limits.planned().get("torque")
    if bounds is None:
        return None
    worst = None
    for p in (0, problem.grid):
        g = problem.gravity[p]
        over = bounds.utilisation(g) - 1.0  # > 0: outside [lower, upper], by that fraction of the half-range
        j = int(np.argmax(over))
        if over[j] > 0 and (worst is None or over[j] > worst[2]):
            worst = (p, j, float(over[j]))
    if worst is None:
        return None
    p, j, excess = worst
    side = "upper" if problem.gravity[p, j] > bounds.upper[j] else "lower"
    bound = float(bounds.upper[j] if side == "upper" else bounds.lower[j])
    pose = "start" if p == 0 else "end"
    when = "before t = 0" if p == 0 else "after the motion, t > T"
    need = float(problem.gravity[p, j])
    value = {
        "constraint": "torque",
        "joint": j,
        "side": side,
        "s": float(problem.s[p]),
        "needed": need,
        "limit": bound,
        "gravity": need,
        "excess": excess,
        "endpoint": pose,
    }
    return InfeasibleError(
        f"{_joint(problem, j)} torque at the {pose} pose (s = {problem.s[p]:.3g}): gravity alone "
        f"needs {need:.4g} N·m, {_limit_text(problem, 'torque', bound)}: the arm cannot hold itself "
        f"at rest at its {pose} pose, where a rest-to-rest trajectory waits ({when}). Raise the "
        f"limit, lighten the load or change the {pose} of the path.",
        value=value,
        problem=problem,
    )


def no_motion(problem: TimeScalingProblem, i: int) -> InfeasibleError:
    """The error for a profile that stops on stage i (ṡ = 0 at both its ends, so the motion would never go
    on): naming the velocity or acceleration bounds that exclude the direction the path moves in there."""
    dq = problem.dq[i] if np.abs(problem.dq[i]).max() > 0 else problem.dq[min(i + 1, problem.grid)]
    found = []
    for kind, b in (("velocity", problem.limits.velocity), ("acceleration", problem.limits.acceleration)):
        if b is None:
            continue
        for j in range(dq.shape[0]):
            if (dq[j] > 0 and b.upper[j] <= 0) or (dq[j] < 0 and b.lower[j] >= 0):
                way = "up" if dq[j] > 0 else "down"
                found.append(
                    f"{_joint(problem, j)} {kind} bounds [{b.lower[j]:.4g}, {b.upper[j]:.4g}] {b.unit} "
                    f"leave it no way to move {way}, as the path does there"
                )
    why = "; ".join(found) if found else "no timing within the limits gets the arm moving there"
    return InfeasibleError(
        f"the limits allow no motion along the path at {_where(problem, i)}: {why}. Widen the "
        "bounds or change the path.",
        value={"s": float(problem.s[i]), "bounds": found},
        problem=problem,
    )


def diagnose(
    problem: TimeScalingProblem,
    rows: tuple[FloatArray, FloatArray, FloatArray],
    code: str,
    x: FloatArray | None,
    K: FloatArray | None,
) -> ArmctlError:
    """The error to raise for a failed toppra solve of ``problem`` (with the rows actually solved).

    In order: a failed forward pass is numerical (SolverError); a point where gravity and Coulomb friction
    alone exceed a torque bound explains the failure in the terms an engineer checks first ("gravity alone
    needs 95 N·m, the limit is 87"); otherwise the failing stage's least-violation LP, first without and then
    with the controllable set of the next stage, names the binding rows — or finds none, and the failure was
    numerical.
    """
    N = problem.grid
    if code == "ErrUnknown":  # the backward pass succeeded, the forward pass did not
        first = int(np.flatnonzero(~np.isfinite(x))[0]) if x is not None and not np.isfinite(x).all() else 0
        return SolverError(
            f"toppra's forward pass failed at s = {problem.s[first]:.4g} although the path is "
            "controllable (a numerical failure of the solver); try another grid size",
            value=first,
            problem=problem,
        )
    if K is None:
        return SolverError(f"toppra failed with code {code} and no controllable sets", value=code, problem=problem)
    bad = np.flatnonzero(np.isnan(K).any(axis=1))
    i, x_fixed = (int(bad.max()), None) if bad.size else (0, 0.0)  # no NaN: 0 ∉ K_0, cannot start from rest
    fail_at = f"toppra finds no timing (its backward pass fails at s = {problem.s[i]:.3g})"
    over = _static_overload(problem)
    if over is not None:
        r, p, t = over
        label = problem.labels[r]
        msg, value = _message(problem, label, p, 0.0)
        value["excess"] = t
        return InfeasibleError(
            f"{msg}: the arm cannot hold itself there and {fail_at}. Raise the limit, lighten "
            "the load or change the path.",
            value=value,
            problem=problem,
        )
    k_next = K[i + 1] if i < N else np.zeros(2)
    t, _, binding = _stage_lp(problem, rows, i, None, x_fixed)
    dynamic = t <= 1e-9
    if dynamic:  # the point itself is feasible: what fails is reaching a controllable velocity beyond it
        t, _, binding = _stage_lp(problem, rows, i, k_next, x_fixed)
    if not np.isfinite(t) or not binding:
        return SolverError(
            f"toppra found no controllable path velocity at s = {problem.s[i]:.4g} and the stage's "
            "bounds conflict by themselves (velocity sets empty)",
            value=i,
            problem=problem,
        )
    if t <= 1e-9:
        return SolverError(
            f"toppra reported the path uncontrollable at s = {problem.s[i]:.4g} (code {code}), but "
            "every limit can be met there: a numerical failure of the solver; try another grid size",
            value=i,
            problem=problem,
        )
    r, p, _ = binding[0]
    label = problem.labels[r]
    sign = 1.0 if label.side == "upper" else -1.0
    need = sign * float(problem.g[r] + t * _row_scales(problem)[r])
    msg, value = _message(problem, label, p, need)
    if dynamic:
        msg += (
            " at the path speed needed to go on from there (the motion cannot be slowed or sped up in time "
            "within the limits)"
        )
    others = [problem.labels[rr] for rr, _, _ in binding[1:] if problem.labels[rr] != label]
    if others:
        msg += "; also binding: " + ", ".join(f"{_joint(problem, o.joint)} {o.kind} ({o.side})" for o in others[:3])
    value["excess"] = t
    return InfeasibleError(
        msg + ". Raise the limit, lighten the load or change the path.", value=value, problem=problem
    )
