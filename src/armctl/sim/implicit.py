"""The implicit schemes of :mod:`armctl.sim.integrators`: backward Euler ("implicit-euler") and symplectic Euler
in momentum form ("semi-implicit-euler"), each solved by Newton's method on the stiff forces (see there for
the equations)."""

from __future__ import annotations

import numpy as np
from scipy.linalg import lapack

from armctl._checks import BoolArray, FloatArray
from armctl.sim.plant import Plant
from armctl.sim.stick_slip import NotPositiveDefinite, constrained_accel

NEWTON_TOL = 1e-11
NEWTON_MAX_ITER = 25


def implicit_euler(
    plant: Plant, t: float, q: FloatArray, v: FloatArray, tau: FloatArray, h: float
) -> tuple[FloatArray, FloatArray, None, float, float]:
    """One backward-Euler step (see :mod:`armctl.sim.integrators`); returns (q₁, q̇₁, None, W_f, W_e).
    (C copy: ``step_schemes.c``'s ``armctl_scheme_step``; tests/sim/test_compiled_plant.py fails when they disagree.)"""
    n = plant.n
    if plant.all_stuck:
        return q, v, None, 0.0, 0.0
    mass = plant.mass(q)
    base = tau - plant.rnea(q, v, plant.zeros)  # τ − C q̇ − g, explicit
    fr = plant.friction
    stuck = plant.stuck
    if plant.simple:  # nothing implicit to solve: one linear solve
        v1 = v + h * constrained_accel(mass, base, None)
        return q + h * v1, v1, None, 0.0, 0.0
    t1 = t + h
    v1 = v.copy()
    f = e = plant.zeros
    converged = False
    for _ in range(NEWTON_MAX_ITER):
        q1 = q + h * v1
        jac = mass.copy()
        force = base
        if fr is not None:
            f = plant.kinetic_friction(v1)
            force = force - f
            jac[np.diag_indices(n)] += h * plant.friction_slope(v1)
        if plant.has_external:
            e, kj, dj = plant.external_stiffness(t1, q1, v1)
            force = force + e
            jac -= h * (dj + h * kj)
        v1, converged = _newton_update(jac, mass @ (v1 - v) - h * force, stuck, v1, "implicit step")
        if converged:
            break
    v1 = _solved(plant, v1, converged, stuck)
    q1 = q + h * v1
    wf = we = 0.0
    if fr is not None:
        wf = -h * float(v1 @ plant.kinetic_friction(v1))
    if plant.has_external:
        we = h * float(v1 @ plant.external(t1, q1, v1))
    return q1, v1, None, wf, we


def symplectic_euler(
    plant: Plant, t: float, q: FloatArray, v: FloatArray, tau: FloatArray, h: float
) -> tuple[FloatArray, FloatArray, None, float, float]:
    """One step of symplectic Euler in momentum form (see :mod:`armctl.sim.integrators`).
    (C copy: ``step_schemes.c``'s ``armctl_scheme_step``; tests/sim/test_compiled_plant.py fails when they disagree.)"""
    if plant.all_stuck:
        return q, v, None, 0.0, 0.0
    kernel = plant.kernel
    n = plant.n
    mass = plant.mass(q)
    base = tau - kernel.gravity(q)
    p0 = mass @ v
    stuck = plant.stuck
    if plant.simple:
        return _symplectic_conservative(plant, q, v, mass, base, p0, h)
    vb = v.copy()
    f = e = plant.zeros
    kj = None
    converged = False
    for _ in range(NEWTON_MAX_ITER):
        force = base + kernel.coriolis(q, vb).T @ vb
        jac = mass.copy()
        if plant.friction is not None:
            f = plant.kinetic_friction(vb)
            force = force - f
            jac[np.diag_indices(n)] += h * plant.friction_slope(vb)
        if plant.has_external:
            if plant.environments:
                e, kj, dj = plant.external_stiffness(t, q, vb)
                jac -= h * dj
            else:
                e = plant.external(t, q, vb)
            force = force + e
        vb, converged = _newton_update(jac, mass @ vb - p0 - h * force, stuck, vb, "semi-implicit Euler")
        if converged:
            break
    vb = _solved(plant, vb, converged, stuck)
    q1 = q + h * vb
    v1 = constrained_accel(plant.mass(q1), mass @ vb, stuck)
    wf = -h * float(vb @ f) if plant.friction is not None else 0.0
    we = 0.0
    if plant.has_external:  # the trapezoid in q of the force at v̄, τ_e(q₁) ≈ τ_e(q) + K h v̄: exact for a linear
        # spring (the left sum h v̄ᵀτ_e(q) overstates a spring's work by k Δq²/2 a step, which hid energy an
        # unstable wall made), at no extra evaluation
        we = h * float(vb @ e)
        if kj is not None:
            we += 0.5 * h * h * float(vb @ kj @ vb)
    return q1, v1, None, wf, we


def _symplectic_conservative(
    plant: Plant, q: FloatArray, v: FloatArray, mass: FloatArray, base: FloatArray, p0: FloatArray, h: float
) -> tuple[FloatArray, FloatArray, None, float, float]:
    """Symplectic Euler without friction or external forces: fixed-point iteration on a Cholesky factor."""
    chol, info = lapack.dpotrf(mass)
    if info != 0:
        raise NotPositiveDefinite(f"mass matrix not positive definite (LAPACK info {info})")
    coriolis = plant.kernel.coriolis
    vb = v
    converged = False
    for _ in range(NEWTON_MAX_ITER):
        new = lapack.dpotrs(chol, p0 + h * (base + coriolis(q, vb).T @ vb))[0]
        dv = np.abs(new - vb).max()
        vb = new
        converged = bool(dv <= NEWTON_TOL * (1.0 + np.abs(vb).max()))
        if converged:
            break
    vb = _solved(plant, vb, converged, None)
    q1 = q + h * vb
    return q1, constrained_accel(plant.mass(q1), mass @ vb, None), None, 0.0, 0.0


def _solved(plant: Plant, x: FloatArray, converged: bool, stuck: BoolArray | None) -> FloatArray:
    """The end of an implicit scheme's iteration: an unconverged one counted in ``plant.stats``, and ``x`` (the
    velocities, changed in place) with the stuck joints' set to zero."""
    if not converged:
        plant.stats["implicit_unconverged"] += 1
    if stuck is not None:
        x[stuck] = 0.0
    return x


def _newton_update(
    jac: FloatArray, res: FloatArray, stuck: BoolArray | None, x: FloatArray, scheme: str
) -> tuple[FloatArray, bool]:
    """One Newton step x − J⁻¹r of the implicit schemes, stuck joints held (their rows and columns replaced by
    the identity, residual zero); returns the new x and whether the step was below the tolerance. ``jac`` and
    ``res`` are modified. (C copy: ``step_schemes.c``'s ``armctl_newton_update``.)"""
    if stuck is not None:
        jac[stuck, :] = 0.0
        jac[:, stuck] = 0.0
        jac[stuck, stuck] = 1.0
        res[stuck] = 0.0
    dx, info = lapack.dgesv(jac, -res)[2:]
    if info != 0:
        raise NotPositiveDefinite(f"{scheme}: singular Newton matrix (LAPACK info {info})")
    x = x + dx
    return x, bool(np.abs(dx).max() <= NEWTON_TOL * (1.0 + np.abs(x).max()))
