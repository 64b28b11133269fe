"""Bad input to the controllers raises a named ArmctlError, and leaves the controller as it was.

* ``Controller.__call__`` checks q and q̇ on a cheap fast path. The built-in laws without state check only τ
  (``_checks_result``: a NaN/inf in any entry of q or q̇ reaches τ through the PD or sliding term), and the
  inputs only when τ is not finite. Whatever the law, every entry of q and q̇ made NaN, +inf or −inf must raise
  a NonFiniteError naming that input and leave the controller's state (integral, θ̂) as it was; arrays that are
  not real numbers must raise an ArmctlError naming the input; lists, integer and object arrays of numbers must
  give the float result. Time must be finite, never runs an integral backwards, and a controller keeps no
  reference to the caller's arrays.
* A masked array is not read through its mask: a masked entry is refused by name by the dynamics' regressors
  and by every controller (never its hidden value; with ``ki=`` or ``Adaptive`` too, not a bare TypeError from
  the controller's base class)."""

from __future__ import annotations

import warnings
from collections.abc import Callable

import numpy as np
import pytest

import armctl
from armctl.controllers import Adaptive, ComputedTorque, Controller, PassivityBased, PDGravity
from armctl.errors import ArmctlError, InvalidParameterError, NonFiniteError, ShapeError
from tests.helpers.arms import dynamics

LAWS: dict[str, Callable[[armctl.Dynamics], Controller]] = {
    "pd": lambda d: PDGravity(d, 100.0, 20.0),
    "pd_integral": lambda d: PDGravity(d, 100.0, 20.0, ki=5.0),
    "pd_matrix_gains": lambda d: PDGravity(d, np.eye(d.n) * 100.0 + 1.0, 20.0),
    "ct": lambda d: ComputedTorque(d, 100.0, 20.0),
    "ct_integral": lambda d: ComputedTorque(d, 100.0, 20.0, ki=5.0),
    "ct_reference_friction": lambda d: ComputedTorque(d, 100.0, 20.0, friction="reference"),
    "pb": lambda d: PassivityBased(d, 5.0, 20.0),
    "adaptive": lambda d: Adaptive(d, 5.0, 20.0, 0.01),
}


# panda (Pinocchio, no friction), puma560 (rotors, asymmetric Coulomb friction), the Lagrange backend on the
# frictionless pendulum (its τ holds no q̇ at all) and on planar_2r, and the compiled Pinocchio backend on the
# Panda (where PD + gravity runs as one call of generated code)
MODELS = (
    ("panda", "pinocchio"),
    ("puma560", "pinocchio"),
    ("pendulum", "lagrange"),
    ("planar_2r", "lagrange"),
    ("panda", "compiled"),
)


def _state(n: int) -> tuple[np.ndarray, np.ndarray, armctl.Reference]:
    q, qd, qdd = np.random.default_rng(5).uniform(-1.0, 1.0, (3, n))
    return q, qd, armctl.Reference(q + 0.02, qd - 0.1, qdd)


def _snapshot(c: Controller) -> list[np.ndarray]:
    out = []
    integral = getattr(c, "_integral", None)
    if integral is not None:
        out += [integral.value.copy(), np.array(np.nan if integral._t is None else integral._t)]
    if isinstance(c, Adaptive):
        out.append(c.theta.copy())
    return out


@pytest.mark.filterwarnings("ignore:invalid value encountered:RuntimeWarning")  # NaN arithmetic before the check
@pytest.mark.parametrize(("name", "backend"), MODELS)
@pytest.mark.parametrize("law", sorted(LAWS))
def test_every_non_finite_entry_is_named_and_changes_nothing(name: str, backend: str, law: str) -> None:
    dyn = dynamics(name, compile=True) if backend == "compiled" else dynamics(name, backend)
    c = LAWS[law](dyn)
    q, qd, ref = _state(dyn.n)
    c(0.0, q, qd, ref)  # start the clock of an integral
    c(1e-3, q, qd, ref)
    before = _snapshot(c)
    for which in ("q", "qd"):
        for j in range(dyn.n):
            for bad in (np.nan, np.inf, -np.inf):
                args = {"q": q.copy(), "qd": qd.copy()}
                args[which][j] = bad
                with pytest.raises(NonFiniteError, match=rf"^{which} holds NaN or inf"):
                    c(2e-3, args["q"], args["qd"], ref)
                for a, b in zip(_snapshot(c), before, strict=True):
                    assert np.array_equal(a, b, equal_nan=True), (which, j, bad)
    # and a good call afterwards gives what a fresh controller in the same state gives
    fresh = LAWS[law](dyn)
    fresh(0.0, q, qd, ref)
    fresh(1e-3, q, qd, ref)
    assert np.array_equal(c(2e-3, q, qd, ref), fresh(2e-3, q, qd, ref))


