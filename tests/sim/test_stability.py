"""The check made before a run: can the chosen explicit integrator integrate a stiff contact stably at this step?

References: the undamped oscillator's stability limits of each scheme in closed form (RK4: ω h ≤ 2√2, the
Euler variants: ω h < 2), and the arm's effective mass at a point computed here from Pinocchio directly."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pinocchio as pin
import pytest

import armctl
from armctl.errors import SimulationWarning
from armctl.sim import Forces, KelvinVoigt, Plane, simulate
from armctl.sim.stability import contact_stability
from tests.sim.helpers import OpenLoop, slider

PANDA_Q0 = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])  # hand pointing down


@pytest.mark.parametrize(
    ("scheme", "limit"), [("rk4", 2.0 * math.sqrt(2.0)), ("euler", 2.0), ("semi-implicit-euler", 2.0)]
)
def test_largest_stable_step_of_an_undamped_contact(scheme: str, limit: float) -> None:
    mass, k = 2.0, 1e7
    wall = Plane(KelvinVoigt(k), normal=(-1.0, 0.0, 0.0), point=(0.01, 0.0, 0.0))
    dyn = armctl.Dynamics(slider(mass))
    omega = math.sqrt(k / mass)
    for h in (0.5 * limit / omega, 1.5 * limit / omega):
        (found,) = contact_stability(dyn, [wall], np.zeros(1), scheme, h)
        assert found.linear_dt == pytest.approx(limit / omega, rel=1e-9)
        assert found.omega_h == pytest.approx(omega * h, rel=1e-12)
        assert (found.radius <= 1.0 + 1e-12) == (h < limit / omega)
        assert found.max_dt < found.linear_dt and not (h > limit / omega and found.stable)
    assert contact_stability(dyn, [wall], np.zeros(1), "implicit-euler", 1.0) == []


def test_effective_mass_of_the_panda_hand() -> None:
    dyn = armctl.Dynamics(armctl.models.panda())
    k = 1e8
    floor = Plane(KelvinVoigt(k), point=(0.0, 0.0, 0.0))
    (found,) = contact_stability(dyn, [floor], PANDA_Q0, "rk4", 1e-3)
    # m_eff = 1 / (nᵀ J M⁻¹ Jᵀ n) at the tool frame, straight from Pinocchio
    pm = dyn.model.to_pinocchio()
    pd = pm.createData()
    mass = pin.crba(pm, pd, PANDA_Q0)
    mass = np.triu(mass) + np.triu(mass, 1).T
    fid = pm.getFrameId(dyn.model.frame(None).name)
    jac = pin.computeFrameJacobian(pm, pd, PANDA_Q0, fid, pin.LOCAL_WORLD_ALIGNED)[:3]
    jn = np.array([0.0, 0.0, 1.0]) @ jac
    m_eff = 1.0 / (jn @ np.linalg.solve(mass, jn))
    assert found.linear_dt == pytest.approx(2.0 * math.sqrt(2.0) / math.sqrt(k / m_eff), rel=1e-9)
    assert not found.stable  # the existing contact test's k = 1e8 at 1 ms: beyond RK4's limit


# the unstable contact also shows in the energy balance
@pytest.mark.filterwarnings("ignore:the arm gained:armctl.errors.SimulationWarning")
# the unstable contact also shows in the contact's work
@pytest.mark.filterwarnings("ignore:the contact did:armctl.errors.SimulationWarning")
def test_simulate_warns_and_records_an_unstable_contact() -> None:
    wall = Plane(KelvinVoigt(1e9), normal=(-1.0, 0.0, 0.0), point=(0.01, 0.0, 0.0))
    push = OpenLoop(lambda t: np.array([10.0]))
    for scheme in ("rk4", "euler", "semi-implicit-euler"):
        with pytest.warns(SimulationWarning, match=rf"'{scheme}' is unstable on this contact"):
            res = simulate(
                slider(2.0), push, armctl.Reference.hold([0.0]), 0.1, integrator=scheme, forces=Forces(environment=wall)
            )
        (entry,) = res.info["unstable_contacts"]
        assert entry["omega_dt"] == pytest.approx(math.sqrt(1e9 / 2.0) * 1e-3)
        assert "unstable on a contact" in repr(res)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = simulate(
            slider(2.0),
            push,
            armctl.Reference.hold([0.0]),
            0.1,
            integrator="implicit-euler",
            forces=Forces(environment=wall),
        )
        assert "unstable_contacts" not in res.info
        soft = Plane(KelvinVoigt(1e5), normal=(-1.0, 0.0, 0.0), point=(0.01, 0.0, 0.0))
        assert (
            "unstable_contacts"
            not in simulate(slider(2.0), push, armctl.Reference.hold([0.0]), 0.1, forces=Forces(environment=soft)).info
        )


@pytest.mark.parametrize("zeta", [0.05, 0.5, 2.0])
def test_rk4_limit_of_a_damped_contact_from_its_stability_function(zeta: float) -> None:
    # RK4 on ẋ = A x is stable while |R(hλ)| ≤ 1 for both eigenvalues λ of A, R(z) = 1 + z + z²/2 + z³/6 + z⁴/24:
    # the largest such h, by bisection on that scalar function (not on the one-step matrix the code uses)
    mass, k = 2.0, 1e7
    omega = math.sqrt(k / mass)
    c = 2.0 * zeta * omega * mass
    lam = np.roots([1.0, c / mass, k / mass])

    def stable(h: float) -> bool:
        z = h * lam
        return bool(np.abs(1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24).max() <= 1.0 + 1e-12)

    lo, hi = 0.0, 10.0 / omega
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    wall = Plane(KelvinVoigt(k, c), normal=(-1.0, 0.0, 0.0), point=(0.01, 0.0, 0.0))
    (found,) = contact_stability(armctl.Dynamics(slider(mass)), [wall], np.zeros(1), "rk4", 1e-3)
    assert found.linear_dt == pytest.approx(lo, rel=1e-6)


@pytest.mark.steps_may_differ("a contact unstable for the scheme, on purpose")
@pytest.mark.parametrize("zeta", [0.0, 0.05])
# the unstable contact also shows in the contact's work
@pytest.mark.filterwarnings("ignore:the contact did:armctl.errors.SimulationWarning")
def test_one_sided_contact_gaining_energy_below_the_linear_limit_is_reported(zeta: float) -> None:
    # a 2 kg slider at rest on a wall's surface, pushed into it with 10 N: the exact motion keeps the force
    # between 0 and 20 N undamped (and below that damped). At ω·dt = 1.8 the Euler variants are linearly stable
    # (limit 2), yet every reopening of the contact pumps energy in; RK4 (limit 2√2) integrates it
    mass, push, omega_h = 2.0, 10.0, 1.8
    k = mass * (omega_h / 1e-3) ** 2
    wall = Plane(KelvinVoigt(k, 2.0 * zeta * math.sqrt(k * mass)), normal=(-1.0, 0.0, 0.0), point=(0.0, 0.0, 0.0))
    run = OpenLoop(lambda t: np.array([push]))
    for scheme in ("euler", "semi-implicit-euler"):
        (found,) = contact_stability(armctl.Dynamics(slider(mass)), [wall], np.zeros(1), scheme, 1e-3)
        assert found.radius <= 1.0 and not found.stable
        with pytest.warns(SimulationWarning, match="linearly stable, but as a one-sided contact"):
            bad = simulate(
                slider(mass), run, armctl.Reference.hold([0.0]), 0.5, integrator=scheme, forces=Forces(environment=wall)
            )
        assert np.abs(bad.contact_force_on_environment).max() > 1.5 * 2.0 * push  # what the warning is about
        dt = 1e-3 / math.ceil(1e-3 / bad.info["unstable_contacts"][0]["max_dt"])  # the step it recommends
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            good = simulate(
                slider(mass),
                run,
                armctl.Reference.hold([0.0]),
                0.5,
                integrator=scheme,
                dt=dt,
                forces=Forces(environment=wall),
            )
        assert np.abs(good.contact_force_on_environment).max() <= 1.02 * 2.0 * push
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = simulate(
            slider(mass), run, armctl.Reference.hold([0.0]), 0.5, integrator="rk4", forces=Forces(environment=wall)
        )
    assert np.abs(res.contact_force_on_environment).max() <= 2.0 * push * (1 + 1e-9)


def test_the_one_sided_limits_hold_for_the_impact_model() -> None:
    # SAFE_OMEGA_H: up to it the one-sided impact model gains at most its energy at every damping ratio where
    # the linear check passes; well beyond it, undamped, it gains orders of magnitude more
    from armctl.sim.stability import SAFE_OMEGA_H, _radius, impact_gain

    for scheme, steps in (("euler", (0.3, 0.4)), ("semi-implicit-euler", (0.3, 0.4)), ("rk4", (1.0, 1.9))):
        assert SAFE_OMEGA_H[scheme] == steps[-1]
        for wh in steps:
            for zeta in (0.0, 0.05, 0.3, 1.0, 2.0):
                if _radius(scheme, wh * wh, 2.0 * zeta * wh, 1.0) <= 1.0 + 1e-12:
                    assert impact_gain(scheme, wh, 2.0 * zeta * wh) <= 1.0, (scheme, wh, zeta)
    assert impact_gain("euler", 1.0, 0.0) > 10.0 and impact_gain("rk4", 2.3, 0.0) > 10.0


def _press(law: object, integrator: str) -> tuple[armctl.sim.SimResult, list[warnings.WarningMessage]]:
    """planar_2r pushed by PD + gravity compensation into a floor 0.3 m below its base, for 0.5 s."""
    from armctl.controllers import PDGravity

    dyn = armctl.Dynamics(armctl.models.planar_2r())
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = simulate(
            dyn,
            PDGravity(dyn, 2000.0, 200.0),
            armctl.Reference([-0.5, 0.3]),
            0.5,
            q0=[0.0, 0.0],
            integrator=integrator,
            forces=Forces(environment=Plane(law, point=(0.0, 0.0, -0.3))),
        )  # type: ignore[arg-type]
    # (a run thrown off the wall may also overrun a velocity limit, said in a warning of its own)
    said = [w for w in caught if issubclass(w.category, SimulationWarning)]
    return res, [w for w in said if not str(w.message).startswith("the run went beyond the plant's limits")]


def test_energy_gained_on_a_contact_that_could_not_be_checked_is_reported() -> None:
    """Hunt–Crossley with p = 1.5 stiffens with depth, so the step cannot be judged before the run. At
    k = 1e11 RK4 at 1 ms throws the arm off with energy no force supplied: the run says so afterwards (it does
    not diverge numerically); implicit Euler, the remedy the warning names, gains none and ends elsewhere."""
    from armctl.sim import HuntCrossley

    stiff = HuntCrossley(1e11, exponent=1.5)
    bad, warned = _press(stiff, "rk4")
    assert not bad.diverged
    # the balance, and the wall's work, which a passive wall keeps ≤ 0
    texts = sorted(str(w.message) for w in warned)
    assert len(texts) == 2 and all("implicit-euler" in t for t in texts)
    assert "a compliant surface only gives back" in texts[1] and "the arm gained" in texts[0]
    assert bad.info["energy_gain"] > 100.0  # joules, against ~150 J exchanged by a stable run
    good, warned = _press(stiff, "implicit-euler")
    assert warned == [] and "energy_gain" not in good.info
    assert np.abs(good.q[-1] - bad.q[-1]).max() > 0.2
    # the same law, softer: RK4 is stable, the balance closes, nothing is said
    soft, warned = _press(HuntCrossley(1e6, exponent=1.5), "rk4")
    assert warned == [] and abs(soft.info["energy_gain"]) < 1e-3
    np.testing.assert_allclose(soft.q[-1], good.q[-1], atol=0.05)  # near where implicit Euler ends


@pytest.mark.parametrize("zeta", [0.1, 0.7, 2.0])
def test_euler_variants_limit_of_a_damped_contact_in_closed_form(zeta: float) -> None:
    """The largest stable step of a damped wall for the two Euler schemes, in closed form: the one-step map's
    characteristic polynomial λ² − T λ + D is Schur-stable iff |D| < 1 and 1 ± T + D > 0 (Jury). Euler
    (v₁ = v − h(ω² x + c v), x₁ = x + h v₁): T = 2 − h²ω² − hc, D = 1 − hc, binding where h²ω² + 2hc = 4;
    semi-implicit Euler (damping at v₁): T = 1 + (1 − h²ω²)/(1 + hc), D = 1/(1 + hc), binding where
    h²ω² − 2hc = 4 — damping shortens the first's step and lengthens the second's."""
    mass, k = 2.0, 1e7
    omega = math.sqrt(k / mass)
    c = 2.0 * zeta * omega  # damping / mass
    wall = Plane(KelvinVoigt(k, c * mass), normal=(-1.0, 0.0, 0.0), point=(0.01, 0.0, 0.0))
    limits = {
        "euler": (-c + math.sqrt(c * c + 4.0 * omega**2)) / omega**2,
        "semi-implicit-euler": (c + math.sqrt(c * c + 4.0 * omega**2)) / omega**2,
    }
    for scheme, limit in limits.items():
        (found,) = contact_stability(armctl.Dynamics(slider(mass)), [wall], np.zeros(1), scheme, 1e-4)
        assert found.linear_dt == pytest.approx(limit, rel=1e-6), scheme
