"""The one closed loop on every engine (:mod:`armctl.sim.engine`): what the loop does with the controller's torque —
its checks, the saturation, the stop rules, the measurement delay, a controller that fails — is the same whether
the Python step, the generated C period (both through the conftest's ``sim_step``) or MuJoCo advances the plant;
and the flat option keywords of ``simulate`` still work, with a DeprecationWarning that names the group.

References: the rules written out here (np.clip at the effort limits, the sample the run must stop at, the
measurement the controller must see), independent of the loop's code.
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np
import pytest

import armctl
from armctl.errors import InvalidParameterError, ShapeError, SimulationWarning
from armctl.sim import Forces, Sensing, StopRules, simulate
from tests.helpers.mjcf_arms import SPATIAL_ARM
from tests.sim.helpers import OpenLoop, PDGravity

REF = armctl.Reference.hold([0.2, 0.5, 0.3])
ENGINES = ("native", "mujoco")


@pytest.fixture(scope="module")
def arm() -> armctl.RobotModel:
    """The spatial arm without joint friction (one plant every engine takes)."""
    pytest.importorskip("mujoco")
    return armctl.RobotModel.from_mjcf(SPATIAL_ARM, tool_frame="tool").reduced(friction=False)


def _run(arm: armctl.RobotModel, engine: str, controller: Any, duration: float = 0.2, **options: Any) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SimulationWarning)  # (the limits' report)
        return simulate(arm, controller, REF, duration, engine=engine, **options)


@pytest.mark.parametrize("engine", ENGINES)
def test_saturation_clips_the_applied_torque_row_by_row(arm: armctl.RobotModel, engine: str) -> None:
    """An open-loop ramp through the effort limits: τ is the command, the applied torque its np.clip at the model's
    limits, on every row."""
    limit = arm.effort_limit
    assert np.isfinite(limit).all()
    ramp = OpenLoop(lambda t: (t / 0.2) * 2.0 * limit * np.array([1.0, -1.0, 1.0]))
    res = _run(arm, engine, ramp)
    np.testing.assert_array_equal(res.tau, np.array([ramp.profile(t) for t in res.t]))
    np.testing.assert_array_equal(res.tau_applied, np.clip(res.tau, -limit, limit))
    beyond = (np.abs(res.tau) > limit).any(axis=1)
    assert beyond.any() and not beyond.all()


@pytest.mark.parametrize("engine", ENGINES)
def test_a_torque_that_is_not_finite_stops_the_run_at_its_sample(arm: armctl.RobotModel, engine: str) -> None:
    """NaN from t = 0.05 s: the run stops as diverged at sample 50 and keeps the 50 before it."""

    def late_nan(t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        return np.full(3, math.nan) if t >= 0.05 - 1e-12 else np.zeros(3)

    res = _run(arm, engine, late_nan)
    assert res.diverged and res.diverged_at == pytest.approx(0.05) and "non-finite torque" in res.divergence
    assert len(res.t) == 50 and np.isfinite(res.tau).all()


@pytest.mark.parametrize("engine", ENGINES)
def test_the_stop_rules_end_the_run_at_the_first_sample_beyond(arm: armctl.RobotModel, engine: str) -> None:
    """Unsaturated 1e4 N·m: every recorded |q̇| is within max_velocity, the state the run stopped at beyond it."""
    push = OpenLoop(lambda t: np.full(3, 1e4))
    res = _run(arm, engine, push, saturate=False, stop=StopRules(max_velocity=50.0))
    assert res.diverged and res.divergence.endswith("beyond max_velocity = 50")
    assert np.abs(res.qd).max() <= 50.0 < np.abs(res.diverged_qd).max()
    assert res.diverged_at == pytest.approx(len(res.t) * 1e-3)


class _Seeing:
    """PD + gravity that keeps the q it is given."""

    def __init__(self, arm: armctl.RobotModel) -> None:
        self.law = PDGravity(armctl.Dynamics(arm), 40.0, 4.0)
        self.seen: list[np.ndarray] = []

    def __call__(self, t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        self.seen.append(q.copy())
        return self.law(t, q, qd, ref)


@pytest.mark.parametrize("engine", ENGINES)
def test_the_controller_sees_the_measurement_of_delay_periods_before(arm: armctl.RobotModel, engine: str) -> None:
    """delay = 3 and noise on q: at sample k the controller is given q_measured[k − 3] (the first one before)."""
    ctrl = _Seeing(arm)
    res = _run(arm, engine, ctrl, q0=[0.3, 0.4, 0.2], sensing=Sensing(noise_q=1e-3, seed=7, delay=3))
    seen = np.array(ctrl.seen)
    assert len(seen) == len(res.t)
    np.testing.assert_array_equal(seen[:3], np.broadcast_to(res.q_measured[0], (3, 3)))
    np.testing.assert_array_equal(seen[3:], res.q_measured[:-3])
    assert 0 < np.abs(res.q_measured - res.q).max() < 1e-2


@pytest.mark.parametrize("engine", ENGINES)
def test_what_the_controller_does_wrong_is_named(arm: armctl.RobotModel, engine: str) -> None:
    """Writing into the q it is given, a torque of the wrong shape, an exception: named, with the samples before."""

    def writes(t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        q += 1.0
        return np.zeros(3)

    with pytest.raises(InvalidParameterError, match="read-only"):
        _run(arm, engine, writes)
    with pytest.raises(ShapeError, match=r"torque of shape \(2,\)"):
        _run(arm, engine, OpenLoop(lambda t: np.zeros(2)))

    def breaks(t: float, q: np.ndarray, qd: np.ndarray, ref: armctl.Reference) -> np.ndarray:
        if t >= 0.03 - 1e-12:
            raise RuntimeError("sensor lost")
        return np.zeros(3)

    with pytest.raises(RuntimeError, match="sensor lost") as info:
        _run(arm, engine, breaks)
    part = info.value.result  # type: ignore[attr-defined]
    assert len(part.t) == 31 and np.isnan(part.tau[30]).all() and np.isnan(part.tau_applied[30]).all()
    assert np.isfinite(part.q).all()


#: each flat keyword of ``simulate`` (with the seed of a noisy run: the same noise both ways), a value, its group
FLAT = [
    ("noise_q", {"noise_q": 1e-3, "seed": 5}, "sensing", Sensing),
    ("noise_qd", {"noise_qd": 1e-2, "seed": 5}, "sensing", Sensing),
    ("seed", {"seed": 3}, "sensing", Sensing),
    ("delay", {"delay": 2}, "sensing", Sensing),
    ("sensors", {"sensors": armctl.sim.ForceSensor("tool")}, "sensing", Sensing),
    ("friction", {"friction": "smooth"}, "forces", Forces),
    (
        "environment",
        {"environment": armctl.sim.Plane(armctl.sim.KelvinVoigt(1e4), point=(0, 0, -5.0))},
        "forces",
        Forces,
    ),
    ("disturbance", {"disturbance": lambda t: np.zeros(6)}, "forces", Forces),
    ("max_velocity", {"max_velocity": 500.0}, "stop", StopRules),
    ("max_position", {"max_position": 100.0}, "stop", StopRules),
]


@pytest.mark.one_step
@pytest.mark.parametrize(("name", "values", "group", "cls"), FLAT, ids=[f[0] for f in FLAT])
def test_a_flat_keyword_is_deprecated_and_still_works(name: str, values: dict, group: str, cls: type) -> None:
    """``simulate(..., noise_q=...)``: a DeprecationWarning naming ``sensing=Sensing(noise_q=...)``, pointing at the
    caller; the run is the one of the group (the same samples bit for bit)."""
    model = armctl.models.planar_2r().with_friction(viscous=0.1, coulomb=0.2, static=0.3)
    ctrl = PDGravity(armctl.Dynamics(model.reduced(friction=False)), 40.0, 4.0)
    ref = armctl.Reference.hold([0.3, -0.2])
    with pytest.warns(DeprecationWarning, match=rf"{name}.*deprecated.*{group}={cls.__name__}\({name}=") as caught:
        flat = simulate(model, ctrl, ref, 0.05, **values)
    assert any(w.filename == __file__ for w in caught if issubclass(w.category, DeprecationWarning))
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        grouped = simulate(model, ctrl, ref, 0.05, **{group: cls(**values)})
    np.testing.assert_array_equal(flat.q, grouped.q)
    np.testing.assert_array_equal(flat.q_measured, grouped.q_measured)