@pytest.mark.parametrize("law", sorted(LAWS))
def test_inputs_that_are_not_real_vectors(law: str) -> None:
    dyn = dynamics("panda")
    q, qd, ref = _state(dyn.n)
    expected = LAWS[law](dyn)(0.0, q, qd, ref)
    for which in ("q", "qd"):
        for bad, err in [
            (np.full(dyn.n, 1.0 + 1.0j), ArmctlError),  # not cut to its real part
            (np.full(dyn.n, 0.5 + 0.0j), ArmctlError),  # complex even when it is real
            (np.array(["a"] * dyn.n), ArmctlError),
            (np.array([0.1] * (dyn.n - 1) + [None], dtype=object), ArmctlError),
            (np.zeros((dyn.n, 1)), ShapeError),
            (np.zeros(dyn.n + 1), ShapeError),
            (np.zeros(1), ShapeError),
            (None, ArmctlError),
        ]:
            args = {"q": q, "qd": qd, which: bad}
            with pytest.raises(err, match=rf"^{which} "):
                LAWS[law](dyn)(0.0, args["q"], args["qd"], ref)
        good = {"q": q, "qd": qd}[which]
        for same in (good.tolist(), good.astype(object)):
            args = {"q": q, "qd": qd, which: same}
            assert np.array_equal(LAWS[law](dyn)(0.0, args["q"], args["qd"], ref), expected), (which, type(same))
    ints = {"q": np.arange(dyn.n) % 2, "qd": np.ones(dyn.n, dtype=int)}
    floats = {k: v.astype(float) for k, v in ints.items()}
    assert np.array_equal(
        LAWS[law](dyn)(0.0, ints["q"], ints["qd"], ref), LAWS[law](dyn)(0.0, floats["q"], floats["qd"], ref)
    )


def test_only_the_stateless_laws_check_their_result() -> None:
    """The flag itself: a law with state (integral, θ̂) must check its inputs before computing."""
    dyn = dynamics("panda")
    flags = {law: LAWS[law](dyn)._checks_result for law in LAWS}
    assert flags == {
        "pd": True,
        "pd_integral": False,
        "pd_matrix_gains": True,
        "ct": True,
        "ct_integral": False,
        "ct_reference_friction": True,
        "pb": True,
        "adaptive": False,
    }
    assert Controller._checks_result is False  # a user's controller: inputs first


def test_a_reference_of_anything_but_real_numbers_is_refused() -> None:
    for field in ("q", "qd", "qdd"):
        for bad in ([0.5j, 0.0], [0.5 + 0j, 0.0], ["a", "b"]):
            values = {"q": [0.1, 0.2], field: bad}
            with pytest.raises(InvalidParameterError, match=rf"^Reference {field} must hold real numbers"):
                armctl.Reference(**values)  # type: ignore[arg-type]
    ref = armctl.Reference(np.array([1, 2]), np.array([0.5, 1], dtype=object))
    assert ref.q.dtype == ref.qd.dtype == np.float64 and ref.qd.tolist() == [0.5, 1.0]


