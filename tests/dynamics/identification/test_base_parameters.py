"""Base parameters: their number against hand-derived counts, and the identities that define them."""

from __future__ import annotations

import numpy as np
import pytest

import armctl
from armctl.dynamics.identification import find_base_parameters
from armctl.errors import InvalidParameterError
from tests.helpers.arms import MODEL_NAMES, dynamics


@pytest.mark.parametrize(("name", "count"), [("pendulum", 5), ("planar_2r", 11), ("planar_3r", 17)])
def test_number_of_base_parameters_matches_hand_derivation(name: str, count: int) -> None:
    """Planar arms in a vertical plane (axis y, gravity in the plane), by hand:

    pendulum: m·c_x, m·c_z (gravity), I_yy + k_r²I_m (lumped: both multiply q̈ only), F_v, F_c → 5.
    planar 2R: link 2 gives m c_x, m c_z, I_yy; rotor 2 (only q̈₂ in row 2, while I_yy2 also enters row 1)
    stays separate; link 1 gives I_yy1 + I_m1 + a² m₂ and m c_x1 + a m₂, m c_z1; plus 2 × 2 friction → 11.
    planar 3R: 3 × 3 link parameters, rotors 2 and 3 (rotor 1 lumps with I_yy1), 3 × 2 friction → 17.
    """
    assert find_base_parameters(dynamics(name)).n_base == count


@pytest.mark.parametrize("name", MODEL_NAMES)
def test_base_regressor_reproduces_the_full_one(name: str) -> None:
    dyn = dynamics(name)
    base = find_base_parameters(dyn)
    rng = np.random.default_rng(11)
    for _ in range(5):
        pi = rng.standard_normal(13 * dyn.n)
        q, qd, qdd = rng.standard_normal((3, dyn.n))
        y = dyn.regressor(q, qd, qdd)
        np.testing.assert_allclose(base.columns(y) @ base.project(pi), y @ pi, atol=1e-9 * max(1, np.abs(y).max()))
        # the null space is invisible to every torque, at states the QR never saw
        assert np.abs(y @ base.null_space).max() <= 1e-9 * max(1.0, np.abs(y).max())


@pytest.mark.parametrize("name", ["planar_2r", "puma560", "panda"])
def test_rank_agrees_with_an_svd_and_ignores_inertial_values(name: str) -> None:
    dyn = dynamics(name)
    base = find_base_parameters(dyn)
    rng = np.random.default_rng(3)
    w = np.vstack([dyn.regressor(*rng.uniform(-2, 2, (3, dyn.n))) for _ in range(60)])
    s = np.linalg.svd(w, compute_uv=False)
    assert base.n_base == int(np.sum(s > 1e-9 * s[0]))
    other = find_base_parameters(
        armctl.Dynamics(dyn.model.perturbed(mass=1.7, inertia=0.6, com_offset=0.03, seed=2)), seed=5
    )
    assert other.independent == base.independent
    np.testing.assert_allclose(other.beta, base.beta, atol=1e-8)


def test_names_show_the_lumping() -> None:
    names = find_base_parameters(dynamics("planar_2r")).base_names()
    assert "Iyy[0] + Im_reflected[0] + m[1]" in names and "Im_reflected[1]" in names


def test_too_few_samples_is_refused() -> None:
    with pytest.raises(InvalidParameterError):
        find_base_parameters(dynamics("puma560"), samples=3)
