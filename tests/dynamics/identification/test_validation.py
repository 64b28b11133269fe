"""Bad input to the identification API raises a named ArmctlError that says what is wrong, and noise-free
data give meaningful diagnostics (a cost ratio of ~1, not one of round-off over round-off)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import armctl
import armctl.dynamics.identification as ident
from armctl.errors import (
    IdentifiabilityError,
    IdentificationWarning,
    InvalidParameterError,
    NonFiniteError,
    ShapeError,
)

CHEAP = {"samples": 20, "grid": 40, "starts": 1, "maxiter": 0}


@pytest.fixture(scope="module")
def dyn() -> armctl.Dynamics:
    return armctl.Dynamics(armctl.models.planar_2r())


@pytest.fixture(scope="module")
def traj() -> ident.FourierExcitation:
    rng = np.random.default_rng(0)
    return ident.FourierExcitation(
        [0.1, -0.2], 0.5 * rng.standard_normal((2, 4)), 0.5 * rng.standard_normal((2, 4)), 5.0
    )


@pytest.fixture(scope="module")
def data(dyn: armctl.Dynamics, traj: ident.FourierExcitation) -> ident.IdentificationData:
    """One period of the excitation with exact inverse-dynamics torques (no noise)."""
    t = np.arange(0.0, traj.period, 0.01)
    q, qd, qdd = traj.evaluate(t)
    tau = np.array([dyn.inverse_dynamics(*x) for x in zip(q, qd, qdd, strict=True)])
    return ident.IdentificationData(t, q, qd, qdd, tau)


@pytest.fixture(scope="module")
def problem(dyn: armctl.Dynamics, data: ident.IdentificationData) -> ident.IdentificationProblem:
    return ident.build_problem(dyn, data)


@pytest.fixture(scope="module")
def result(dyn: armctl.Dynamics, data: ident.IdentificationData) -> ident.IdentificationResult:
    return ident.identify(dyn, data)


# 1. the cost ratio on noise-free data


@pytest.mark.parametrize("weighted", [True, False])
def test_cost_ratio_is_about_one_on_noise_free_data(
    dyn: armctl.Dynamics, data: ident.IdentificationData, weighted: bool
) -> None:
    cons = ident.identify(dyn, data, weighted=weighted).consistent
    assert cons is not None and cons.converged, cons
    assert 0.999 <= cons.cost_ratio <= 1.01, cons.cost_ratio  # was 2.4e302 (round-off over a 1e-300 floor)


# 2. the rank tolerance of the base parameters


@pytest.mark.parametrize("tol", [1.0, 0.1, 1e-2, 0.0, -1e-8, 1e-20])
def test_base_parameter_tolerance_out_of_range(dyn: armctl.Dynamics, tol: float) -> None:
    with pytest.raises(InvalidParameterError, match=r"tol must be (in \[1e-14, 0\.001\]|> 0)"):
        ident.find_base_parameters(dyn, tol=tol)


def test_base_parameter_tolerance_at_its_bounds_keeps_every_base_parameter(dyn: armctl.Dynamics) -> None:
    assert {ident.find_base_parameters(dyn, tol=t).n_base for t in (1e-14, 1e-8, 1e-3)} == {11}


# 3. an excitation design without a finite condition number


@pytest.mark.parametrize("kwargs", [{"acceleration_limit": 1e-300}, {"acceleration_limit": 5.0, "period": 1e-9}])
def test_excitation_design_with_infinite_condition_number(dyn: armctl.Dynamics, kwargs: dict) -> None:
    with pytest.raises(IdentifiabilityError, match="no excitation with a finite condition number"):
        ident.optimize_excitation(dyn, **kwargs, **dict(CHEAP, maxiter=2))


# 4. zero torques


def test_zero_torques_carry_no_information(dyn: armctl.Dynamics, data: ident.IdentificationData) -> None:
    zero = replace(data, tau=0.0 * data.tau)
    with pytest.raises(IdentifiabilityError, match=r"torques .* are all zero"):
        ident.solve_least_squares(ident.build_problem(dyn, zero))
    with pytest.raises(IdentifiabilityError, match=r"torques .* are all zero"):
        ident.identify(dyn, zero)


def test_tiny_torques_give_finite_standard_deviations(problem: ident.IdentificationProblem) -> None:
    tiny = replace(problem, torque=1e-200 * problem.torque)
    est = ident.solve_least_squares(tiny)
    assert np.isfinite(est.std).all() and np.isfinite(est.theta).all()


# 5. strings are not booleans


def test_strings_are_not_booleans(
    dyn: armctl.Dynamics,
    data: ident.IdentificationData,
    problem: ident.IdentificationProblem,
    result: ident.IdentificationResult,
) -> None:
    with pytest.raises(InvalidParameterError, match="weighted must be True or False, got 'False'"):
        ident.solve_least_squares(problem, weighted="False")  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="offsets must be True or False, got 'no'"):
        ident.build_problem(dyn, data, offsets="no")  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="consistent must be True or False, got 'no'"):
        ident.identify(dyn, data, consistent="no")  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="consistent must be True or False, got 'no'"):
        result.predict(data.q[:3], data.qd[:3], data.qdd[:3], consistent="no")  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="consistent must be True or False"):
        result.validate(data, consistent="yes")  # type: ignore[arg-type]


# 6. raw exceptions replaced by named ones


@pytest.mark.parametrize("seed", ["a", -1, 1.5, None])
def test_bad_seed(dyn: armctl.Dynamics, seed: object) -> None:
    with pytest.raises(InvalidParameterError, match="seed must be a whole number >= 0"):
        ident.find_base_parameters(dyn, seed=seed)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="seed must be a whole number >= 0"):
        ident.optimize_excitation(dyn, acceleration_limit=5.0, seed=seed, **CHEAP)  # type: ignore[arg-type]


@pytest.mark.parametrize(("name", "value"), [("harmonics", 1.5), ("samples", "20"), ("starts", 0), ("maxiter", -1)])
def test_bad_design_counts(dyn: armctl.Dynamics, name: str, value: object) -> None:
    with pytest.raises(InvalidParameterError, match=f"{name} must be a whole number"):
        ident.optimize_excitation(dyn, acceleration_limit=5.0, **dict(CHEAP, **{name: value}))


@pytest.mark.parametrize(
    ("rtol", "match"),
    [
        ("x", "rtol must be a real number"),
        (None, "rtol must be a real number"),
        (0.0, "rtol must be > 0"),
        (1.0, "rtol must be < 1"),
    ],
)
def test_bad_rtol(problem: ident.IdentificationProblem, rtol: object, match: str) -> None:
    with pytest.raises(InvalidParameterError, match=match):
        ident.solve_least_squares(problem, rtol=rtol)  # type: ignore[arg-type]


@pytest.mark.parametrize("budget", [0, 2.5, "10"])
def test_bad_max_evaluations(dyn: armctl.Dynamics, problem: ident.IdentificationProblem, budget: object) -> None:
    with pytest.raises(InvalidParameterError, match="max_evaluations must be a whole number >= 1"):
        ident.consistent_estimate(problem, dyn.model, max_evaluations=budget)  # type: ignore[arg-type]


def test_data_that_are_not_identification_data(dyn: armctl.Dynamics, result: ident.IdentificationResult) -> None:
    for bad in ([], "x", [1, 2]):
        with pytest.raises(InvalidParameterError, match="data must be an IdentificationData"):
            ident.build_problem(dyn, bad)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match=r"data must be an IdentificationData .* got str"):
        result.validate("x")  # type: ignore[arg-type]


def test_bad_problem(problem: ident.IdentificationProblem) -> None:
    torque = problem.torque.copy()
    torque[3] = np.nan
    with pytest.raises(NonFiniteError, match=r"torque holds NaN or inf \(first at index \[3\]\)"):
        replace(problem, torque=torque)
    with pytest.raises(InvalidParameterError, match="n must be a whole number >= 1, got 0"):
        replace(problem, n=0)
    with pytest.raises(InvalidParameterError, match="offsets must be True or False"):
        replace(problem, offsets="yes")
    with pytest.raises(InvalidParameterError, match="problem must be an IdentificationProblem"):
        ident.solve_least_squares("problem")  # type: ignore[arg-type]


def test_bad_identification_data(data: ident.IdentificationData) -> None:
    with pytest.raises(ShapeError, match=r"sos must be second-order sections of shape \(sections, 6\)"):
        replace(data, sos=[1, 2, 3])
    for value in (None, 1.5, "3", 0):
        with pytest.raises(InvalidParameterError, match="decimate must be a whole number >= 1"):
            replace(data, decimate=value)
    with pytest.raises(InvalidParameterError, match="trim must be a whole number >= 0"):
        replace(data, trim=-1)
    with pytest.raises(InvalidParameterError, match="q must hold real numbers"):
        replace(data, q=data.q + 0j)
    with pytest.warns(IdentificationWarning, match="trim=0 leaves the filter's start-up transient"):
        short = ident.IdentificationData(
            data.t[:10],
            data.q[:10],
            data.qd[:10],
            data.qdd[:10],
            data.tau[:10],
            sos=np.array([[1.0, 0.0, 0.0, 1.0, 0.5, 0.1]] * 4),
        )
    with pytest.raises(InvalidParameterError, match="10 samples are too few for the filter sos"):
        short.reduce(short.tau)


def test_bad_log(data: ident.IdentificationData) -> None:
    t, q, tau = data.t, data.q, data.tau
    for bad in ([["a", "b"]] * len(t), q.astype(str), q + 1j):
        with pytest.raises(InvalidParameterError, match="q must hold real numbers"):
            ident.prepare_data(t, bad, tau, cutoff=5.0)
    with pytest.raises(InvalidParameterError, match="decimate must be a whole number >= 1"):
        ident.prepare_data(t, q, tau, cutoff=5.0, decimate=1.5)


def test_bad_fourier_excitation(traj: ident.FourierExcitation) -> None:
    for period in ("5", None):
        with pytest.raises(InvalidParameterError, match="period must be a real number"):
            ident.FourierExcitation(traj.q0, traj.a, traj.b, period)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="period=1e-310 s is too small"):
        ident.FourierExcitation(traj.q0, traj.a, traj.b, 1e-310)
    with pytest.raises(NonFiniteError, match="t holds NaN or inf"):
        traj.evaluate(np.nan)
    with pytest.raises(ShapeError, match=r"factor must be a scalar or an \(2,\) vector, got shape \(3,\)"):
        traj.scaled([1, 2, 3])
    with pytest.raises(ShapeError, match=r"velocity must be a scalar or an \(2,\) vector"):
        traj.within(-3.0, 3.0, [1.0, 1.0, 1.0], 10.0)
    with pytest.raises(InvalidParameterError, match="samples_per_period must be a whole number >= 1, got 0"):
        traj.extremes(0)
    assert traj.within(-np.inf, np.inf, np.inf, np.inf)  # infinite limits stay allowed


def test_bad_validation_result_and_plot(result: ident.IdentificationResult, data: ident.IdentificationData) -> None:
    with pytest.raises(ShapeError, match="S >= 1 samples"):
        ident.ValidationResult([], np.zeros((0, 2)), np.zeros((0, 2)))
    with pytest.raises(ShapeError, match=r"predicted \(S, n\) and measured \(S, n\)"):
        ident.ValidationResult([0.0, 1.0], [1.0, 2.0], [1.0, 2.0])
    validation = result.validate(data)
    with pytest.raises(ShapeError, match="joint_names has 1 names for 2 joints"):
        ident.validation_plot(validation, joint_names=["a"])
    with pytest.raises(InvalidParameterError, match="joint_names must be a sequence of 2 strings"):
        ident.validation_plot(validation, joint_names="ab")


# 7. the prior's weight


@pytest.mark.parametrize("weight", [1e300, 10.0, 1e-20])
def test_prior_weight_out_of_range(dyn: armctl.Dynamics, data: ident.IdentificationData, weight: float) -> None:
    with pytest.raises(InvalidParameterError, match=r"prior_weight must be in \[1e-12, 1\]"):
        ident.identify(dyn, data, prior_weight=weight)


def test_an_offset_no_motion_can_excite_is_named_with_its_cause() -> None:
    # an RRPR SCARA: the vertical prismatic joint 2 carries the constant gravity load (m₂ + m₃) g, and its
    # Coulomb offset column |sgn q̇₂| is 1 whenever it moves: the two are the same column for every motion. The
    # error used to ask for a better excitation, which cannot help
    import math

    import armctl
    from armctl.dynamics.identification import IdentificationData, identify
    from armctl.errors import IdentifiabilityError
    from armctl.model.dh import DHLink
    from armctl.model.parts import JointFriction, Motor

    fr = JointFriction(0.1, 0.5)
    rows = [
        DHLink(d=0.4, a=0.4, mass=5, com=(-0.2, 0, 0), inertia=(0.02, 0.1, 0.1), motor=Motor(1e-4, 80), friction=fr),
        DHLink(
            a=0.3,
            alpha=math.pi,
            mass=3,
            com=(-0.15, 0, 0),
            inertia=(0.01, 0.05, 0.05),
            motor=Motor(1e-4, 60),
            friction=fr,
        ),
        DHLink(
            kind="prismatic",
            mass=1,
            com=(0, 0, -0.1),
            inertia=(0.01, 0.01, 0.001),
            motor=Motor(1e-5, 1000),
            friction=fr,
        ),
        DHLink(d=0.05, mass=0.5, com=(0, 0, 0.02), inertia=(0.001, 0.001, 0.0005), motor=Motor(1e-5, 50), friction=fr),
    ]
    model = armctl.RobotModel.from_dh(rows, name="scara")
    dyn = armctl.Dynamics(model)
    t = np.linspace(0.0, 10.0, 2000)
    w = np.array([0.6, 1.3, 2.1])
    ph = np.random.default_rng(0).uniform(0, 6, (4, 3))
    arg = w[None, None, :] * (np.arange(4)[None, :, None] + 1) * t[:, None, None] + ph[None]
    amp = 0.3 * np.ones(3)
    freq = w[None, None, :] * (np.arange(4)[None, :, None] + 1)
    q = (amp * np.sin(arg)).sum(axis=2)
    qd = (amp * freq * np.cos(arg)).sum(axis=2)
    qdd = (-amp * freq**2 * np.sin(arg)).sum(axis=2)
    tau = np.array([dyn.inverse_dynamics(a, b, c) for a, b, c in zip(q, qd, qdd, strict=True)])
    data = IdentificationData(t, q, qd, qdd, tau)
    with pytest.raises(IdentifiabilityError, match=r"offset of joint\(s\) \[2\] .* for any motion: .* offsets=False"):
        identify(model, data, consistent=False)
    est = identify(model, data, consistent=False, offsets=False).estimate
    base = dyn.base_parameters()
    np.testing.assert_allclose(est.theta, base.project(model.parameters()), rtol=1e-8, atol=1e-10)