@pytest.mark.parametrize("law", sorted(LAWS))
def test_time_must_be_a_finite_real_number(law: str) -> None:
    dyn = dynamics("panda")
    c = LAWS[law](dyn)
    q, qd, ref = _state(dyn.n)
    c(0.0, q, qd, ref)
    c(1e-3, q, qd, ref)
    before = _snapshot(c)
    for bad, err in [
        (np.nan, NonFiniteError),
        (np.inf, NonFiniteError),
        ("soon", InvalidParameterError),
        (None, InvalidParameterError),
        (1j, InvalidParameterError),
    ]:
        with pytest.raises(err, match=r"^t must be"):
            c(bad, q, qd, ref)  # type: ignore[arg-type]
        for a, b in zip(_snapshot(c), before, strict=True):
            assert np.array_equal(a, b, equal_nan=True), bad
    assert np.isfinite(c(np.float32(2e-3), q, qd, ref)).all()


@pytest.mark.parametrize("law", ["pd_integral", "ct_integral"])
def test_an_integral_never_runs_backwards_in_time(law: str) -> None:
    # a second run without reset() starts its clock at 0 again: the interval back to 0 is not integrated
    dyn = dynamics("panda")
    c = LAWS[law](dyn)
    q, qd, ref = _state(dyn.n)
    e = ref.q - q
    for t in (0.0, 1.0, 1.5):
        c(t, q, qd, ref)
    assert np.allclose(c._integral.value, 1.5 * e)  # type: ignore[attr-defined]
    c(0.5, q, qd, ref)  # back in time: the clock restarts here
    assert np.allclose(c._integral.value, 1.5 * e)  # type: ignore[attr-defined]
    c(0.6, q, qd, ref)
    assert np.allclose(c._integral.value, 1.6 * e)  # type: ignore[attr-defined]
    c(0.6, q, qd, ref)  # the same instant again adds nothing
    assert np.allclose(c._integral.value, 1.6 * e)  # type: ignore[attr-defined]


def test_adaptive_keeps_no_reference_to_the_callers_arrays() -> None:
    # composite adaptation differences q̇ between calls: a loop that refills one q̇ buffer in place (and clips
    # τ in place) must get what fresh arrays get
    dyn = dynamics("planar_2r")
    rng = np.random.default_rng(3)
    states = rng.uniform(-1.0, 1.0, (6, 2, dyn.n))
    ref = armctl.Reference([0.2, -0.3], [0.1, 0.0])
    fresh = Adaptive(dyn, 5.0, 10.0, 0.5, composite=0.2)
    reused = Adaptive(dyn, 5.0, 10.0, 0.5, composite=0.2)
    q_buf, qd_buf = np.zeros(dyn.n), np.zeros(dyn.n)
    for k, (q, qd) in enumerate(states):
        t = 1e-3 * k
        expected = fresh(t, q.copy(), qd.copy(), ref)
        q_buf[:], qd_buf[:] = q, qd
        tau = reused(t, q_buf, qd_buf, ref)
        assert np.array_equal(tau, expected), k
        tau *= 0.5  # the caller scales or clips the command in place
    assert np.array_equal(fresh.theta, reused.theta)


def test_adaptive_dead_zone_holds_theta() -> None:
    # inside the dead zone no term moves θ̂: neither the gradient nor σ-modification nor the composite term
    dyn = dynamics("planar_2r")
    theta0 = dyn.parameters() * 1.1
    c = Adaptive(dyn, 5.0, 10.0, 0.5, theta0=theta0, sigma=1.0, composite=0.5, dead_zone=1e3)
    rng = np.random.default_rng(8)
    ref = armctl.Reference([0.2, -0.3], [0.1, 0.0])
    for k in range(5):
        q, qd = rng.uniform(-0.5, 0.5, (2, dyn.n))
        c(1e-3 * k, q, qd, ref)
    assert np.array_equal(c.theta, theta0)
    outside = Adaptive(dyn, 5.0, 10.0, 0.5, theta0=theta0, sigma=1.0, composite=0.5, dead_zone=1e-6)
    for k in range(2):
        outside(1e-3 * k, np.array([0.4, 0.1]), np.array([0.3, -0.2]), ref)
    assert not np.array_equal(outside.theta, theta0)


