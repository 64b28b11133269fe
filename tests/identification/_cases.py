"""Shared cases for the identification tests, each built once per test run.

Simulated measurements: the *true* arm's inverse dynamics (Pinocchio RNEA plus the model's joint friction,
through ``Dynamics.inverse_dynamics``) along the excitation trajectory, sampled at 500 Hz, with Gaussian
noise on q (σ = 10⁻⁴ rad, an encoder's order) and on τ (σ = 2% of each joint's torque RMS). Inverse dynamics
rather than a closed-loop simulation: a logged (q, τ) pair is what identification sees, however the motion
was produced, and inverse dynamics gives that pair with no integration error, so what the tests measure is
the identification alone. Only the noisy q and τ reach the code under test (q̇, q̈ are reconstructed).

The identification starts from a deliberately wrong model (the truth perturbed: masses ×1.3, inertias
×1.5, centres of mass moved 2 cm, friction ×0.5, rotors ×1.5, 10% random per link); its kinematics are
exact.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

import armctl
import armctl.dynamics.identification as ident

FS = 500.0  # Hz
NOISE_Q = 1e-4  # rad
NOISE_TAU = 0.02  # of each joint's torque RMS


@dataclass(frozen=True)
class Case:
    truth: armctl.RobotModel
    nominal: armctl.RobotModel
    design: ident.ExcitationDesign
    data: ident.IdentificationData
    result: ident.IdentificationResult
    validation: ident.FourierExcitation  # a fresh trajectory
    wrist: tuple[int, ...]


def measure(
    truth: armctl.Dynamics, traj: ident.FourierExcitation, periods: float, seed: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t, q, τ) as a robot would log them: true inverse dynamics along the trajectory, noise added."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, periods * traj.period, 1.0 / FS)
    q, qd, qdd = traj.evaluate(t)
    tau = np.array([truth.inverse_dynamics(*x) for x in zip(q, qd, qdd, strict=True)])
    rms = np.sqrt((tau**2).mean(axis=0))
    return (t, q + NOISE_Q * rng.standard_normal(q.shape), tau + NOISE_TAU * rms * rng.standard_normal(tau.shape))


def true_torque(
    truth: armctl.Dynamics, traj: ident.FourierExcitation, step: float = 0.01
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Noise-free (q, q̇, q̈, τ) of the truth over one period of ``traj``."""
    t = np.arange(0.0, traj.period, step)
    q, qd, qdd = traj.evaluate(t)
    return q, qd, qdd, np.array([truth.inverse_dynamics(*x) for x in zip(q, qd, qdd, strict=True)])


def panda_truth() -> armctl.RobotModel:
    """The Panda with joint friction (the URDF has none): viscous 0.2–0.6 N·m·s/rad, Coulomb 0.3–1.0 N·m,
    asymmetric on some joints — magnitudes of the order published for the real arm."""
    return armctl.models.panda().with_friction(
        viscous=[0.6, 0.6, 0.5, 0.5, 0.3, 0.3, 0.2],
        coulomb=[0.8, 0.9, 0.7, 0.7, 0.4, 0.35, 0.3],
        coulomb_negative=[0.7, 1.0, 0.6, 0.75, 0.45, 0.3, 0.3],
    )


@cache
def case(name: str) -> Case:
    if name == "puma560":
        # the published Corke set, as the toolbox has it (links 1 and 3 not physical; see test_identify.py)
        truth = armctl.models.puma560()
        limits = {"velocity_limit": 1.5, "acceleration_limit": 4.0}
        wrist = (3, 4, 5)
    else:
        truth = panda_truth()
        limits = {"acceleration_limit": [5.0, 5.0, 5.0, 5.0, 8.0, 8.0, 8.0]}
        wrist = (4, 5, 6)
    nominal = truth.perturbed(mass=1.3, inertia=1.5, com_offset=0.02, friction=0.5, rotor=1.5, noise=0.1, seed=1)
    dyn = armctl.Dynamics(nominal)
    base = ident.find_base_parameters(dyn)
    design = ident.optimize_excitation(dyn, base, period=10.0, harmonics=5, maxiter=10, grid=100, **limits)
    t, q, tau = measure(armctl.Dynamics(truth), design.trajectory, periods=2, seed=0)
    data = ident.prepare_data(t, q, tau, cutoff=5.0)
    result = ident.identify(dyn, data, base=base)
    validation = ident.optimize_excitation(dyn, base, maxiter=0, seed=7, **limits).trajectory
    return Case(truth, nominal, design, data, result, validation, wrist)
