"""Bad input to `Dynamics` raises a named ArmctlError.

* The hot methods check their inputs on a cheap fast path and fall back to a named check only when it fails.
  Every entry of every input, made NaN, +inf or −inf, must still raise a NonFiniteError naming that input,
  whatever the model terms depend on (M(q) does not depend on q₁, for instance); wrong shapes must raise a
  ShapeError; lists and integer arrays must give the same result as float arrays.
* A masked array is not read through its mask: a masked entry is refused by name (the regressors and the
  inverse dynamics included: they never use the hidden value).
* Finite inputs too large for floats are named: the error says which input overflowed, on every method whose
  result can overflow (kinetic energy, the Coriolis matrix, both regressors and the passivity torque included,
  never NaN or inf with no error; a huge wrench is named, not τ)."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from functools import cache

import numpy as np
import pytest

import armctl
from armctl.errors import InvalidParameterError, NonFiniteError, ShapeError
from tests.helpers.arms import dynamics

# method name → its vector arguments, in order
METHODS: dict[str, tuple[str, ...]] = {
    "mass_matrix": ("q",),
    "gravity_torque": ("q",),
    "coriolis_matrix": ("q", "qd"),
    "friction_torque": ("qd",),
    "inverse_dynamics": ("q", "qd", "qdd"),
    "forward_dynamics": ("q", "qd", "tau"),
    "regressor": ("q", "qd", "qdd"),
    "passivity_regressor": ("q", "qd", "qd_r", "qdd_r"),
    "passivity_torque": ("q", "qd", "qd_r", "qdd_r"),
}


# panda: no friction (the rigid fast paths); puma560: rotors and asymmetric Coulomb friction; the Lagrange
# backend (CasADi functions) on a small arm; "compiled": the Pinocchio backend with compile=True (generated C
# code whose expressions CasADi simplified, the Panda's g₁ free of q₁ for one; "pendulum_bare": one joint, no
# motor and no friction, the regressor probe's least favourable case)
MODELS = (
    ("panda", "pinocchio"),
    ("puma560", "pinocchio"),
    ("planar_2r", "lagrange"),
    ("panda", "compiled"),
    ("puma560", "compiled"),
    ("pendulum_bare", "compiled"),
)


def _dynamics(name: str, backend: str) -> armctl.Dynamics:
    if name == "pendulum_bare":
        return _bare_pendulum()
    return dynamics(name, "pinocchio", compile=True) if backend == "compiled" else dynamics(name, backend)


@cache
def _bare_pendulum() -> armctl.Dynamics:
    return armctl.Dynamics(armctl.models.pendulum().reduced(rotors=False, friction=False), compile=True)


def _args(n: int, k: int) -> list[np.ndarray]:
    return list(np.random.default_rng(11).uniform(-1.0, 1.0, (k, n)))


@pytest.mark.parametrize(("name", "backend"), MODELS)
@pytest.mark.parametrize("method", sorted(METHODS))
# the fast paths compute first and check the result, so an inf may meet another (inf − inf) on the way:
# NumPy's RuntimeWarning, then the named error this test checks
@pytest.mark.filterwarnings("ignore:invalid value encountered:RuntimeWarning")
def test_every_nonfinite_entry_is_named(name: str, backend: str, method: str) -> None:
    dyn = _dynamics(name, backend)
    fn: Callable[..., object] = getattr(dyn, method)
    names = METHODS[method]
    args = _args(dyn.n, len(names))
    fn(*args)  # finite inputs pass
    for pos, arg_name in enumerate(names):
        for j in range(dyn.n):
            for bad in (np.nan, np.inf, -np.inf):
                broken = [a.copy() for a in args]
                broken[pos][j] = bad
                with pytest.raises(NonFiniteError, match=rf"^{arg_name} holds NaN or inf"):
                    fn(*broken)


@pytest.mark.parametrize(("name", "backend"), MODELS)
@pytest.mark.parametrize("method", sorted(METHODS))
def test_wrong_shapes_are_named(name: str, backend: str, method: str) -> None:
    dyn = _dynamics(name, backend)
    names = METHODS[method]
    args = _args(dyn.n, len(names))
    wrong = {(dyn.n + 1,), (dyn.n - 1,), (1,), (dyn.n, 1), (1, dyn.n), ()} - {(dyn.n,)}  # n = 1: (1,) is right
    for pos, arg_name in enumerate(names):
        for shape in sorted(wrong):
            broken = list(args)
            broken[pos] = np.ones(shape)
            with pytest.raises(ShapeError, match=rf"^{arg_name} must have shape \({dyn.n},\)"):
                getattr(dyn, method)(*broken)


@pytest.mark.parametrize(("name", "backend"), MODELS)
@pytest.mark.parametrize("method", sorted(METHODS))
def test_lists_and_integer_arrays_give_the_same_result(name: str, backend: str, method: str) -> None:
    dyn = _dynamics(name, backend)
    fn = getattr(dyn, method)
    k = len(METHODS[method])
    ints = list(np.random.default_rng(5).integers(-2, 3, (k, dyn.n)))
    expected = np.array(fn(*[a.astype(float) for a in ints]))  # copied: results may be reused workspaces
    assert np.array_equal(fn(*ints), expected)
    assert np.array_equal(fn(*[a.tolist() for a in ints]), expected)


@pytest.mark.parametrize(("name", "backend"), MODELS)
@pytest.mark.parametrize("method", sorted(METHODS))
def test_big_endian_and_single_precision_arrays_give_the_float64_result(name: str, backend: str, method: str) -> None:
    # Pinocchio reads a big-endian array's bytes as if they were native (τ off by 3 N·m on puma560); float32
    # inputs must be converted before they are combined, not combined in single precision
    dyn = _dynamics(name, backend)
    fn = getattr(dyn, method)
    args = _args(dyn.n, len(METHODS[method]))
    single = [a.astype(np.float32) for a in args]
    for converted, expected_from in (
        ([a.astype(">f8") for a in args], args),
        (single, [a.astype(np.float64) for a in single]),
    ):
        expected = np.array(fn(*expected_from))
        assert np.array_equal(fn(*converted), expected)


@pytest.mark.parametrize(("name", "backend"), MODELS)
@pytest.mark.parametrize("method", sorted(METHODS))
def test_object_arrays_are_converted_and_complex_ones_refused(name: str, backend: str, method: str) -> None:
    # an object array of numbers passes the cheap finite test but Pinocchio refuses it: converted, not an
    # escaped Boost ArgumentError; complex values are refused, not cut to their real part
    dyn = _dynamics(name, backend)
    fn = getattr(dyn, method)
    names = METHODS[method]
    args = _args(dyn.n, len(names))
    expected = np.array(fn(*args))
    for pos, arg_name in enumerate(names):
        broken = list(args)
        broken[pos] = args[pos].astype(object)
        out = fn(*broken)
        assert out.dtype == np.float64 and np.array_equal(out, expected), arg_name
        for imag in (0.0, 1e-3):
            broken[pos] = args[pos] + 1j * imag
            with pytest.raises(InvalidParameterError, match=rf"^{arg_name} must hold real numbers"):
                fn(*broken)


@pytest.mark.parametrize(("name", "backend"), MODELS)
@pytest.mark.parametrize("method", sorted(METHODS))
def test_a_result_survives_the_next_call(name: str, backend: str, method: str) -> None:
    # results are fresh arrays: a later call, at another state, leaves an earlier result as it was
    dyn = _dynamics(name, backend)
    fn = getattr(dyn, method)
    k = len(METHODS[method])
    first = fn(*_args(dyn.n, k))
    kept = np.array(first, copy=True)
    second = fn(*list(np.random.default_rng(12).uniform(-1.0, 1.0, (k, dyn.n))))
    assert not np.shares_memory(first, second)
    assert np.array_equal(first, kept)


def test_an_input_the_expression_does_not_contain_is_still_checked() -> None:
    # CasADi simplifies: a frictionless pendulum's τ = (I + m l²) q̈ + m g l sin q holds no q̇, so a NaN q̇ never
    # reaches the result and must be caught on the inputs
    model = armctl.models.pendulum().with_friction(viscous=0.0, coulomb=0.0)
    for dyn in (
        armctl.Dynamics(model, backend="lagrange"),
        armctl.Dynamics(model),
        armctl.Dynamics(model, compile=True),
    ):
        for method in ("inverse_dynamics", "forward_dynamics"):
            with pytest.raises(NonFiniteError, match=r"^qd holds NaN or inf"):
                getattr(dyn, method)(np.array([0.3]), np.array([np.nan]), np.array([0.1]))


def test_none_entries_are_not_real_numbers() -> None:
    # NumPy turns None into NaN in a float conversion: the error must say what was given
    dyn = dynamics("panda")
    for q in ([None] + [0.0] * 6, np.array([None] * 7)):
        with pytest.raises(InvalidParameterError, match=r"^q must hold real numbers"):
            dyn.mass_matrix(q)


def test_an_integer_too_large_for_a_float_is_named() -> None:
    dyn = dynamics("panda")
    with pytest.raises(InvalidParameterError, match=r"^q must hold real numbers"):
        dyn.mass_matrix([10**400] + [0] * 6)
    huge = np.array([10**400] + [0] * 6, dtype=object)  # an object array: the sum of its entries overflows
    for method in ("passivity_torque", "passivity_regressor"):
        with pytest.raises(InvalidParameterError, match=r"^qd_r must hold real numbers"):
            getattr(dyn, method)(np.zeros(7), np.zeros(7), huge, np.zeros(7))


def test_masked_entries_are_refused_on_the_checked_paths() -> None:
    """NumPy would hand over the data hidden under a mask; the checks name it instead. (The hot fast paths
    take float64 arrays as they are and do not look for masks.)"""
    dyn = dynamics("puma560", "pinocchio")  # friction: the checked paths
    masked = np.ma.masked_array(np.ones(6), mask=[0, 1, 0, 0, 0, 0])
    for call in (
        lambda: dyn.coriolis_matrix(masked, masked),
        lambda: dyn.friction_torque(masked),
        lambda: dyn.coulomb_offset(masked),
        lambda: dyn.inverse_dynamics(masked, masked, masked),
    ):
        with pytest.raises(InvalidParameterError, match=r"^qd? has masked entries: fill them first"):
            call()
    unmasked = np.ma.masked_array(np.full(6, 0.5), mask=False)
    np.testing.assert_array_equal(dyn.friction_torque(unmasked), dyn.friction_torque(np.full(6, 0.5)))


@pytest.mark.parametrize("model", [armctl.models.puma560(), armctl.models.planar_2r().with_friction(viscous=0.5)])
def test_finite_inputs_too_large_for_floats_raise_with_friction_too(model: armctl.RobotModel) -> None:
    # q̇ = 1e200 overflows C q̇ to inf − inf = NaN; without friction this raised, with friction τ came back NaN
    dyn = armctl.Dynamics(model)
    assert dyn.friction.any
    n = dyn.n
    with pytest.raises(NonFiniteError, match=r"overflowed .* qd\[0\] = 1e\+200 is too large"):
        dyn.inverse_dynamics(np.zeros(n), np.full(n, 1e200), np.zeros(n))


@pytest.mark.parametrize(
    ("backend", "option", "names"),
    [
        ("pinocchio", "rotor_coupling", "its options: compile, cache_dir"),
        ("lagrange", "compiled", "its options: rotor_coupling, compile"),
    ],
)
def test_an_unknown_backend_option_is_named_with_the_valid_ones(backend: str, option: str, names: str) -> None:
    # it was a bare TypeError without the valid options
    from armctl.errors import InvalidParameterError

    with pytest.raises(InvalidParameterError, match=rf"\['{option}'\] for backend '{backend}' \({names}"):
        armctl.Dynamics(armctl.models.planar_2r(), backend=backend, **{option: True})


def test_the_name_universe_is_reserved() -> None:
    # Pinocchio's world frame is called "universe": a joint of that name made Dynamics fail on construction
    # with "Several frames match the filter"
    from armctl.errors import InvalidParameterError
    from armctl.model.dh import DHLink

    with pytest.raises(InvalidParameterError, match="'universe' is reserved"):
        armctl.RobotModel.from_dh([DHLink(a=0.3, mass=1.0, name="universe"), DHLink(a=0.2, mass=1.0)])


def _masked() -> np.ma.MaskedArray:
    return np.ma.masked_array([0.1, 1e6], mask=[False, True])  # the hidden entry would be a wild value


@pytest.mark.parametrize("method", ["regressor", "passivity_regressor", "passivity_torque", "inverse_dynamics"])
def test_the_dynamics_refuse_a_masked_entry(method: str) -> None:
    dyn = armctl.Dynamics(armctl.models.planar_2r())
    z = np.zeros(2)
    args = [z] * (4 if method.startswith("passivity") else 3)
    args[1] = _masked()
    with pytest.raises(InvalidParameterError, match=r"^qd has masked entries"):
        getattr(dyn, method)(*args)


BIG = 1e200  # finite; its square is not


def _cases(n: int) -> dict[str, tuple]:
    q, z = np.full(n, 0.3), np.zeros(n)
    big = np.full(n, BIG)
    return {
        "kinetic_energy": ("kinetic_energy", (q, big), "qd"),
        "regressor": ("regressor", (q, big, z), "qd"),
        "passivity_regressor": ("passivity_regressor", (q, big, z, z), "qd"),
        "passivity_torque": ("passivity_torque", (q, big, z, z), "qd"),
        "inverse_dynamics": ("inverse_dynamics", (q, big, z), "qd"),
        "forward_dynamics": ("forward_dynamics", (q, big, z), "qd"),
        "coriolis_matrix": ("coriolis_matrix", (q, np.full(n, 1e307)), "qd"),
    }


@pytest.mark.parametrize(
    ("backend", "options"), [("pinocchio", {}), ("pinocchio", {"compile": True}), ("lagrange", {})]
)
@pytest.mark.parametrize("case", sorted(_cases(2)))
def test_an_overflowing_input_is_named(backend: str, options: dict, case: str) -> None:
    model = armctl.models.planar_2r().with_friction(viscous=0.1, coulomb=0.2)
    dyn = armctl.Dynamics(model, backend=backend, **options)
    method, args, culprit = _cases(dyn.n)[case]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # NumPy may say "overflow" before the named error
        with pytest.raises(NonFiniteError, match=rf"overflowed .*{culprit}\[\d\] = 1e\+\d+ is too large") as info:
            getattr(dyn, method)(*args)
    assert np.array_equal(info.value.value, args[1])


@pytest.mark.parametrize(("backend", "options"), [("pinocchio", {}), ("lagrange", {"compile": True})])
@pytest.mark.parametrize("method", ["inverse_dynamics", "forward_dynamics"])
def test_a_huge_wrench_is_named_not_blamed_on_tau(backend: str, options: dict, method: str) -> None:
    dyn = armctl.Dynamics(armctl.models.planar_2r(), backend=backend, **options)
    q, z, wrench = np.array([0.3, 0.4]), np.zeros(2), np.full(6, 1.7e308)
    with np.errstate(over="ignore", invalid="ignore"):
        assert not np.isfinite(dyn.jacobian(q).T @ wrench).all()  # the premise: Jᵀh overflows
    with pytest.raises(NonFiniteError, match=r"overflowed .*wrench\[\d\] = 1\.7e\+308 is too large"):
        getattr(dyn, method)(q, z, z, wrench=wrench)


def test_large_but_representable_results_are_returned() -> None:
    dyn = armctl.Dynamics(armctl.models.panda())
    q, qd = np.full(7, 0.3), np.full(7, 1e120)  # quadratic terms ~1e240: finite
    y = dyn.regressor(q, qd, np.zeros(7))
    assert np.isfinite(y).all() and np.abs(y).max() > 1e200
    assert np.isfinite(dyn.kinetic_energy(q, qd))


# ------------------------------------------------------------------------- found by reading the boundary again
def test_kinetic_energy_names_a_nan_in_the_first_joints_position() -> None:
    """M(q) does not depend on q₁, so a NaN there did not reach T: the kinetic energy came back finite."""
    for options in ({}, {"compile": True}):
        dyn = armctl.Dynamics(armctl.models.planar_2r(), **options)
        with pytest.raises(NonFiniteError, match=r"^q holds NaN or inf"):
            dyn.kinetic_energy(np.array([np.nan, 0.3]), np.ones(2))


def _revolute_then_prismatic() -> armctl.RobotModel:
    from armctl.model.dh import DHLink

    links = [DHLink(a=0.3, alpha=np.pi / 2, mass=1.0, com=(-0.15, 0, 0)), DHLink(kind="prismatic", mass=1.0)]
    return armctl.RobotModel.from_dh(links)


def test_a_prismatic_position_too_large_for_floats_is_named() -> None:
    """A prismatic joint 1e200 m out made M and U overflow; the mass matrix came back with inf in it."""
    model = _revolute_then_prismatic()
    dyn = armctl.Dynamics(model)
    q = np.array([0.3, 1e200])
    with np.errstate(over="ignore", invalid="ignore"):
        assert not np.isfinite(dyn.kernel.mass(q)).all()  # the premise
    for method in ("mass_matrix", "check_mass_matrix"):
        with pytest.raises(NonFiniteError, match=r"overflowed .*q\[1\] = 1e\+200 is too large"):
            getattr(dyn, method)(q)


def test_the_compiled_regressors_name_an_overflow_anywhere_in_y() -> None:
    """The generated code folds constant zeros out of the first joint's row, so an overflow in a later row did
    not show there: Y came back with inf in it."""
    from armctl.model.dh import DHLink

    model = armctl.RobotModel.from_dh(
        [DHLink(alpha=np.pi / 2, mass=1.0, com=(0, 0.1, 0)), DHLink(a=0.3, mass=1.0, com=(-0.15, 0, 0))]
    )
    z = np.zeros(2)
    for options in ({}, {"compile": True}):
        dyn = armctl.Dynamics(model, **options)
        with np.errstate(over="ignore", invalid="ignore"), pytest.raises(NonFiniteError, match=r"overflowed"):
            dyn.regressor(z, np.array([1e160, 0.0]), z)
        with np.errstate(over="ignore", invalid="ignore"), pytest.raises(NonFiniteError, match=r"overflowed"):
            dyn.passivity_regressor(z, np.array([1e160, 0.0]), z, z)


def test_dynamics_of_something_else_than_a_model_is_named() -> None:
    for backend in ("pinocchio", "lagrange"):
        with pytest.raises(InvalidParameterError, match=r"Dynamics needs a RobotModel, got str"):
            armctl.Dynamics("panda", backend=backend)  # type: ignore[arg-type]
    assert armctl.Dynamics(armctl.models.pendulum(), compile=np.True_).options["compile"] is True


def test_a_dynamics_no_one_refers_to_is_freed_without_the_cycle_collector() -> None:
    import gc
    import weakref

    gc.disable()
    try:
        for options in ({}, {"compile": True}):
            ref = weakref.ref(armctl.Dynamics(armctl.models.planar_2r(), **options))
            assert ref() is None
    finally:
        gc.enable()


THREE_BACKENDS = [("pinocchio", {}), ("pinocchio", {"compile": True}), ("lagrange", {})]


@pytest.mark.parametrize(("backend", "options"), THREE_BACKENDS)
def test_a_wrench_whose_joint_torque_is_finite_but_whose_acceleration_overflows_is_named(
    backend: str, options: dict
) -> None:
    """Jᵀh is finite (one entry of ~1e308 against Jacobian entries below 1), but M⁻¹(τ − Jᵀh) is not: the
    wrench is the input at fault, not the τ it was folded into."""
    dyn = armctl.Dynamics(armctl.models.panda(), backend=backend, **options)
    q, z = np.array([0.0, -0.5, 0.0, -2.0, 0.0, 1.6, 0.8]), np.zeros(7)
    wrench = np.array([1e308, 0.0, 0.0, 0.0, 0.0, 0.0])
    assert np.isfinite(dyn.jacobian(q).T @ wrench).all()  # the premise: the joint torque itself is finite
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        with pytest.raises(NonFiniteError, match=r"overflowed .*wrench\[0\] = 1e\+308 is too large"):
            dyn.forward_dynamics(q, z, z, wrench=wrench)


@pytest.mark.parametrize(("backend", "options"), THREE_BACKENDS)
@pytest.mark.parametrize("method", ["passivity_regressor", "passivity_torque"])
def test_a_missing_reference_acceleration_is_named(backend: str, options: dict, method: str) -> None:
    """``qdd_r=None`` (left out by mistake) is refused by name on every backend, not passed to Pinocchio or to
    the generated code, which would refuse it in their own terms."""
    dyn = armctl.Dynamics(armctl.models.planar_2r(), backend=backend, **options)
    z = np.zeros(2)
    with pytest.raises(InvalidParameterError, match=r"^qdd_r must hold real numbers, got None"):
        getattr(dyn, method)(z, z, z, None)
