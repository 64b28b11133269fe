"""Which joints stick: the constraint solve of the stick–slip friction model.

At the start of every integration step, every joint that can stick and is exactly at rest (q̇_i = 0) is a
candidate. With S the stuck joints and F the others, sticking is the constraint q̈_S = 0; the friction torques
λ_S of the stuck joints are its multipliers:

    M q̈ = r − E_S λ_S,   q̈_S = 0     ⇒   M_FF q̈_F = r_F,   λ_S = r_S − M_SF q̈_F

where r = τ − C q̇ − g − τ_f,F − Jᵀh_e holds every other torque (the kinetic friction of the sliding joints
included). A stuck joint whose λ_i leaves its breakaway band −F_s⁻ ≤ λ_i ≤ F_s⁺ breaks away in the direction of
λ_i, with the kinetic friction it has at zero speed; releasing one joint changes the others' λ, so joints are
released one at a time, the one furthest beyond its band (largest |λ_i|/F_s) first, and λ is solved again.

This largest-violation-first rule is a heuristic for what is, in general, a linear complementarity problem;
the simulator checks its outcome (a released joint that does not move in its breakaway direction is held
again, see ``armctl.sim.stepper``).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import lapack

from armctl._checks import BoolArray, FloatArray
from armctl.sim.friction import StickSlip


class NotPositiveDefinite(ArithmeticError):
    """The (reduced) mass matrix could not be factored: the state has left the physical range."""


def constrained_accel(mass: FloatArray, rhs: FloatArray, stuck: BoolArray | None) -> FloatArray:
    """q̈ with q̈_S = 0 for the boolean mask ``stuck``: M_FF q̈_F = rhs_F (a Cholesky solve of the free
    joints' block, taken out of M, so that the stuck joints do not enter the factorisation).
    (C copy: ``step_core.c``'s ``armctl_masked_solve``; tests/sim/test_compiled_plant.py fails when they disagree.)"""
    if stuck is None:
        a, info = lapack.dposv(mass, rhs)[1:]
    else:
        free = (~stuck).nonzero()[0]
        a = np.zeros(rhs.shape[0])
        if not free.size:  # every joint stuck
            return a
        a_free, info = lapack.dposv(mass.take(free, 0).take(free, 1), rhs.take(free))[1:]
        a[free] = a_free
        if info > 0:  # the free block's pivot: name the arm's joint
            info = int(free[info - 1]) + 1
    if info != 0:
        raise NotPositiveDefinite(f"mass matrix not positive definite (LAPACK info {info})")
    return a


def solve_sticking(
    friction: StickSlip,
    mass: FloatArray,
    rhs: FloatArray,
    candidates: BoolArray,
    direction: FloatArray,
    held: BoolArray | None = None,
) -> tuple[BoolArray, FloatArray, FloatArray]:
    """(stuck, direction, λ) for the joints ``candidates`` at rest.

    mass: M(q); rhs: r (every torque but the friction of the candidates); direction: sliding direction of
    every joint (0 at rest), updated for the joints that break away; held: joints kept stuck whatever their
    λ. λ (n,) is the friction torque of each stuck joint (0 elsewhere) [N·m], with the sign it has in τ_f.

    (C copy: ``step_events.c``'s ``armctl_solve_sticking``; tests/sim/test_compiled_plant.py fails when they
    disagree.)
    """
    n = rhs.shape[0]
    stuck = candidates.copy()
    direction = direction.copy()
    r = rhs.copy()
    bp, bn = friction.breakaway_pos.tolist(), friction.breakaway_neg.tolist()
    free_held = [] if held is None else np.flatnonzero(held).tolist()
    while True:
        if stuck.all():
            lam = r.copy()
        else:
            lam = r - mass @ constrained_accel(mass, r, stuck if stuck.any() else None)
        worst, k = 1.0, -1
        lam_l = lam.tolist()
        for i in np.flatnonzero(stuck).tolist():
            if i in free_held:
                continue
            x = lam_l[i]
            ratio = (
                (x / bp[i] if bp[i] > 0 else math.inf)
                if x > 0
                else (-x / bn[i] if bn[i] > 0 else math.inf)
                if x < 0
                else 0.0
            )
            if ratio > worst:
                worst, k = ratio, i
        if k < 0:
            return stuck, direction, np.where(stuck, lam, 0.0)
        # joint k breaks away in the direction of the torque that overcame it, against its friction at 0⁺
        stuck[k] = False
        d = 1.0 if lam_l[k] > 0 else -1.0
        direction[k] = d
        dvec = np.zeros(n)
        dvec[k] = d
        r[k] -= float(friction.torque(np.zeros(n), dvec)[k])
