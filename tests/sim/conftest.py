"""Every simulator test runs twice: on the generated step (``simulate``'s default, ``compile="auto"``) and on the
Python step (``compile="auto"`` read as False). A run that a test makes under both is compared: the joint
positions of the two must agree within :data:`AGREEMENT` rad at every sample.

Markers: ``one_step`` — the test does not depend on which step runs (it runs once, on the default);
``steps_may_differ(reason)`` — the test's runs are ones whose rounding grows (an unstable contact or friction,
which the simulator itself reports): both steps still run it, their runs are not compared.
"""

from __future__ import annotations

import importlib
from typing import Any

import numpy as np
import pytest

simulate_module = importlib.import_module("armctl.sim.simulate")  # (armctl.sim.simulate is also the function)
#: the largest difference between the two steps' joint positions in a test's run [rad]
AGREEMENT = 1e-9
#: the runs of the variant that ran first, by test (without the variant) and call
_first: dict[str, tuple[str, list[tuple[Any, np.ndarray, bool]]]] = {}


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "one_step: a simulator test that runs on the default step only")
    config.addinivalue_line(
        "markers", "steps_may_differ(reason): the generated and the Python step's runs of this test are not compared"
    )


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    if "sim_step" in metafunc.fixturenames:
        one = metafunc.definition.get_closest_marker("one_step") is not None
        metafunc.parametrize("sim_step", ["generated"] if one else ["generated", "python"], indirect=True)


def _key(request: pytest.FixtureRequest) -> str:
    params = dict(getattr(request.node, "callspec", None).params) if hasattr(request.node, "callspec") else {}
    params.pop("sim_step", None)
    return f"{request.node.module.__name__}::{request.node.originalname}{sorted(params.items(), key=str)!r}"


@pytest.fixture(autouse=True)
def sim_step(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> str:
    """The step this test's native runs use; records their results for the comparison of the two steps."""
    variant = getattr(request, "param", "generated")
    if variant == "python":
        choose = simulate_module.choose_step

        def python_by_default(dyn: Any, scheme: str, plant: Any, compile: Any = "auto", cache_dir: Any = None) -> Any:
            return choose(dyn, scheme, plant, False if isinstance(compile, str) and compile == "auto" else compile)

        monkeypatch.setattr(simulate_module, "choose_step", python_by_default)
    runs: list[tuple[Any, np.ndarray, bool]] = []
    after_run = simulate_module.after_run

    def recording(res: Any, *args: Any, **kwargs: Any) -> Any:
        noisy = not np.array_equal(res.q, res.q_measured)  # measurement noise (drawn from the run's seed)
        runs.append((res.info.get("seed"), np.array(res.q), noisy))
        return after_run(res, *args, **kwargs)

    monkeypatch.setattr(simulate_module, "after_run", recording)
    yield variant
    compare = request.node.get_closest_marker("steps_may_differ") is None and not getattr(
        request.function, "is_hypothesis_test", False
    )
    key = _key(request)
    if not compare:
        return
    if key not in _first:
        _first[key] = (variant, runs)
        return
    other, before = _first.pop(key)
    if other == variant or len(before) != len(runs):
        return
    for k, ((seed0, q0, noisy0), (seed1, q1, noisy1)) in enumerate(zip(before, runs, strict=True)):
        if (noisy0 or noisy1) and seed0 != seed1:
            continue  # noise of fresh seeds: not the same run
        assert q0.shape == q1.shape, f"run {k}: the steps ran {len(q0)} and {len(q1)} samples"
        gap = float(np.abs(q0 - q1).max()) if q0.size else 0.0
        assert gap <= AGREEMENT, f"run {k}: the generated and the Python step differ by {gap:.3g} rad"