def test_a_one_joint_reference_from_scalars() -> None:
    ref = armctl.Reference(0.3, 0.1, -0.2)
    assert (ref.q.tolist(), ref.qd.tolist(), ref.qdd.tolist()) == ([0.3], [0.1], [-0.2])
    assert armctl.Reference.hold(0.3).q.tolist() == [0.3]
    with pytest.raises(InvalidParameterError, match="q is required"):
        armctl.Reference(None)  # type: ignore[arg-type]
    with pytest.raises(ShapeError, match=r"qd must have shape \(2,\) like q, got \(\)"):
        armctl.Reference([0.1, 0.2], 0.5)  # type: ignore[arg-type]
    pendulum = dynamics("pendulum")
    assert np.isfinite(PDGravity(pendulum, 10.0, 1.0)(0.0, np.array([0.1]), np.array([0.0]), ref)).all()


@pytest.mark.parametrize(
    ("make", "gains"),
    [
        (lambda d, **g: PDGravity(d, **{"kp": 100.0, "kd": 20.0, **g}), {"kp": 400.0, "kd": np.arange(1.0, 8.0)}),
        (lambda d, **g: PDGravity(d, **{"kp": 100.0, "kd": 20.0, **g}), {"ki": 3.0}),
        (lambda d, **g: ComputedTorque(d, **{"kp": 100.0, "kd": 20.0, **g}), {"kp": np.eye(7) * 9.0, "kd": 7.0}),
        (lambda d, **g: PassivityBased(d, **{"lam": 5.0, "kd": 20.0, **g}), {"lam": 2.0, "kd": np.eye(7) * 3.0}),
        (lambda d, **g: Adaptive(d, **{"lam": 5.0, "kd": 20.0, "gamma": 0.01, **g}), {"lam": 2.0, "gamma": 0.5}),
    ],
    ids=["pd", "pd_integral_added", "ct", "pb", "adaptive"],
)
def test_gains_reassigned_take_effect(make: Callable[..., Controller], gains: dict[str, object]) -> None:
    # a gain sweep that reassigns ctrl.kp must run the new gain, not the one the controller was built with
    dyn = dynamics("panda")
    q, qd, ref = _state(dyn.n)
    changed, fresh = make(dyn), make(dyn, **gains)
    for name, value in gains.items():
        setattr(changed, name, value)
    for k in range(3):
        assert np.array_equal(changed(1e-3 * k, q, qd, ref), fresh(1e-3 * k, q, qd, ref)), k
    with pytest.raises(InvalidParameterError, match="positive definite"):
        setattr(changed, next(iter(gains)), -1.0)


def test_a_gain_is_the_controllers_own_copy() -> None:
    # the law's precomputed product follows assignments only: editing the array given, or the one read back,
    # must not change one and not the other
    dyn = dynamics("panda")
    q, qd, ref = _state(dyn.n)
    k = np.eye(7) * 100.0 + 1.0  # full (not diagonal)
    ctrl, fresh = PDGravity(dyn, k, 20.0), PDGravity(dyn, k.copy(), 20.0)
    k *= 2.0
    assert np.array_equal(ctrl.kp, fresh.kp) and np.array_equal(ctrl(0.0, q, qd, ref), fresh(0.0, q, qd, ref))
    with pytest.raises(ValueError, match="read-only"):
        ctrl.kp[0, 0] = 1.0
    ctrl.kp = 2.0 * ctrl.kp  # the way to change it
    assert np.array_equal(ctrl(0.0, q, qd, ref), PDGravity(dyn, k, 20.0)(0.0, q, qd, ref))


def test_task_gains_reassigned_take_effect() -> None:
    from armctl.controllers.osc import PostureTask

    task, fresh = PostureTask(7, kp=100.0), PostureTask(7, kp=400.0, kd=40.0)
    task.kp, task.kd = 400.0, 40.0  # type: ignore[assignment]
    assert np.array_equal(task._kp, fresh._kp) and np.array_equal(task._kd, fresh._kd)
    with pytest.raises(InvalidParameterError, match="kp"):
        task.kp = -1.0  # type: ignore[assignment]


def test_pd_friction_flag_must_be_a_bool() -> None:
    with pytest.raises(InvalidParameterError, match="friction"):
        PDGravity(dynamics("panda"), 1.0, 1.0, friction="reference")  # type: ignore[arg-type]


