"""
Tuning the controllers and writing the presets
==============================================

Tune every joint-space controller of every scene and write the presets to controllers/.

How: one closed-loop bandwidth ω_n per scene, chosen well inside the sampled-data stability limit that
python-control computes for a 1 kHz loop with one period of measurement delay; then

* computed torque: K_p = ω_n², K_d = 2ω_n (critically damped error dynamics), checked by the gain margin;
  on planar_2r the LQR gains of the double-integrator error dynamics instead (weights recorded);
* PD + gravity: K_p = ω_n² M̄, K_d = 2ω_n M̄ (M̄ = diag M at the start of the reference), the same double
  pole for a single joint; on a coupled arm the off-diagonal inertia moves the poles (measured:
  6.3–23.7 rad/s on planar_2r against ω_n = 10, 10.4–232 on the Panda against 20, both at q_ref(0); all
  stable when sampled);
* passivity-based and adaptive: Λ = ω_n, K_D = ω_n M̄ (ṡ = −(K_D/M) s has its pole at ω_n for a single
  joint, spread by the coupling likewise); Γ for the adaptive law in proportion to abs(π_i) + 0.01, so that
  parameters move in proportion to their size, scaled by 0.1/(0.01 max M̄) — a scale, not a rate: how fast a
  parameter moves at a given error depends on the regressor (measured at 0.01 rad/s: a median 56 %/s on the
  pendulum, 0.14 %/s on planar_2r);
* panda_contact (operational-space QP and Khatib's closed form): the pose task's error dynamics, which the
  operational-space law decouples to ë = u per task coordinate, get the double pole at ω_n, checked the same way.

Run: ``python examples/tune_gains.py [--out DIR] [--scenes NAME ...]`` (default DIR: the presets folder armctl
reads, $ARMCTL_PRESETS or the checkout's controllers/, wherever the script is run from: it rewrites the
shipped presets)
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from armctl.scenes import scene
from armctl.tuning import SampledDataAnalysis, lqr_gains, pd_from_bandwidth
from armctl.tuning.presets import presets_dir, write_preset

BANDWIDTH = {"pendulum": 15.0, "planar_2r": 10.0, "panda_topp": 20.0, "panda_contact": 20.0}  # ω_n [rad/s]


def margins(kp: float, kd: float, control_dt: float, name: str) -> tuple[str, dict[str, float]]:
    """The sampled-data margins of ë = −k_p e − k_d ė at the scene's rate with one period of delay: the
    text for ``how`` and the record; exits if the loop is unstable."""
    margin = SampledDataAnalysis.of(kp, kd, control_dt, delay=1)
    if not margin.stable:
        raise SystemExit(f"{name}: {margin.summary()}")
    text = (
        f"; sampled-data gain margin {margin.critical_multiplier:.1f} and phase margin "
        f"{margin.phase_margin_deg:.0f}° at {1 / control_dt:g} Hz with one period of delay"
    )
    return text, {"gain_margin": margin.critical_multiplier, "phase_margin_deg": margin.phase_margin_deg}


def tune_contact(name: str, out: Path) -> list[Path]:
    """The pose task's gains of both operational-space methods (the force is regulated by the QP's contact,
    or, in the closed form, by the pose stiffness alone)."""
    sc = scene(name)
    wn = BANDWIDTH[name]
    kp, kd = pd_from_bandwidth(wn, 1.0)
    text, record = margins(kp, kd, sc.control_dt, name)
    how = f"pose task: double pole of the decoupled ë = u at ω_n = {wn:g} rad/s{text}"
    return [
        write_preset(name, method, {"kp": kp, "kd": kd}, how, "examples/tune_gains.py", out, omega_n=wn, **record)
        for method in sc.methods
    ]


def tune(name: str, out: Path) -> list[Path]:
    if name == "panda_contact":
        return tune_contact(name, out)
    sc = scene(name)
    wn = BANDWIDTH[name]
    if name == "planar_2r":
        kp, kd = lqr_gains(position_weight=wn**4, velocity_weight=0.0, effort_weight=1.0)
        how_ct = f"LQR on ë = v, weights q_p = ω_n⁴, q_v = 0, r = 1 (ω_n = {wn:g} rad/s: ζ = {kd / (2 * wn):.2f})"
    else:
        kp, kd = pd_from_bandwidth(wn, 1.0)
        how_ct = f"double pole at ω_n = {wn:g} rad/s"
    text, record = margins(kp, kd, sc.control_dt, name)
    how_ct += text
    paths = []
    for method in ("computed_torque", "computed_torque_reduced"):
        paths.append(
            write_preset(
                name, method, {"kp": kp, "kd": kd}, how_ct, "examples/tune_gains.py", out, omega_n=wn, **record
            )
        )
    record = {"omega_n": wn}  # the margins above are the computed-torque loop's, not the others'

    dyn = sc.dynamics("exact")
    q_start = sc.reference(0.0).q
    m_bar = np.diag(dyn.mass_matrix(q_start))
    paths.append(
        write_preset(
            name,
            "pd_gravity",
            {"kp": (wn**2 * m_bar).tolist(), "kd": (2 * wn * m_bar).tolist()},
            "K_p = ω_n² M̄, K_d = 2 ω_n M̄ with M̄ = diag M(q_ref(0))",
            "examples/tune_gains.py",
            out,
            **record,
        )
    )
    paths.append(
        write_preset(
            name,
            "passivity",
            {"lam": wn, "kd": (wn * m_bar).tolist()},
            "Λ = ω_n, K_D = ω_n M̄",
            "examples/tune_gains.py",
            out,
            **record,
        )
    )
    pi = np.abs(sc.dynamics("reduced").parameters())
    gamma = 0.1 * (pi + 1e-2) / (0.01 * max(float(m_bar.max()), 1e-3))
    paths.append(
        write_preset(
            name,
            "adaptive",
            # no projection: the textbook law, whose V = ½ sᵀMs + ½ θ̃ᵀΓ⁻¹θ̃ does not increase (the projection
            # onto the physical set is nearest in the pseudo-inertia's norm, not Γ⁻¹'s, and can raise V)
            {"lam": wn, "kd": (wn * m_bar).tolist(), "gamma": gamma.tolist(), "projection": False},
            "Λ = ω_n, K_D = ω_n M̄; Γ_i = 0.1 (|π_i| + 0.01)/(0.01 max M̄); projection off (the textbook law: V "
            "non-increasing)",
            "examples/tune_gains.py",
            out,
            **record,
        )
    )
    return paths


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument(
        "--out",
        type=Path,
        default=presets_dir(),
        help="folder to write the presets to (default: %(default)s, the one armctl reads)",
    )
    parser.add_argument("--scenes", nargs="*", default=list(BANDWIDTH), help="scenes to tune (default: all)")
    args = parser.parse_args()
    for name in args.scenes:
        for p in tune(name, args.out):
            print("wrote", p)


if __name__ == "__main__":
    main()
