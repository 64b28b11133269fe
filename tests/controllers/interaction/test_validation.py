"""Bad input to the interaction controllers gets a named ArmctlError that says what is wrong."""

from __future__ import annotations

import re

import numpy as np
import pytest

import armctl
from armctl.controllers import (
    Admittance,
    CartesianImpedance,
    ForceControl,
    JointImpedance,
    Measurement,
    ParallelForcePosition,
)
from armctl.errors import InvalidParameterError, ShapeError, SingularConfigurationError, UnknownNameError

Q_READY = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])


@pytest.fixture(scope="module")
def panda() -> armctl.Dynamics:
    return armctl.Dynamics(armctl.models.panda())


def test_a_stiffness_that_is_not_symmetric_is_named(panda: armctl.Dynamics) -> None:
    k = np.diag([500.0] * 6)
    k[0, 1] = 50.0
    with pytest.raises(InvalidParameterError, match=r"stiffness .* symmetric"):
        CartesianImpedance(panda, k)


def test_a_stiffness_with_a_negative_eigenvalue_is_named(panda: armctl.Dynamics) -> None:
    with pytest.raises(InvalidParameterError, match=r"positive semi-definite.*-100"):
        CartesianImpedance(panda, [500.0, 500.0, -100.0])
    with pytest.raises(InvalidParameterError, match="stiffness"):
        JointImpedance(panda, -1.0)


def test_negative_damping_is_named(panda: armctl.Dynamics) -> None:
    with pytest.raises(InvalidParameterError, match=r"damping.*negative damping"):
        CartesianImpedance(panda, [500.0] * 6, damping=[10.0] * 5 + [-1.0])
    with pytest.raises(InvalidParameterError, match="damping"):
        JointImpedance(panda, 100.0, damping=-2.0)
    with pytest.raises(InvalidParameterError, match="zeta"):
        CartesianImpedance(panda, [500.0] * 6, zeta=-0.5)


def test_a_stiffness_of_the_wrong_size_is_named(panda: armctl.Dynamics) -> None:
    with pytest.raises(ShapeError, match=r"\(6,\) or \(6, 6\) or \(3,\) or \(3, 3\)"):
        CartesianImpedance(panda, [500.0] * 4)
    with pytest.raises(ShapeError, match="not a scalar"):
        CartesianImpedance(panda, 500.0)
    with pytest.raises(ShapeError, match="damping"):
        CartesianImpedance(panda, [500.0] * 6, damping=[10.0] * 3)


@pytest.mark.parametrize(
    ("law", "stiffness", "unit"),
    [
        (JointImpedance, [100.0] * 7, "N·m·s/rad"),
        (CartesianImpedance, [500.0] * 6, "N·s/m; N·m·s/rad"),
        (Admittance, [500.0] * 6, "N·s/m; N·m·s/rad"),
    ],
)
def test_the_spring_laws_name_a_bad_damping_alike(
    panda: armctl.Dynamics, law: type, stiffness: list[float], unit: str
) -> None:
    """The three spring laws check D the same way: a negative entry, and a size other than K's, named with D's
    unit."""
    bad = [10.0] * (len(stiffness) - 1) + [-1.0]
    with pytest.raises(InvalidParameterError, match=re.escape(f"damping [{unit}]") + ".*negative damping"):
        law(panda, stiffness, bad)
    with pytest.raises(ShapeError, match=re.escape(f"damping [{unit}]")):
        law(panda, stiffness, [10.0] * (len(stiffness) - 2))


def test_admittance_keeps_a_given_damping_and_derives_the_default(panda: armctl.Dynamics) -> None:
    """D_d given: that matrix; None: ζ-damped for M_d, which for diagonal M_d and K_d is 2 ζ (k m)^½ per axis."""
    given = Admittance(panda, [400.0] * 3, [30.0, 20.0, 10.0], inertia=[4.0] * 3, compile=False)
    np.testing.assert_array_equal(given.damping, np.diag([30.0, 20.0, 10.0]))
    derived = Admittance(panda, [400.0, 100.0, 400.0], inertia=[4.0, 1.0, 9.0], zeta=0.5, compile=False)
    np.testing.assert_allclose(derived.damping, np.diag([40.0, 10.0, 60.0]), rtol=1e-12, atol=1e-12)


def test_an_unknown_frame_is_named(panda: armctl.Dynamics) -> None:
    with pytest.raises(UnknownNameError, match="no_such_frame"):
        CartesianImpedance(panda, [500.0] * 6, frame="no_such_frame")
    with pytest.raises(UnknownNameError, match="no_such_frame"):
        ForceControl(panda, [0.0, 0.0, -5.0], 1e-4, frame="no_such_frame")
    with pytest.raises(UnknownNameError, match="no_such_frame"):
        Admittance(panda, [500.0] * 6, frame="no_such_frame")