def test_a_subclass_with_its_own_compute_gets_its_inputs_checked_first() -> None:
    # the result-only check holds for the built-in law; a subclass's compute may keep state (here a velocity
    # filter) that a NaN must never reach
    class Filtered(PDGravity):
        def compute(self, t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
            self.filtered = qd if not hasattr(self, "filtered") else 0.5 * (self.filtered + qd)
            return super().compute(t, q, self.filtered, ref)

    dyn = dynamics("panda")
    q, qd, ref = _state(dyn.n)
    c = Filtered(dyn, 100.0, 20.0)
    assert not c._checks_result and PDGravity(dyn, 100.0, 20.0)._checks_result
    c(0.0, q, qd, ref)
    bad = qd.copy()
    bad[1] = np.nan
    with pytest.raises(NonFiniteError, match=r"^qd"):
        c(1e-3, q, bad, ref)
    assert np.isfinite(c(2e-3, q, qd, ref)).all()

    class Sub(PassivityBased):  # a subclass that keeps the built-in law keeps its fast check
        pass

    assert Sub(dyn, 5.0, 20.0)._checks_result


@pytest.mark.parametrize("law", ["pd", "ct", "pb"])
def test_non_finite_input_is_named_even_when_numpy_warnings_are_errors(law: str) -> None:
    dyn = dynamics("panda")
    c = LAWS[law](dyn)
    q, qd, ref = _state(dyn.n)
    for which, bad in (("q", np.inf), ("qd", -np.inf), ("q", np.nan)):
        args = {"q": q.copy(), "qd": qd.copy()}
        args[which][2] = bad
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            with pytest.raises(NonFiniteError, match=rf"^{which} "):
                c(0.0, args["q"], args["qd"], ref)
        with np.errstate(all="raise"), pytest.raises(NonFiniteError, match=rf"^{which} "):
            c(0.0, args["q"], args["qd"], ref)


def test_text_is_not_a_number() -> None:
    # NumPy would parse "0.3"; a string where a number belongs is a mistake to report
    dyn = dynamics("planar_2r")
    q, qd, ref = _state(dyn.n)
    c = PDGravity(dyn, 10.0, 1.0)
    for bad_ref in (
        lambda: armctl.Reference("0.3"),
        lambda: armctl.Reference(b"0.3"),
        lambda: armctl.Reference(np.array(["0.1", "0.2"])),
    ):
        with pytest.raises(InvalidParameterError, match="must hold real numbers"):
            bad_ref()
    with pytest.raises(InvalidParameterError, match=r"^q must hold real numbers"):
        c(0.0, np.array(["0.1", "0.2"]), qd, ref)
    with pytest.raises(InvalidParameterError, match=r"^q must hold real numbers"):
        dyn.mass_matrix(np.array([0.1, "0.2"], dtype=object))
    for t in ("0.5", b"0.5", np.complex128(0.5 + 1j), 10**400):
        with pytest.raises(InvalidParameterError, match=r"^t must be a real number"):
            c(t, q, qd, ref)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="kp"):
        PDGravity(dyn, "100", 1.0)  # type: ignore[arg-type]


def test_composite_adaptation_switched_on_between_calls() -> None:
    dyn = dynamics("planar_2r")
    q, qd, ref = _state(dyn.n)
    c = Adaptive(dyn, 5.0, 10.0, 0.5)
    c(0.0, q, qd, ref)
    c.composite = 0.2
    for k in range(1, 4):  # the filters start at the first call with composite on
        assert np.isfinite(c(1e-3 * k, q, qd + 0.01 * k, ref)).all()


def test_task_gains_reassigned_reach_the_qp() -> None:
    from armctl.controllers.osc import OperationalSpaceQP, PostureTask

    dyn = dynamics("panda")
    q, qd, ref = _state(dyn.n)
    task = PostureTask(7, kp=100.0)
    changed = OperationalSpaceQP(dyn, [task])
    task.kp, task.kd = 400.0, 40.0  # type: ignore[assignment]
    fresh = OperationalSpaceQP(dyn, [PostureTask(7, kp=400.0, kd=40.0)])
    np.testing.assert_allclose(changed(0.0, q, qd, ref), fresh(0.0, q, qd, ref), rtol=1e-9, atol=1e-9)


