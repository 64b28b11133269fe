"""
Identifying an arm's dynamic parameters
=======================================

The whole offline pipeline on the Puma 560, starting from a deliberately wrong model (masses ×1.3, inertias ×1.5,
centres of mass moved 2 cm, friction halved, rotors ×1.5, 10 % random per link) whose kinematics are right:

1. the base parameters, the combinations of π the joint torques can see (``find_base_parameters``);
2. an excitation trajectory, a Fourier series within the joint limits with a small condition number of the
   stacked base regressor (``optimize_excitation``);
3. the measurement: here the true arm's inverse dynamics along it, sampled at 500 Hz with encoder noise on q
   (10⁻⁴ rad) and 2 % noise on τ — what a robot's log holds;
4. the data made ready: q filtered without phase lag and differentiated, τ and the regressor filtered alike
   and decimated (``prepare_data``);
5. weighted least squares with standard deviations, then a physically consistent full π and model
   (``identify``);
6. validation on a fresh trajectory: the torques each model predicts against the measured ones.

Run: ``python examples/identification.py [--out DIR] [--show]`` (writes its figures under DIR, default example-out/)
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import armctl
import armctl.dynamics.identification as ident

RATE = 500.0  # Hz
LIMITS = {"velocity_limit": 1.5, "acceleration_limit": 4.0}  # rad/s, rad/s²


def measure(
    truth: armctl.Dynamics, trajectory: ident.FourierExcitation, periods: float, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t, q, τ) as a robot would log them along ``trajectory``: noisy encoders and torques."""
    t = np.arange(0.0, periods * trajectory.period, 1.0 / RATE)
    q, qd, qdd = trajectory.evaluate(t)
    tau = np.array([truth.inverse_dynamics(*x) for x in zip(q, qd, qdd, strict=True)])
    rms = np.sqrt((tau**2).mean(axis=0))
    return t, q + 1e-4 * rng.standard_normal(q.shape), tau + 0.02 * rms * rng.standard_normal(tau.shape)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        "--out", type=Path, default=Path("example-out"), help="folder for the figures (default: example-out)"
    )
    parser.add_argument("--show", action="store_true", help="also show the figures in windows")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(0)
    truth = armctl.models.puma560()
    nominal = truth.perturbed(mass=1.3, inertia=1.5, com_offset=0.02, friction=0.5, rotor=1.5, noise=0.1, seed=1)
    dyn = armctl.Dynamics(nominal)

    base = ident.find_base_parameters(dyn)
    print(f"{base.n_full} parameters, {base.n_base} base parameters, e.g. {base.base_names()[0]}")

    design = ident.optimize_excitation(dyn, base, period=10.0, harmonics=5, maxiter=10, **LIMITS)
    print(
        f"excitation: cond(W_b) {design.initial_condition_number:.0f} (best random start) → "
        f"{design.condition_number:.0f}, bandwidth {design.trajectory.bandwidth:.2f} Hz"
    )

    t, q, tau = measure(armctl.Dynamics(truth), design.trajectory, periods=2, rng=rng)
    data = ident.prepare_data(t, q, tau, cutoff=5.0)
    result = ident.identify(dyn, data, base=base)
    consistent = result.consistent
    print(
        f"weighted least squares on {data.samples} samples: residual RMS per joint "
        f"{np.round(result.estimate.residual_rms, 3)} N·m; consistent estimate: cost ratio "
        f"{consistent.cost_ratio:.4f}, converged {consistent.converged}"
    )

    fresh = ident.optimize_excitation(dyn, base, maxiter=0, seed=7, **LIMITS).trajectory
    t2, q2, tau2 = measure(armctl.Dynamics(truth), fresh, periods=1, rng=rng)
    check = ident.prepare_data(t2, q2, tau2, cutoff=5.0)
    validation = result.validate(check, consistent=True)
    # what the nominal model predicts on the same samples, filtered and decimated as the measured torque is
    nominal_tau = check.reduce([dyn.inverse_dynamics(*x) for x in zip(check.q, check.qd, check.qdd, strict=True)])
    nominal_err = np.sqrt(((nominal_tau - validation.measured) ** 2).mean(axis=0)) / validation.rms_torque
    print("validation on a fresh trajectory, RMS torque error / RMS torque per joint:")
    print(f"  nominal model     {np.round(100 * nominal_err, 1)} %")
    print(f"  identified model  {np.round(100 * validation.relative_error, 2)} %")
    print(result.report(validation).splitlines()[0])
    fig = result.plot(validation)  # measured and predicted torques on the fresh trajectory, per joint
    path = args.out / "identification.png"
    fig.savefig(path, dpi=100)
    print("wrote", path)
    if args.show:
        plt.figure(fig)  # a Figure of the library's, handed to pyplot to show
        plt.show()


if __name__ == "__main__":
    main()
