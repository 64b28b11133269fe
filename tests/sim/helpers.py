"""Helpers of the simulator's tests: tiny controllers and models, and a job that fails on demand for the sweeps
(module level, so that they pickle for sweeps).

They are written here from the textbook laws, on purpose independent of ``armctl.controllers``.
"""

from __future__ import annotations

import os
import signal
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

import armctl
from armctl.controllers import Controller
from armctl.model.parts import Frame, Joint, JointLimits, Link
from armctl.references import Reference
from armctl.sim import SimResult, simulate
from armctl.sim.result import _ARRAYS


class PDGravity(Controller):
    """τ = g(q) + K_p (q_r − q) + K_d (q̇_r − q̇)."""

    def __init__(self, dyn: armctl.Dynamics, kp: float, kd: float) -> None:
        super().__init__(dyn)
        self.kp, self.kd = kp, kd

    def compute(self, t: float, q: np.ndarray, qd: np.ndarray, ref: Reference) -> np.ndarray:
        return self.dynamics.gravity_torque(q) + self.kp * (ref.q - q) + self.kd * (ref.qd - qd)


class ComputedTorque(Controller):
    """τ = M(q)(q̈_r + K_p e + K_d ė) + C q̇ + g, logging the tracking error."""

    def __init__(self, dyn: armctl.Dynamics, kp: float, kd: float) -> None:
        super().__init__(dyn)
        self.kp, self.kd = kp, kd

    def compute(self, t: float, q: np.ndarray, qd: np.ndarray, ref: Reference) -> np.ndarray:
        e = ref.q - q
        self.last_log = {"error_norm": float(np.linalg.norm(e))}
        return self.dynamics.inverse_dynamics(q, qd, ref.qdd + self.kp * e + self.kd * (ref.qd - qd))


class ForceControl(Controller):
    """Gravity compensation, a commanded contact force f at the tool (τ = g + J_linᵀ f) and joint damping;
    optionally a joint-space spring K_p (q_r − q) holding the posture."""

    def __init__(self, dyn: armctl.Dynamics, force: np.ndarray, kd: float, kp: float = 0.0) -> None:
        super().__init__(dyn)
        self.force, self.kd, self.kp = np.asarray(force, dtype=float), kd, kp

    def compute(self, t: float, q: np.ndarray, qd: np.ndarray, ref: Reference) -> np.ndarray:
        jac = self.dynamics.jacobian(q)[:3]
        return self.dynamics.gravity_torque(q) + jac.T @ self.force - self.kd * qd + self.kp * (ref.q - q)


class OpenLoop:
    """τ = profile(t), whatever the state."""

    def __init__(self, profile: Callable[[float], np.ndarray]) -> None:
        self.profile = profile

    def __call__(self, t: float, q: np.ndarray, qd: np.ndarray, ref: Reference) -> np.ndarray:
        return np.asarray(self.profile(t), dtype=float)


class Ramp:
    """τ = offset + rate · t (a picklable open-loop profile)."""

    def __init__(self, offset: np.ndarray, rate: np.ndarray) -> None:
        self.offset, self.rate = np.asarray(offset, dtype=float), np.asarray(rate, dtype=float)

    def __call__(self, t: float) -> np.ndarray:
        return self.offset + self.rate * t


def zero_torque(t: float, q: np.ndarray, qd: np.ndarray, ref: Reference) -> np.ndarray:
    return np.zeros(len(q))


def slider(mass: float = 2.0, effort: float = float("inf"), vertical: bool = False) -> armctl.RobotModel:
    """One prismatic joint moving a point-like body of ``mass`` [kg] along world x (horizontal: gravity does
    nothing) or z (``vertical``); tool frame at the body."""
    axis = (0.0, 0.0, 1.0) if vertical else (1.0, 0.0, 0.0)
    joint = Joint(
        "slide",
        "prismatic",
        axis,
        np.eye(4),
        Link(mass, (0, 0, 0), (1e-3, 1e-3, 1e-3)),
        limits=JointLimits(effort=effort),
    )
    return armctl.RobotModel((joint,), name="slider", frames=(Frame("tool", 1, np.eye(4)),), tool_frame="tool")


def failing_job(x: int, log: str, mode: str = "ok") -> int:
    """x², after noting the start in ``log``; or fail the way ``mode`` says."""
    with open(log, "a") as f:
        f.write(f"{x}\n")
    if mode == "raise":
        raise ValueError(f"x = {x} is not allowed")
    if mode == "exit":
        os._exit(7)
    if mode == "sigkill":
        os.kill(os.getpid(), signal.SIGKILL)
    if mode == "exit-once" and Path(log).read_text().split().count(str(x)) == 1:
        os._exit(7)  # dies on its first start only
    if mode == "hang":
        time.sleep(3600)
    if mode == "slow":
        time.sleep(0.5)
    return x * x


def failing_cases(log: Path, modes: dict[int, str], n: int = 6) -> list[dict[str, object]]:
    """n cases of :func:`failing_job`, all "ok" but those ``modes`` names, noting their starts in ``log``."""
    return [{"x": x, "log": str(log), "mode": modes.get(x, "ok")} for x in range(n)]


class LoggingController:
    """A controller holding zero torque whose log has numbers, None, dicts and ragged arrays."""

    def __init__(self) -> None:
        self.last_log: dict[str, Any] = {}

    def __call__(self, t: float, q: np.ndarray, qd: np.ndarray, ref: Any) -> np.ndarray:
        k = round(t / 1e-3)
        self.last_log = {"number": float(k), "none": None, "info": {"k": k}, "ragged": np.zeros(1 + k % 2)}
        return np.zeros(1)


def logging_run() -> SimResult:
    """10 ms of the pendulum held by :class:`LoggingController`."""
    return simulate(armctl.models.pendulum(), LoggingController(), armctl.Reference.hold([0.0]), 0.01)


def without_samples(res: SimResult) -> SimResult:
    """``res`` cut to no samples (a run stopped before its first one)."""
    return SimResult(**{name: getattr(res, name)[:0] for name in _ARRAYS})