def test_a_force_controller_without_a_force_source_is_named(panda: armctl.Dynamics) -> None:
    for make in (
        lambda src: ForceControl(panda, [0.0, 0.0, -5.0], 1e-4, force_source=src),
        lambda src: ParallelForcePosition(panda, [0.0, 0.0, -5.0], 1e-4, 1e-3, force_source=src),
        lambda src: Admittance(panda, [500.0] * 6, force_source=src),
        lambda src: CartesianImpedance(panda, [500.0] * 6, inertia=[2.0] * 6, force_source=src),
    ):
        with pytest.raises(InvalidParameterError, match="needs a force source"):
            make(None)
        with pytest.raises(InvalidParameterError, match="needs a force source"):
            make(object())  # no update/wrench


def test_a_call_without_the_wrench_says_how_to_give_it(panda: armctl.Dynamics) -> None:
    ctrl = ForceControl(panda, [0.0, 0.0, -5.0], 1e-4)
    assert ctrl.reads == {"wrench"}
    with pytest.raises(InvalidParameterError, match="Measurement"):
        ctrl(0.0, Q_READY, np.zeros(7), armctl.Reference(Q_READY))
    tau = ctrl(0.0, Q_READY, np.zeros(7), armctl.Reference(Q_READY), measurement=Measurement(wrench=np.zeros(6)))
    assert tau.shape == (7,)


def test_parallel_control_needs_integral_action(panda: armctl.Dynamics) -> None:
    with pytest.raises(InvalidParameterError, match=r"integral_gain.*positive definite"):
        ParallelForcePosition(panda, [0.0, 0.0, -5.0], 1e-4, 0.0)


def test_other_bad_input_is_named(panda: armctl.Dynamics) -> None:
    with pytest.raises(UnknownNameError, match="inner motion loop"):
        ForceControl(panda, [0.0, 0.0, -5.0], 1e-4, inner="pid")
    with pytest.raises(ShapeError, match="force"):
        ForceControl(panda, [0.0, -5.0], 1e-4)
    with pytest.raises(InvalidParameterError, match="linearly independent"):
        ForceControl(panda, [0.0, 0.0, -5.0], 1e-4, directions=[[0.0, 0.0, 1.0], [0.0, 0.0, 2.0]])
    with pytest.raises(InvalidParameterError, match=r"inertia .* positive definite"):
        CartesianImpedance(panda, [500.0] * 6, inertia=[1.0] * 5 + [0.0])
    with pytest.raises(InvalidParameterError, match="not a pose"):
        CartesianImpedance(panda, [500.0] * 6).set_target(2.0 * np.eye(4))


def test_a_singular_configuration_is_named() -> None:
    dyn = armctl.Dynamics(armctl.models.planar_2r())
    ctrl = CartesianImpedance(dyn, [100.0, 100.0, 100.0])  # three axes on a planar arm: J M⁻¹ Jᵀ is singular
    q = np.array([0.3, 0.5])
    with pytest.raises(SingularConfigurationError, match="singular"):
        ctrl(0.0, q, np.zeros(2), armctl.Reference(q))


def test_the_controllers_pickle_with_their_gains(panda: armctl.Dynamics) -> None:
    # a sweep hands controllers to worker processes: the copy computes what the original does
    import pickle

    q = Q_READY + 0.05
    m = Measurement(wrench=np.array([1.0, -2.0, 3.0, 0.1, 0.2, -0.1]), world_axes=True)
    for ctrl in (
        CartesianImpedance(panda, [800.0] * 3 + [40.0] * 3, [50.0] * 3 + [3.0] * 3, nullspace_stiffness=5.0),
        ForceControl(panda, [0.0, 0.0, -5.0], 1e-4, 1e-3, directions=[0.0, 0.0, 1.0]),
        ParallelForcePosition(panda, [0.0, 0.0, -5.0], 1e-4, 1e-3, inner="osc"),
        Admittance(panda, [500.0] * 3 + [20.0] * 3),
        JointImpedance(panda, 200.0),
    ):
        if hasattr(ctrl, "set_target"):
            ctrl.set_target(panda.frame_pose(Q_READY))
        copy = pickle.loads(pickle.dumps(ctrl))
        ref = armctl.Reference(Q_READY)
        expected = ctrl(0.0, q, np.full(7, 0.1), ref, measurement=m)
        np.testing.assert_allclose(copy(0.0, q, np.full(7, 0.1), ref, measurement=m), expected, rtol=1e-12)
