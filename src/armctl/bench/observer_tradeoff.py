"""The momentum observer's gain trades detection delay against noise: one run of the Panda held by PD + gravity
with noisy velocity measurements, pushed at the tool by a step of 20 N at t = 0.5 s; the observer (on the measured
q, q̇ and the applied torques, as a controller would see them) replays it for each gain K_O.

Per gain: the residual's noise before the push (RMS over joints and samples [N·m]); the estimation error against
the simulator's true external joint torques after the push has settled (RMS from 5/K_O on [N·m]); the detection
delay with a threshold of 3 N·m (from the push to the first residual above it [s]), and false alarms (a detection
before the push). The closed forms beside them: a first-order lag crosses a threshold θ on a step of height A after
−ln(1 − θ/A)/K_O; and since r = K_O (p − ∫ … dt), white velocity noise of deviation σ reaches joint j's residual
with the deviation (1 − γ)/T · σ ‖M_j‖ (2/(1 + γ))^½, γ = exp(−K_O T) (the lag's response to the differenced
momentum noise; ≈ K_O σ ‖M_j‖ for K_O T ≪ 1: in proportion to the gain; M_j: row j of M(q)).
Numbers that do not exist (no settled samples in the run, no detection) are None.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

import armctl

Q_READY = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
STEP_AT, PUSH, THRESHOLD, NOISE_QD = 0.5, 20.0, 3.0, 2e-3


def push_run(duration: float = 1.2, seed: int = 0) -> Any:
    """The recorded run (see the module)."""
    from armctl.controllers import PDGravity
    from armctl.sim import Sensing, simulate

    model = armctl.models.panda()
    dyn = armctl.Dynamics(model)
    kp = np.array([400.0, 400.0, 400.0, 400.0, 50.0, 50.0, 20.0])
    kd = np.array([40.0, 40.0, 40.0, 40.0, 4.0, 4.0, 1.0])
    h = np.array([0.0, PUSH, 0.0, 0.0, 0.0, 0.0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return simulate(model, PDGravity(dyn, kp, kd), armctl.Reference(Q_READY), duration, q0=Q_READY,
                        disturbance=lambda t: h if t >= STEP_AT else np.zeros(6),
                        sensing=Sensing(noise_qd=NOISE_QD, seed=seed))  # fmt: skip


def replay(gain: float, res: Any) -> np.ndarray:
    """The residual of an observer of gain ``gain`` over the run's measurements."""
    from armctl.controllers import MomentumObserver

    obs = MomentumObserver(armctl.Dynamics(armctl.models.panda()), gain)
    n = res.q.shape[1]
    out = np.empty_like(res.q)
    for k in range(len(res.t)):
        tau = res.tau_applied[k - 1] if k else np.zeros(n)
        out[k] = obs.update(res.t[k], res.q_measured[k], res.qd_measured[k], tau)
    return out


def run(quick: bool = False) -> dict[str, Any]:
    """The figures of every gain (see the module)."""
    gains = [10.0, 30.0, 100.0, 300.0] if quick else [5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0]
    res = push_run(1.0 if quick else 1.2)
    before, true = res.t < STEP_AT, res.tau_ext
    height = float(np.abs(true[-1]).max())
    rows_m = np.linalg.norm(armctl.Dynamics(armctl.models.panda()).mass_matrix(Q_READY), axis=1)
    period = float(res.t[1] - res.t[0])
    rows = []
    for k_o in gains:
        r = replay(k_o, res)
        settled = res.t >= STEP_AT + 5.0 / k_o
        above = np.flatnonzero((np.abs(r) > THRESHOLD).any(axis=1) & (res.t > 0.05))  # past the start-up
        first = float(res.t[above[0]]) if above.size else float("nan")
        gamma = np.exp(-k_o * period)
        rows.append(
            {
                "gain": k_o,
                "noise": float(np.sqrt((r[before & (res.t > 0.05)] ** 2).mean())),
                "noise_predicted": float(
                    (1.0 - gamma) / period * NOISE_QD * np.sqrt(2.0 / (1.0 + gamma) * (rows_m**2).mean())
                ),
                "error": float(np.sqrt(((r - true)[settled] ** 2).mean())) if settled.any() else None,
                "delay": first - STEP_AT if above.size and first >= STEP_AT else None,
                "false_alarm": bool(above.size and first < STEP_AT),
                "lag_delay": float(-np.log(1.0 - THRESHOLD / height) / k_o),
            }
        )
    return {"rows": rows, "threshold": THRESHOLD, "noise_qd": NOISE_QD, "push": PUSH, "step_height": height}


def plot_axes(data: dict[str, Any], ax_delay: Any, ax_noise: Any) -> None:
    """Detection delay (with the first-order lag's closed form) and noise / error against K_O on two axes."""
    rows = data["rows"]
    k = [r["gain"] for r in rows]
    nan = float("nan")
    ax_delay.loglog(k, [nan if r["delay"] is None else 1e3 * r["delay"] for r in rows], "o-", label="simulated")
    ax_delay.loglog(k, [1e3 * r["lag_delay"] for r in rows], "k--", label="−ln(1 − θ/A)/K_O")
    for r in rows:
        if r["false_alarm"]:
            ax_delay.axvline(r["gain"], color="tab:red", alpha=0.3)
    ax_delay.set_xlabel("observer gain K_O [1/s]")
    ax_delay.set_ylabel(f"detection delay at θ = {data['threshold']:g} N·m [ms]")
    ax_delay.set_title("detection delay (red: false alarms before the push)", fontsize=10)
    ax_delay.legend(fontsize=8)
    ax_noise.loglog(k, [r["noise"] for r in rows], "o-", label="noise before the push (RMS)")
    ax_noise.loglog(k, [r["noise_predicted"] for r in rows], "k--", label="(1 − γ)/T σ ‖M_j‖ (2/(1 + γ))^½")
    ax_noise.loglog(k, [nan if r["error"] is None else r["error"] for r in rows], "s-",
                    label="error against the true τ_ext after 5/K_O (RMS)")  # fmt: skip
    ax_noise.axhline(data["threshold"], color="tab:red", ls=":", label="threshold")
    ax_noise.set_xlabel("observer gain K_O [1/s]")
    ax_noise.set_ylabel("[N·m]")
    ax_noise.set_title(f"residual noise (σ_q̇ = {data['noise_qd']:g} rad/s) and estimation error", fontsize=10)
    ax_noise.legend(fontsize=8)


def summary_lines(data: dict[str, Any]) -> list[str]:
    """One line per gain."""
    out = [f"observer gain against detection (threshold {data['threshold']:g} N·m, σ_q̇ = {data['noise_qd']:g})"]
    for r in data["rows"]:
        if r["false_alarm"] or r["delay"] is None:
            delay = "false alarm" if r["false_alarm"] else "none"
        else:
            delay = f"{1e3 * r['delay']:6.1f} ms (lag {1e3 * r['lag_delay']:.1f})"
        err = "  —  " if r["error"] is None else f"{r['error']:.3f}"
        out.append(
            f"  K_O = {r['gain']:6.0f}/s  noise {r['noise']:.3f} (closed form {r['noise_predicted']:.3f})  "
            f"error {err} N·m  delay {delay}"
        )
    return out