def test_a_non_finite_torque_from_a_finite_state_raises() -> None:
    """Gains, estimates or a state too large for floats: the law's τ overflows although every input is
    finite. Every controller, with or without state, and a user's own, raises instead of returning it."""
    dyn = dynamics("planar_2r")
    z, ref = np.zeros(2), armctl.Reference(np.zeros(2))

    class Overflowing(Controller):
        def compute(self, t: float, q: np.ndarray, qd: np.ndarray, r: armctl.Reference) -> np.ndarray:
            return np.array([1e308, 1e308]) * 10.0

    class AsList(Controller):  # a user's law may return a list: passed through as it is
        def compute(self, t: float, q: np.ndarray, qd: np.ndarray, r: armctl.Reference) -> list[float]:
            return [1.0, 2.0]

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # NumPy's overflow warnings on the way
        cases = [
            (PDGravity(dyn, 100.0, 10.0), np.array([1e307, 0.0])),
            (PassivityBased(dyn, 1e308, 10.0), np.array([1.0, 0.0])),
            (ComputedTorque(dyn, 1e308, 1e308, ki=1.0), np.array([1.0, 0.0])),  # with state (integral)
            (Adaptive(dyn, 1.0, 10.0, 1.0, theta0=np.full(26, 1e308)), np.array([1.0, 0.5])),
            (Overflowing(n=2), z),
        ]
        for ctrl, q in cases:
            with pytest.raises(NonFiniteError, match=rf"^{type(ctrl).__name__} gave a non-finite torque"):
                ctrl(0.0, q, z, ref)
    assert AsList(n=2)(0.0, z, z, ref) == [1.0, 2.0]


def test_a_users_law_gets_finite_native_floats_and_only_those() -> None:
    """A law with state (its inputs checked before it runs): a byte-swapped float64 state reaches it as native
    floats of the same values, finite entries whose sum overflows are taken, NaN or inf in q, q̇ or t raise
    before the law runs."""
    seen: list[tuple[np.ndarray, np.ndarray]] = []

    class Recording(Controller):
        def compute(self, t: float, q: np.ndarray, qd: np.ndarray, r: armctl.Reference) -> np.ndarray:
            seen.append((q, qd))
            return np.array([q[0] - qd[1], 2.0])

    ctrl, ref = Recording(n=2), armctl.Reference(np.zeros(2))
    swapped = np.array([0.5, -1.5], dtype=">f8")
    np.testing.assert_array_equal(ctrl(0.0, swapped, swapped, ref), [2.0, 2.0])
    assert seen[-1][0].dtype == np.float64 and seen[-1][0].dtype.isnative
    np.testing.assert_array_equal(seen[-1][0], [0.5, -1.5])
    big = np.array([1e308, 1e308])
    np.testing.assert_array_equal(ctrl(0.0, big, np.zeros(2), ref), [1e308, 2.0])
    calls = len(seen)
    for t, q, qd, name in [
        (0.0, np.array([0.0, np.nan]), np.zeros(2), "^q"),
        (0.0, np.zeros(2), np.array([np.inf, 0.0]), "^qd"),
        (np.inf, np.zeros(2), np.zeros(2), "^t must be finite"),
    ]:
        with pytest.raises(NonFiniteError, match=name):
            ctrl(t, q, qd, ref)
    assert len(seen) == calls


@pytest.mark.parametrize("flag", [1, 1.0, 0, "measured", None])
def test_computed_torque_friction_mode_is_true_false_or_reference(flag: object) -> None:
    # 1 and 1.0 equal True, so they passed the check and then took the reference-velocity branch
    dyn = dynamics("planar_2r")
    with pytest.raises(InvalidParameterError, match=r"^friction must be True, False or 'reference', got"):
        ComputedTorque(dyn, 100.0, 20.0, friction=flag)  # type: ignore[arg-type]
    ct = ComputedTorque(dyn, 100.0, 20.0)
    with pytest.raises(InvalidParameterError, match=r"^friction must be True, False or 'reference', got"):
        ct.friction = flag  # type: ignore[assignment]
    assert ct.friction is True


