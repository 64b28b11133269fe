"""Integrators of the second-order system q̈ = a(t, q, q̇) over one step of length h.

* ``"rk4"``: the classic fourth-order Runge–Kutta scheme on (q, q̇). For q̈ = a it reduces to

      q₁ = q + h q̇ + h²/6 (a₁ + a₂ + a₃),     q̇₁ = q̇ + h/6 (a₁ + 2a₂ + 2a₃ + a₄)

  with a₁ = a(t, q, q̇), a₂ = a(t + h/2, q + h/2 q̇, q̇ + h/2 a₁), a₃ = a(t + h/2, q + h/2 q̇₂, q̇ + h/2 a₂),
  a₄ = a(t + h, q + h q̇₃, q̇ + h a₃). Global error O(h⁴); energy drifts slowly (not symplectic). The default.
* ``"semi-implicit-euler"``: symplectic Euler on the momentum p = M(q) q̇, implicit in the velocity, explicit in
  the position (Hairer, Lubich & Wanner, *Geometric Numerical Integration*, VI.3):

      p₁ = p + h [τ − g(q) + C(q, v̄)ᵀ v̄ − τ_f(v̄) + τ_e(t, q, v̄)],   v̄ = M(q)⁻¹ p₁,   q₁ = q + h v̄,
      q̇₁ = M(q₁)⁻¹ p₁

  (∂T/∂q = C(q, q̇)ᵀq̇ for the Christoffel C). First order; for a conservative arm its energy error stays
  bounded — no drift — over long runs, even though M depends on q. v̄ is found by Newton's method (Jacobian
  M + h(∂τ_f/∂q̇ − D)), so stiff friction and damping do not limit the step; contact stiffness does.
* ``"euler"``: the velocity form q̇₁ = q̇ + h a(t, q, q̇), q₁ = q + h q̇₁ that many simulators call semi-implicit
  Euler: one evaluation per step, the cheapest scheme, but its energy drifts when M depends on q.
* ``"implicit-euler"``: backward Euler on the velocity, implicit in every stiff force (friction slope,
  contact stiffness and damping) and explicit in the rigid-body bias C q̇ + g, which is not stiff:

      M(q)(q̇₁ − q̇) = h [τ − C(q, q̇) q̇ − g(q) − τ_f(q̇₁) + τ_e(t + h, q + h q̇₁, q̇₁)],   q₁ = q + h q̇₁

  solved by Newton's method with the Jacobian M + h (∂τ_f/∂q̇ − D − h K). L-stable: stiff contact and damping
  cannot make it blow up, at the price of first-order accuracy and numerical damping. Use it for stiff
  contact (the step an explicit scheme needs shrinks as 1/√k) and stiff smooth friction.

Each integrator also integrates the friction and external powers with its own quadrature, so that the energy
balance E(t) − E(0) = W_actuator + W_friction + W_external closes to the scheme's order.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import numpy as np

from armctl._checks import FloatArray
from armctl.errors import UnknownNameError
from armctl.sim.implicit import implicit_euler, symplectic_euler
from armctl.sim.plant import Plant

#: The integrators ``simulate(integrator=...)`` accepts: fixed-step RK4 (the default), symplectic Euler on the
#: momentum, backward Euler implicit in the stiff forces (contact, friction), and Euler in velocity form.
INTEGRATORS = ("rk4", "semi-implicit-euler", "implicit-euler", "euler")

#: step(t, q, q̇, τ, h) → (q₁, q̇₁, a(t, q, q̇) or None, friction work, external work)
Step = Callable[[float, FloatArray, FloatArray, FloatArray, float], tuple[FloatArray, FloatArray, Any, float, float]]


def rk4(
    f: Callable[..., FloatArray], t: float, q: FloatArray, v: FloatArray, tau: FloatArray, h: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """One RK4 step of q̈ = f(t, q, q̇, τ); returns (q₁, q̇₁, a₁)."""
    h2 = 0.5 * h
    a1 = f(t, q, v, tau)
    v2 = v + h2 * a1
    a2 = f(t + h2, q + h2 * v, v2, tau)
    v3 = v + h2 * a2
    a3 = f(t + h2, q + h2 * v2, v3, tau)
    v4 = v + h * a3
    a4 = f(t + h, q + h * v3, v4, tau)
    s23 = a2 + a3
    return q + h * v + (h * h / 6.0) * (a1 + s23), v + (h / 6.0) * (a1 + a4 + 2.0 * s23), a1


def rk4_work(
    g: Callable[..., tuple[FloatArray, float, float]], t: float, q: FloatArray, v: FloatArray, tau: FloatArray, h: float
) -> tuple[FloatArray, FloatArray, FloatArray, float, float]:
    """RK4 of q̈ with the powers (p_f, p_e) = g(...)[1:] integrated alongside (stages as in :func:`rk4`,
    computed as products of :func:`_rk4_coefficients` with the rows [q, q̇, a₁, a₂, a₃, a₄])."""
    c = _rk4_coefficients(h)
    rows = np.empty((6, q.shape[0]))
    rows[0] = q
    rows[1] = v
    h2 = 0.5 * h
    a1, f1, e1 = g(t, q, v, tau)
    rows[2] = a1
    x = c[0] @ rows[:3]
    a, f2, e2 = g(t + h2, x[0], x[1], tau)
    rows[3] = a
    x = c[1] @ rows[:4]
    a, f3, e3 = g(t + h2, x[0], x[1], tau)
    rows[4] = a
    x = c[2] @ rows[:5]
    a, f4, e4 = g(t + h, x[0], x[1], tau)
    rows[5] = a
    x = c[3] @ rows
    h6 = h / 6.0
    return x[0], x[1], a1, h6 * (f1 + 2.0 * (f2 + f3) + f4), h6 * (e1 + 2.0 * (e2 + e3) + e4)


def semi_implicit_euler(
    f: Callable[..., FloatArray], t: float, q: FloatArray, v: FloatArray, tau: FloatArray, h: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """q̇₁ = q̇ + h f(t, q, q̇, τ), q₁ = q + h q̇₁."""
    a = f(t, q, v, tau)
    v1 = v + h * a
    return q + h * v1, v1, a


@functools.lru_cache(maxsize=64)
def _rk4_coefficients(h: float) -> tuple[FloatArray, ...]:
    """Matrices giving (q, q̇) of RK4's stages 2, 3, 4 and of the result from the rows [q, q̇, a₁], [q, q̇, a₁, a₂],
    [q, q̇, a₁, a₂, a₃] and [q, q̇, a₁, a₂, a₃, a₄] (only rows already computed are multiplied)."""
    h2, hh = 0.5 * h, h * h
    return (
        np.array([[1.0, h2, 0.0], [0.0, 1.0, h2]]),  # q + h/2 q̇, q̇ + h/2 a₁
        np.array([[1.0, h2, hh / 4, 0.0], [0.0, 1.0, 0.0, h2]]),  # q + h/2 q̇₂, q̇ + h/2 a₂
        np.array([[1.0, h, 0.0, hh / 2, 0.0], [0.0, 1.0, 0.0, 0.0, h]]),  # q + h q̇₃, q̇ + h a₃
        np.array([[1.0, h, hh / 6, hh / 6, hh / 6, 0.0], [0.0, 1.0, h / 6, h / 3, h / 3, h / 6]]),
    )  # q₁, q̇₁


def fast_step(name: str, plant: Plant) -> Callable[..., tuple[FloatArray, FloatArray, FloatArray]] | None:
    """For a plant with no friction, contact or disturbance, an RK4 or Euler step (q, q̇, τ, h) → (q₁, q̇₁, a₁)
    that calls the backend's forward dynamics directly, with no events to look for and no external forces to
    add; else None."""
    if not plant.simple or name not in ("rk4", "euler"):
        return None
    fwd = plant.forward
    # RK4 as linear combinations of the rows [q, q̇, a₁, a₂, a₃, a₄] of one array: each stage's (q, q̇) is one
    # small matrix product of the rows computed so far, instead of four vector operations.
    # Two such arrays take turns: a step writes its (q₁, q̇₁) straight into the first two rows of the other,
    # and returns views of them, which the next step finds in place (no copy in); the views stay valid
    # until the step after next overwrites them, which is all the simulator needs (it stores q and q̇ at once)
    bufs = [np.zeros((6, plant.n)), np.zeros((6, plant.n))]
    views = [(b, b[:3], b[:4], b[:5], b[0], b[1], b[:2]) for b in bufs]  # slices made once, not per stage
    turn = [0]

    def rk4_step(q: FloatArray, v: FloatArray, tau: FloatArray, h: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        c0, c1, c2, c3 = _rk4_coefficients(h)
        rows, rows3, rows4, rows5, row_q, row_v, rows2 = views[turn[0]]
        if row_q is not q or row_v is not v:  # not the last step's result: copy the state in, as a new pair
            rows2[...] = np.array((q, v))  # first (q or v may be a view of these very rows, in either order),
            q, v = row_q, row_v  # and read it from there
        rows[2] = a1 = fwd(q, v, tau)
        x = c0.dot(rows3)
        rows[3] = fwd(x[0], x[1], tau)
        x = c1.dot(rows4)
        rows[4] = fwd(x[0], x[1], tau)
        x = c2.dot(rows5)
        rows[5] = fwd(x[0], x[1], tau)
        turn[0] ^= 1
        _, _, _, _, q1, v1, out = views[turn[0]]
        c3.dot(rows, out=out)
        return q1, v1, a1

    step_h: list[Any] = [0.0, np.zeros(plant.n)]  # h and h as an (n,) array: a product with an array costs less than
    # one with a Python float, and the in-place additions allocate nothing

    def euler_step(
        q: FloatArray, v: FloatArray, tau: FloatArray, h: float
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        a = fwd(q, v, tau)
        if h != step_h[0]:
            step_h[0], step_h[1] = h, np.full(plant.n, h)
        hv = step_h[1]
        v1 = a * hv
        v1 += v
        q1 = v1 * hv
        q1 += q
        return q1, v1, a

    return rk4_step if name == "rk4" else euler_step


def make_step(name: str, plant: Plant) -> Step:
    """The step function of integrator ``name`` (one of :data:`INTEGRATORS`) for ``plant``."""
    if name == "implicit-euler":
        return lambda t, q, v, tau, h: implicit_euler(plant, t, q, v, tau, h)
    if name == "rk4":
        if plant.simple:
            fwd = plant.forward

            def f(t: float, q: FloatArray, v: FloatArray, tau: FloatArray) -> FloatArray:
                return fwd(q, v, tau)

            return lambda t, q, v, tau, h: (*rk4(f, t, q, v, tau, h), 0.0, 0.0)
        return lambda t, q, v, tau, h: rk4_work(plant.accel_work, t, q, v, tau, h)
    if name == "semi-implicit-euler":
        return lambda t, q, v, tau, h: symplectic_euler(plant, t, q, v, tau, h)
    if name == "euler":
        if plant.simple:
            fwd = plant.forward
            return lambda t, q, v, tau, h: (
                *semi_implicit_euler(lambda t, q, v, tau: fwd(q, v, tau), t, q, v, tau, h),
                0.0,
                0.0,
            )

        def euler_work(
            t: float, q: FloatArray, v: FloatArray, tau: FloatArray, h: float
        ) -> tuple[FloatArray, FloatArray, FloatArray, float, float]:
            # the work of the step's forces at the mean velocity (q̇ + q̇₁)/2: for a constant M the kinetic
            # energy changes by exactly h Fᵀ(q̇ + q̇₁)/2, so the balance does not drift. At the start velocity
            # it drifted by h²Fᵀq̈ a step, ∝ h ∫|F|²/m dt, and read as energy gained on a stable contact
            a, f, e = plant.accel_forces(t, q, v, tau)
            v1 = v + h * a
            mean = 0.5 * (v + v1)
            wf = -h * float(mean @ f) if f is not None else 0.0
            we = h * float(mean @ e) if e is not None else 0.0
            return q + h * v1, v1, a, wf, we

        return euler_work
    raise UnknownNameError("integrator", name, INTEGRATORS)