def test_computed_torque_numpy_true_compensates_at_the_measured_velocity() -> None:
    dyn = armctl.Dynamics(armctl.models.planar_2r().with_friction(viscous=[2.0, 1.0], coulomb=[4.0, 3.0]))
    q, qd = np.array([0.2, -0.3]), np.array([0.5, -0.4])
    ref = armctl.Reference([0.1, 0.0], [-0.6, 0.7], [0.0, 0.0])  # q̇_d opposite to q̇: the two modes differ
    tau = {
        flag: ComputedTorque(dyn, 100.0, 20.0, friction=flag)(0.0, q, qd, ref)
        for flag in (True, np.True_, "reference", False)
    }
    fv, fc = np.array([2.0, 1.0]), np.array([4.0, 3.0])
    np.testing.assert_allclose(tau[np.True_] - tau[False], fv * qd + fc * np.sign(qd), rtol=1e-12)
    np.testing.assert_allclose(tau["reference"] - tau[False], fv * ref.qd + fc * np.sign(ref.qd), rtol=1e-12)
    assert np.array_equal(tau[np.True_], tau[True])


def test_composite_adaptation_is_stable_at_a_step_where_explicit_euler_diverged() -> None:
    # pendulum, controller model with mass and inertia ×1.5, κ = 10: Γ κ dt λ_max(W_fᵀW_f) ≈ 2.8 at 1 ms, past
    # explicit Euler's limit of 2 (θ̂ reached 4e6 and the run diverged at 0.44 s). The reference: the same law
    # at a tenth of the period, where every scheme follows the continuous law
    from armctl.references import Sinusoid

    plant = armctl.Dynamics(armctl.models.pendulum().with_friction(viscous=0.0))
    model = armctl.Dynamics(armctl.models.pendulum().with_friction(viscous=0.0).perturbed(mass=1.5, inertia=1.5))
    ref = Sinusoid([0.3], [0.8], [0.7])
    runs = {
        dt: armctl.simulate(
            plant, Adaptive(model, 10.0, 5.0, 0.5, composite=10.0), ref, 2.0, control_dt=dt, saturate=False
        )
        for dt in (1e-3, 1e-4)
    }
    assert not any(r.diverged for r in runs.values())
    coarse, fine = (np.asarray(runs[dt].logs["theta"])[-1] for dt in (1e-3, 1e-4))
    assert np.abs(coarse - fine).max() < 0.005 * np.abs(fine).max()  # 0.09 % measured
    assert np.abs(runs[1e-3].q[-1] - runs[1e-4].q[-1]).max() < 1e-4


CONTROLLERS = {
    "ComputedTorque": lambda d: ComputedTorque(d, 100.0, 20.0),
    "PDGravity": lambda d: PDGravity(d, 100.0, 20.0),
    "PDGravity(ki=)": lambda d: PDGravity(d, 100.0, 20.0, ki=10.0),
    "PassivityBased": lambda d: PassivityBased(d, 5.0, 20.0),
    "Adaptive": lambda d: Adaptive(d, 5.0, 20.0, 0.1),
}


def _masked() -> np.ma.MaskedArray:
    return np.ma.masked_array([0.1, 1e6], mask=[False, True])  # the hidden entry would be a wild value


@pytest.mark.parametrize("make", sorted(CONTROLLERS))
@pytest.mark.parametrize("position", ["q", "qd"])
def test_controllers_refuse_a_masked_entry(make: str, position: str) -> None:
    dyn = armctl.Dynamics(armctl.models.planar_2r())
    ctrl = CONTROLLERS[make](dyn)
    z = np.zeros(2)
    args = {"q": z, "qd": z, position: _masked()}
    with pytest.raises(InvalidParameterError, match=rf"^{position} has masked entries"):
        ctrl(0.0, args["q"], args["qd"], armctl.Reference(z, z, z))
